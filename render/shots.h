// Shots: rendered images of a scene at instrument pointings, written to a
// folder, and their detection into pixel observations.
//
// RenderShots writes into `out_dir`:
//   <shot id>.png   8-bit grey image of each shot
//   shots.csv       index, shot, face, zoom, phi, theta, image [, placement]
//                   [, focus_distance] (placement when the shots have
//                   placements, SPEC 7.1: each shot sees the scene of its
//                   placement; focus_distance when a shot has one, SPEC 4.1:
//                   the distance its camera was focused at)
//   exact.csv       pixels.csv columns (SPEC 3: face, zoom, phi, theta, shot,
//                   target, corner, X, Y, Z, u, v) plus `status`: the exact
//                   projection (ProjectToPixel) of every corner that
//                   lands in the image, of every tag (inner corner of a point
//                   board: corner 0 only) that faces the camera and
//                   is not occluded; `status` is the tag's TagStatus
//                   (visible / border / grazing / small), so exact.csv with
//                   status = visible lists what DetectShots should find.
// `index` is the shot's position in the full list, so shards can be merged.
//
// Parallelism: `jobs` worker processes (fork), each with its own
// HeadlessDisplay and SceneRenderer, worker k rendering the k-th, (k+jobs)-th,
// ... of this shard's shots; progress goes to stderr. Mesa's llvmpipe gets
// LP_NUM_THREADS = max(1, cores / jobs) per worker unless already set.
// Sharding: only shots with index % num_shards == shard are rendered; with
// num_shards > 1 the tables are named shots.shard-K-of-N.csv and
// exact.shard-K-of-N.csv, and MergeShards concatenates them.
#pragma once

#include <string>
#include <vector>

#include "detect/detector.h"
#include "libcalib/geometry/rotation.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"
#include "libcalib/model/targets.h"
#include "render/headless.h"
#include "render/scene_renderer.h"
#include "render/tag_matching.h"

namespace rtscalib::render {

struct Shot {
  int face = 1;
  int zoom = 0;
  double phi = 0, theta = 0;  // control angles [rad]
  std::string id;             // unique; the image is <id>.png ([A-Za-z0-9_.-], no leading '.')
  std::string placement;      // SPEC 7.1: which scene it sees ("" = the one placement)
  Rigid3 ref_from_cam;        // the camera's true pose for this shot
  CameraTool cam;             // intrinsics (as focused for this shot), distortion, size
  double focus_distance = 0;  // [m] SPEC 4.1: written to shots.csv when > 0
};

struct RenderShotsOptions {
  std::string out_dir;  // created if missing
  int jobs = 1;         // worker processes (1 = render in this process)
  int shard = 0;        // render shots with index % num_shards == shard
  int num_shards = 1;
  bool progress = true;     // progress lines on stderr
  // zlib level 0..9, or -1: OpenCV's speed setting (no level given to
  // cv::imencode: libpng's SUB filter alone at zlib level 1), faster to
  // write and to read back than level 1 with libpng's own filter choice
  // (docs/rendering.md, "Shots, workers and shards").
  int png_compression = -1;
  RenderOptions render;
  VisibilityOptions visibility;  // statuses in exact.csv
  HeadlessOptions headless;

  std::string Check() const;  // empty when valid
};

struct RenderShotsResult {
  int rendered = 0;       // images written by this call
  int exact_corners = 0;  // rows of exact.csv
  double seconds = 0;     // wall time of the rendering
};

// Empty when `shots` are valid (ids unique and usable as file names, sizes
// positive), else the first problem.
std::string CheckShots(const std::vector<Shot>& shots);

// Renders this shard of `shots`. Throws std::invalid_argument for invalid
// options or shots, std::runtime_error when a worker fails (its message
// included), DisplayError when no display can be had.
RenderShotsResult RenderShots(const TargetScene& scene, const std::vector<Shot>& shots,
                              const RenderShotsOptions& options);
// The same for shots of several placements (SPEC 7.1): each shot sees
// scenes.at(shot.placement); std::invalid_argument when a shot's placement
// has no scene.
RenderShotsResult RenderShots(const PlacedScenes& scenes, const std::vector<Shot>& shots,
                              const RenderShotsOptions& options);

// A rendered photo's PNG bytes at `png_compression` (RenderShotsOptions);
// false when OpenCV cannot encode it. photo_session_benchmark's
// BM_PhotoPng measures the settings on the demo's photos.
bool EncodePhotoPng(const cv::Mat& img, int png_compression, std::vector<unsigned char>* png);

// The tables' file names for a shard ("shots.csv" when num_shards == 1).
std::string ShotsTableName(int shard, int num_shards);
std::string ExactTableName(int shard, int num_shards);

// Concatenates the shard tables found in `shard_dirs` (all N shards of one
// N-way split, each exactly once, any folder order) into out_dir/shots.csv and
// out_dir/exact.csv, rows ordered by shot index, and copies images into
// out_dir when a shard folder is not out_dir. Throws std::runtime_error
// naming the missing or duplicated shard.
void MergeShards(const std::vector<std::string>& shard_dirs, const std::string& out_dir);

struct DetectShotsOptions {
  detect::DetectorOptions detector;  // families default to the scene's families
  MatchOptions match;
  VisibilityOptions visibility;
  int jobs = 1;  // detection threads (one detect::TagDetector each)
  bool progress = true;

  std::string Check() const;  // empty when valid
};

struct DetectShotsResult {
  std::vector<PixelObservation> pixels;  // shot order, then detection order, corners 0..3 (0)
  std::vector<ShotStats> stats;          // one per shot, in shot order
  ShotStats total;                       // sums over the shots
};

// Detects the tags in image_dir/<shot id>.png for every shot (AprilTags with
// detect::TagDetector, the inner corners of ChArUco and chessboards with
// detect::DetectPointBoard, chessboards oriented by the shot's face), keeps
// the detections of visible targets (tag_matching.h) and returns them as
// pixel observations of the scene's corners (one per inner corner). Throws
// std::runtime_error when an image is missing or unreadable (naming it).
DetectShotsResult DetectShots(const TargetScene& scene, const std::vector<Shot>& shots,
                              const std::string& image_dir, const DetectShotsOptions& options);

}  // namespace rtscalib::render

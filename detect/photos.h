// A real instrument's photos -> detected tag corners (SPEC 7, `rtscalib detect`).
//
// Every photo of shots.csv is read (photo_image.h: any of PNG/JPEG/TIFF, 8 or
// 16 bit, grey or colour, converted to 8-bit grey; a damaged or unreadable
// file is an InputError naming its shots.csv line), searched for tags of the
// families of targets.yaml (each with its boards' border_bits), and a
// detection is kept only when its family, border and id belong to one of the
// boards. Each AprilTag board then grows from the tags libapriltag found
// (board_growth.h): a missing tag next to found ones is looked for where the
// board's layout puts it and kept only when its own bits read as its code
// and its own edges or pattern fit its corners. What is kept never depends
// on a model, and never on where a tag "should" be alone, so partial boards,
// occlusions and any pose are fine. Per photo, also:
//   * a detection that neither of the detector's refinements could refine
//     (edges, or the whole-pattern fit of small tags; detector.h: bits under
//     1.5 px, heavy blur, a quad cut by the image edge) is dropped and
//     counted, unless keep_unrefined (libapriltag's own corners are ~0.1-0.2
//     px off);
//   * a tag detected twice in one photo (two printed copies) is dropped
//     entirely and counted: neither copy can be told from the other;
//   * the detector's own check: the shift between our refined corners and
//     libapriltag's (RMS and max) over the tags libapriltag found (not those
//     grown from their neighbours). Both estimate the same corner, so a large
//     shift means one of them went wrong (a smudge on an edge, heavy blur);
//     typically 0.1-0.3 px;
//   * a photo in which no target was found (no tag, no ChArUco corner, no
//     chessboard), and one in which a tag or a chessboard was found twice,
//     is a warning naming its line and file.
// Image sizes are read from the images (never guessed); a photo whose size
// differs from the first photo of the same zoom is an InputError naming both.
//
// Parallelism: `jobs` threads pull photos from one shared counter, each with
// its own TagDetector (libapriltag with `detector.threads` workers, 1 by
// default). OpenCV's own thread pool is limited to one thread while jobs > 1,
// so that the detection threads do not compete with it for the cores. Results
// do not depend on jobs (they are stored by photo and written in shots.csv
// order).
#pragma once

#include <Eigen/Core>
#include <array>
#include <map>
#include <string>
#include <vector>

#include "detect/board_growth.h"
#include "detect/detector.h"
#include "libcalib/io/shots.h"
#include "libcalib/model/observations.h"
#include "libcalib/model/targets.h"

namespace rtscalib::detect {

struct PhotoDetectionOptions {
  DetectorOptions detector;  // `families` is replaced by the boards' families
  bool grow_boards = true;   // AprilTag boards grown from their found tags (board_growth.h)
  GrowthOptions growth;
  int jobs = 1;              // detection threads
  bool keep_unrefined = false;
  bool progress = true;  // images/s lines on stderr during long runs

  std::string Check() const;  // empty when valid
};

struct DetectedTag {
  int board = 0;                      // index in TargetScene::boards
  int id = 0;                         // tag id = pixels.csv `target`
  // TargetCorner order, OpenCV pixels; a point board's inner corner
  // (ChArUco, chessboard: TagBoard::CornersPerTarget() == 1) is uv[0], the
  // others repeat it.
  std::array<Eigen::Vector2d, 4> uv;
  CornerRefinement refinement = CornerRefinement::kEdges;
};

struct PhotoDetection {
  int width = 0, height = 0;        // the image's size [px]
  int channels = 0, bit_depth = 0;  // of the file
  int tags_of_boards = 0;           // all tags of all boards
  std::vector<DetectedTag> tags;    // kept, by id
  int corners = 0;                  // of the kept targets: 4 per tag, 1 per inner corner
  int unrefined = 0;      // board tags whose refinement failed (dropped unless keep_unrefined)
  int pattern_refined = 0;  // kept tags whose corners come from the pattern fit (detector.h)
  int from_neighbours = 0;  // kept tags grown from their found neighbours (board_growth.h)
  int not_on_boards = 0;  // detections of families/ids of no board (dropped)
  int duplicates = 0;     // detections of a tag seen twice in this photo (dropped)
  std::vector<int> duplicate_ids;  // those tags' ids
  int duplicate_boards = 0;  // chessboards found twice in this photo (dropped, point_boards.h)
  int misoriented_boards = 0;  // chessboards found in no orientation a face allows (point_boards.h)
  // Refined vs libapriltag corners over the kept refined tags that
  // libapriltag found [px]; `refined_corners` counts those corners.
  double shift_rms_px = 0, shift_max_px = 0;
  int refined_corners = 0;
};

struct PhotoDetectionResult {
  std::vector<PhotoDetection> photos;  // one per shot, shots.csv order
  std::vector<std::string> warnings;   // "shots.csv:7: image a.png: no target of the boards found ..."
  double seconds = 0;                  // wall time
};

// What DetectPhotos can find, for ReadTargets's `family_codes`: the AprilTag
// families with their numbers of codes (tag_family.h) and OpenCV's ArUco
// dictionaries as "aruco:<name>" with their numbers of markers.
std::map<std::string, int> DetectableCodeCounts();

// What DetectPhotos looks for on `targets`' boards, in words for a log line:
// "AprilTags", "chessboard corners", "ChArUco corners", or two or three of
// them joined ("AprilTags and chessboard corners").
std::string TargetsInWords(const TargetScene& targets);

// Detects every photo of `shots`. Throws InputError (naming shots.csv's line
// and the image) for unreadable images and for image sizes that differ within
// a zoom level, std::invalid_argument for invalid options.
PhotoDetectionResult DetectPhotos(const ShotsFile& shots, const TargetScene& targets,
                                  const PhotoDetectionOptions& options);

// The one conversion of detected targets into pixel observations (for the
// calibration of a photo session, `rtscalib detect`'s pixels.csv and the
// renderer's checks): per target, one observation per corner (4 for a tag,
// 1 for a point board's inner corner, TagBoard::CornersPerTarget) with the
// photo's face, zoom, reading (has_reading), shot id, placement, focus
// distance and shots.csv line; X = the corner in the reference frame for a
// board with a pose (X_known), unknown for a board without one (SPEC 7).
// `tags` index into `targets.boards` (DetectedTag::board).
void AppendPixelObservations(const PhotoShot& shot, const TargetScene& targets,
                             const std::vector<DetectedTag>& tags,
                             std::vector<PixelObservation>* out);
// Every photo's kept targets (AppendPixelObservations), in shots.csv order,
// then by target id, corners 0..3.
std::vector<PixelObservation> PixelObservationsOf(const ShotsFile& shots,
                                                  const TargetScene& targets,
                                                  const PhotoDetectionResult& result);
// The image size of every zoom's photos (DetectPhotos checked that they agree).
std::map<int, ImageSize> ImageSizesOf(const ShotsFile& shots, const PhotoDetectionResult& result);

// One row per photo: line, shot, image, face, zoom, width, height, channels,
// bit_depth, tags_found, tags_of_boards, corners, refined_corners, unrefined,
// not_on_boards, duplicates, shift_rms_px, shift_max_px, pattern_refined,
// from_neighbours. `tags_found` and `tags_of_boards` count targets: tags, and
// the inner corners of ChArUco and chessboards.
void WriteDetectionSummary(const std::string& path, const ShotsFile& shots,
                           const PhotoDetectionResult& result);

}  // namespace rtscalib::detect

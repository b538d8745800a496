// Which targets of a scene a camera should see, and detections matched to them.
//
// A target is a tag of an AprilTag board (four corners) or an inner corner of
// a ChArUco or chessboard (one point; targets.h, CornersPerTarget). ExpectTags
// classifies every target of the scene for one camera pose, from the exact
// projection of its corners (ProjectToPixel). In order of precedence:
//   behind       a corner is not in front of the camera (z <= 0)
//   back_facing  the camera is on the unprinted (+z) side of the board
//   outside      no corner lands in the image, or a projection fails / folds
//                (a pixel that does not undistort back to its ray)
//   occluded     another board cuts a line of sight to a corner
//   border       some corner is outside the image or closer than
//                border_margin_px to its edge: partly cut tags are skipped;
//                for an inner corner, the corners of the four squares around
//                it are checked (the detector needs those squares, ChArUco
//                the markers in them)
//   grazing      the angle between a corner's line of sight and the board
//                normal exceeds max_view_angle_deg
//   small        a code bit (PrintedBitSize: a tag's, a ChArUco marker's,
//                1/8 of a chessboard square) is smaller than min_bit_px along
//                an edge (for an inner corner: along its squares' edges)
//   visible      everything else: these targets are expected to be found
// MatchDetections keeps the detections of `visible` targets only; detections
// of any other target are dropped and counted, never reported.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "detect/detector.h"
#include "libcalib/geometry/rotation.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/targets.h"

namespace rtscalib::render {

enum class TagStatus {
  kVisible,
  kBehind,
  kBackFacing,
  kOutside,
  kOccluded,
  kBorder,
  kGrazing,
  kSmall
};
const char* TagStatusName(TagStatus status);

struct VisibilityOptions {
  double border_margin_px = 8.0;     // corners nearer the image edge -> border
  double max_view_angle_deg = 70.0;  // line of sight vs board normal -> grazing
  double min_bit_px = 2.5;           // smallest code bit along an edge -> small

  std::string Check() const;  // empty when valid
};

struct ExpectedTag {
  int board = 0;  // index in TargetScene::boards
  int id = 0;     // tag id (TargetCorner::target)
  std::string family;
  TagStatus status = TagStatus::kOutside;
  // Corners of the target: 4 for a tag, 1 for a point board's inner corner,
  // whose arrays below repeat it (as TagBoard::CornersInBoard does).
  int corners = 4;
  std::array<Eigen::Vector3d, 4> X;   // corners, reference frame [m], TargetCorner order
  std::array<Eigen::Vector2d, 4> uv;  // exact projections [px] (where `projected`)
  std::array<bool, 4> projected{};    // in front of the camera, projection valid
  std::array<bool, 4> in_image{};     // projected and inside [-0.5, size - 0.5)
  double view_angle = 0;              // largest over the corners [rad]
  double bit_px = 0;                  // smallest code bit along an edge [px]
};

// Every tag of `scene` as seen by camera `cam` at `ref_from_cam`.
std::vector<ExpectedTag> ExpectTags(const TargetScene& scene, const Rigid3& ref_from_cam,
                                    const CameraTool& cam, const VisibilityOptions& options = {});

struct MatchOptions {
  // A detection of a visible tag with a corner further than this from the
  // exact projection is a mis-detection: dropped and counted [px].
  double max_corner_error_px = 3.0;
  // Drop detections whose sub-pixel refinement failed (libapriltag's corners
  // are ~0.1-0.2 px off).
  bool require_refined = true;

  std::string Check() const;  // empty when valid
};

// Per-shot bookkeeping: nothing is dropped silently.
struct ShotStats {
  std::string shot;
  int expected = 0;        // visible tags
  int found = 0;           // visible tags detected and kept
  int missed = 0;          // visible tags not detected (or dropped below)
  int unrefined = 0;       // visible tags detected, refinement failed, dropped
  int mismatched = 0;      // visible tags detected with corners off, dropped
  int skipped_border = 0;  // tags in view but skipped, by reason
  int skipped_grazing = 0;
  int skipped_small = 0;
  int skipped_occluded = 0;
  int dropped_skipped = 0;  // detections of skipped tags (dropped)
  int unknown = 0;          // detections of ids/families not in the scene
  int duplicate = 0;        // second detections of one tag (dropped)
  double rms_error_px = 0;  // kept corners vs exact projections
  double max_error_px = 0;

  void Add(const ShotStats& o);  // sums the counts (for totals), errors combined
  int corners_kept = 0;          // corners of the found targets (for combining RMS)
};

struct MatchedTag {
  int id = 0;
  int corners = 4;                    // ExpectedTag::corners
  std::array<Eigen::Vector3d, 4> X;   // reference frame
  std::array<Eigen::Vector2d, 4> uv;  // detected
};

// Matches one image's detections to its expected tags (a point board's inner
// corner as a TagDetection of its board's family whose corners all hold the
// point). `stats` is reset (keeping its `shot`) and filled.
std::vector<MatchedTag> MatchDetections(const std::vector<detect::TagDetection>& detections,
                                        const std::vector<ExpectedTag>& expected,
                                        const MatchOptions& options, ShotStats* stats);

}  // namespace rtscalib::render

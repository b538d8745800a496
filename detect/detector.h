// AprilTag detection with sub-pixel corner refinement.
//
// libapriltag (quad_decimate 1, refine_edges on) finds and decodes the tags;
// its corners then seed one of two refinements. Tags with code bits of at
// least `min_bit_pixels` (2.5 px) get our refinement of the four quad edges
// (below); tags too small for it, or whose edges fail, get the fit of their
// whole decoded pattern (tag_pattern_fit.h), down to bits of
// `min_pattern_bit_pixels`. The edge refinement:
//   * along each edge, away from the corners, the intensity profile across the
//     edge is sampled (bilinear) and the edge point is where it crosses the
//     mean of the two plateau levels on either side. For any blur that is
//     symmetric across the edge (the renderer's filtering, optics, defocus)
//     that crossing is the geometric edge;
//   * each edge's points are fitted with s(t) = a + b t (+ c t^2 on long edges,
//     which absorbs the curvature lens distortion gives a straight edge);
//   * a corner is the intersection of its two edges' curves;
//   * twice more, re-centred on the new curves.
// The profiles stay within one code bit of the edge, where the family
// guarantees clean plateaus (the black border ring and the white quiet zone,
// or the reversed families' black and white rings).
//
// Corner order is TargetCorner's (targets.h): 0 bottom-left, 1 bottom-right,
// 2 top-right, 3 top-left of the upright tag. This is libapriltag's order of
// apriltag_detection::p (tag coordinates (-1, 1), (1, 1), (1, -1), (-1, -1)
// with tag y pointing down the printed tag), checked on photos synthesized
// from the bit patterns alone (tests/detect/detector_test.cc) and on renders
// (tests/render/detector_test.cc). Pixel convention: OpenCV's, (0, 0) is the
// centre of the top-left pixel (libapriltag's own corners are shifted by half a
// pixel; only our refined corners are returned when refinement succeeds).
//
// Measured (tests/render/detector_test.cc, SmallTagsAtEveryZoom, and
// docs/rendering.md): edges 0.01-0.02 px RMS from 2.5 px per bit up;
// the pattern fit 0.02-0.03 px RMS at 1.5-2.5 px per bit on our renders, where
// libapriltag's own corners are 0.14-0.19 px off.
#pragma once

#include <Eigen/Core>
#include <array>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "detect/tag_family.h"
#include "detect/tag_pattern_fit.h"

namespace rtscalib::detect {

struct DetectorOptions {
  std::vector<PrintedFamily> families = {PrintedFamily{}};  // tag36h11, 1-bit border
  int threads = 1;          // libapriltag worker threads
  float quad_sigma = 0.0f;  // Gaussian blur before segmentation [px]
  double decode_sharpening = 0.25;
  int max_hamming = 1;         // detections with more corrected bits are dropped
  bool refine_corners = true;  // our refinements (else libapriltag's corners)
  // The edge refinement needs a code bit of at least this many pixels (the
  // profiles must fit inside one bit on either side of the edge).
  double min_bit_pixels = 2.5;
  // Tags the edge refinement cannot refine get the pattern fit down to code
  // bits of this many pixels; below, libapriltag's corners stay (unrefined).
  double min_pattern_bit_pixels = 1.5;
  PatternFitOptions pattern;
  // A refined corner further than this from libapriltag's is a failure [px].
  double max_refine_shift = 2.0;
  // libapriltag's segmentation ignores every region whose local contrast
  // (max - min over its 12 x 12 px neighbourhood) is below a threshold; at its
  // default of 5 grey levels, sensor noise alone passes it in flat areas (144
  // samples of Gaussian noise span more than 5 sigma 2 times in 3) and fills
  // the image with noise blobs that cost far more time than the tags
  // themselves. The
  // threshold is this multiple of the image's own noise sigma
  // (EstimateNoiseSigma), at least 5 (libapriltag's default) and at most
  // `max_segmentation_contrast`. Ten sigma: the span of 144 Gaussian samples
  // exceeds 9 sigma with probability < 1e-5, and a tag whose ink and paper
  // differ by less than 10 sigma has no sub-pixel corners to give.
  double segmentation_noise_multiple = 10.0;
  // Texture inflates the noise estimate (EstimateNoiseSigma); any tag with
  // more contrast than this [grey levels] stays detectable however textured
  // the scene.
  double max_segmentation_contrast = 40.0;
  // Families of a wider black border (Kalibr's AprilGrid, SPEC 7.2) get a
  // libapriltag pass of their own, on the photo's levels v seen as
  // 255 (v / 255)^wide_border_gamma. libapriltag calls a pixel black when it
  // is darker than the middle of its neighbourhood's range; where an
  // AprilGrid's square touches a tag's corner, a blurred photo is exactly at
  // that middle level (a saddle point), and on some prints the squares even
  // overlap the corners, so squares and tags merge into one black region
  // without a quad of the tag's own. Seen through the gamma, the middle
  // level falls to a tenth of the range (0.5^(1 / 0.3), ink near black):
  // the black regions come apart at the saddles, and a 2-bit border is wide
  // enough to stay whole (libapriltag alone, hamming <= 1: on
  // yac_d435i_aprilgrid 906 tags on the photos, 1,019 through the gamma; on
  // the six TUM VI fisheye photos of aprilgrid_rs_kalibr_grids none at
  // all, 196; 0.5 gave 1,013 and 104). The tags still merged are grown from
  // their neighbours (board_growth.h). libapriltag segments and decodes the
  // remapped levels; every corner is refined on the photo itself.
  double wide_border_gamma = 0.3;

  std::string Check() const;  // empty when valid
};

// Where a detection's corners come from.
enum class CornerRefinement {
  kNone,     // libapriltag's corners (refinement off, too small, or failed)
  kEdges,    // the refinement of the quad edges (RefineTagCorners)
  kPattern,  // the fit of the whole decoded pattern (FitTagPattern)
  kSaddle,   // a ChArUco or chessboard inner corner (OpenCV's cornerSubPix, point_boards.h)
};
const char* CornerRefinementName(CornerRefinement refinement);

struct TagDetection {
  std::string family;
  int border_bits = 1;  // of the printed family it was decoded as (tag_family.h)
  int id = -1;
  int hamming = 0;
  double decision_margin = 0;
  std::array<Eigen::Vector2d, 4> corners;           // TargetCorner order, OpenCV pixels
  std::array<Eigen::Vector2d, 4> apriltag_corners;  // libapriltag's, same order, +0.5 shift undone
  CornerRefinement refinement = CornerRefinement::kNone;
  // Found from the board's layout and verified by its own bits
  // (board_growth.h), not by libapriltag: `apriltag_corners` are then the
  // prediction the refinement started from.
  bool from_neighbours = false;

  bool refined() const { return refinement != CornerRefinement::kNone; }
};

class TagDetector {
 public:
  // Throws std::invalid_argument for invalid options or unknown families.
  explicit TagDetector(const DetectorOptions& options = {});
  ~TagDetector();
  TagDetector(const TagDetector&) = delete;
  TagDetector& operator=(const TagDetector&) = delete;

  // Detects tags in an 8-bit grayscale image (CV_8UC1). Not thread-safe: use
  // one detector per thread.
  std::vector<TagDetection> Detect(const cv::Mat& gray);

  // The refinement Detect applies, on its own: refines d->corners from
  // d->apriltag_corners (libapriltag's, or any start roughly right to ~1 px)
  // by the edges or the whole pattern and sets d->refinement (kNone, corners
  // unchanged, when neither holds). d's family and border_bits must be one of
  // the detector's families.
  void Refine(const cv::Mat& gray, TagDetection* d);

  const DetectorOptions& options() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The sigma of the image's noise [grey levels], robust to edges: the median
// of |L| over the image, with L the 3 x 3 kernel [1 -2 1; -2 4 -2; 1 -2 1]
// (zero on any plane of intensity, 6 sigma on white noise: the square root of
// the sum of its squared weights), sampled on every second row and column.
// For Gaussian noise the median of |L| is 0.6745 of its sigma. The few pixels
// on edges do not move a median; a textured scene does (it counts as noise).
double EstimateNoiseSigma(const cv::Mat& gray);

// The refinement on its own: refines `corners` (TargetCorner order, OpenCV
// pixels, roughly right to ~1 px) of a tag whose quad is `width_at_border`
// bits wide. Returns false (corners unchanged) when the tag is too small or an
// edge has too few clean profiles.
bool RefineTagCorners(const cv::Mat& gray, int width_at_border, const DetectorOptions& options,
                      std::array<Eigen::Vector2d, 4>* corners);

}  // namespace rtscalib::detect

// AprilTag detection with sub-pixel corner refinement.
//
// libapriltag (quad_decimate 1, refine_edges on) finds and decodes the tags;
// its corners then seed our own refinement of the four quad edges:
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
#pragma once

#include <Eigen/Core>
#include <array>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace rtscalib::detect {

struct DetectorOptions {
  std::vector<std::string> families = {"tag36h11"};
  int threads = 1;          // libapriltag worker threads
  float quad_sigma = 0.0f;  // Gaussian blur before segmentation [px]
  double decode_sharpening = 0.25;
  int max_hamming = 1;         // detections with more corrected bits are dropped
  bool refine_corners = true;  // our edge refinement (else libapriltag's corners)
  // Refinement needs a code bit of at least this many pixels (the profiles
  // must fit inside one bit on either side of the edge).
  double min_bit_pixels = 2.5;
  // A refined corner further than this from libapriltag's is a failure [px].
  double max_refine_shift = 2.0;

  std::string Check() const;  // empty when valid
};

struct TagDetection {
  std::string family;
  int id = -1;
  int hamming = 0;
  double decision_margin = 0;
  std::array<Eigen::Vector2d, 4> corners;           // TargetCorner order, OpenCV pixels
  std::array<Eigen::Vector2d, 4> apriltag_corners;  // libapriltag's, same order, +0.5 shift undone
  bool refined = false;                             // corners are the sub-pixel refined ones
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

  const DetectorOptions& options() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The refinement on its own: refines `corners` (TargetCorner order, OpenCV
// pixels, roughly right to ~1 px) of a tag whose quad is `width_at_border`
// bits wide. Returns false (corners unchanged) when the tag is too small or an
// edge has too few clean profiles.
bool RefineTagCorners(const cv::Mat& gray, int width_at_border, const DetectorOptions& options,
                      std::array<Eigen::Vector2d, 4>* corners);

}  // namespace rtscalib::detect

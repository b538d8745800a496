// Sub-pixel corners of a decoded tag from its whole printed pattern.
//
// The edge refinement of detector.h measures each quad edge between two
// plateaus one code bit wide; at 2-4 px per bit there is no plateau left once
// the pixel's own area and the optics have blurred the edge. But a decoded tag
// is known in full: every bit of its code image (tag_family.h) is ink or
// paper. The fit adjusts an image of that pattern to the photo, over every
// pixel of the tag, by Levenberg-Marquardt:
//
//   I(p) = ink + (paper - ink) W(q(p)),   q(p) = H^-1(p),
//
// with H the homography from code-image coordinates q (bits; bit (x, y)
// covers [x, x+1) x [y, y+1), y down the upright tag) to SPEC 2 pixels p, and
// W the pattern's paper fraction at q blurred by one Gaussian of `blur` px in
// the image. That Gaussian stands for the optics and the pixel's own area (a
// 1 px box, variance 1/12 px^2) together: a box and a Gaussian of the same
// variance are both symmetric, so they put an edge at the same place.
// Mapped into code-image coordinates, an image Gaussian of s px blurs the
// x-edges with s_x = s |grad_p q_x| and the y-edges with s_y = s |grad_p q_y|
// (the distance from a straight edge in px, per bit); the pattern, a union of
// axis-aligned squares, blurred by a Gaussian separable along the tag axes
// is the sum over ink bits of products of normal-CDF differences:
//
//   W = 1 - sum_{ink bits (i, j)} [Phi((q_x - i)/s_x) - Phi((q_x - i - 1)/s_x)]
//                                 [Phi((q_y - j)/s_y) - Phi((q_y - j - 1)/s_y)].
//
// This is exact along every straight bit edge whatever the tag's tilt; only
// near the corners of bits does the neglected shear of a tilted view change
// the blur's shape. Outside the code image the print is taken as paper (the
// quiet zone and the board's spacing); the fitted pixels are those whose
// centres lie at least half a bit inside the code image, so a neighbouring
// tag one bit of paper further away does not reach them.
//
// Parameters (11): the 8 entries of H (normalised, H(2,2) = 1), ink, paper
// and the blur s. Lens distortion is not modelled: over a tag of a few tens
// of pixels it bends an edge by hundredths of a pixel at most, which is why
// this fit is meant for small tags and long edges keep the edge refinement.
// The corners are H's images of the quad corners (TargetCorner order).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

namespace rtscalib::detect {

// A bit of a code image that the print does not fix: the corner bits of the
// quiet zone of a Kalibr AprilGrid's tag, which the grid's black squares
// cover, are white on other prints. No pixel whose centre lies within half a
// bit of such a bit is fitted, and the model takes it as paper.
constexpr uint8_t kUnknownCodeBit = 128;

struct PatternFitOptions {
  int max_iterations = 20;
  // Converged when no corner moves by more than this in an iteration [px].
  double tolerance_px = 1e-4;
  // The fit fails when the residual RMS exceeds this fraction of the
  // paper-ink contrast: the photo does not show the decoded pattern (a wrong
  // decode, an occluded or smudged tag, a bent board). Sensor noise and the
  // model's approximations are a few hundredths.
  double max_residual_fraction = 0.12;
  double min_contrast = 10;  // paper - ink [grey levels]

  std::string Check() const;  // empty when valid
};

struct PatternFitResult {
  bool converged = false;
  std::array<Eigen::Vector2d, 4> corners;  // TargetCorner order, SPEC 2 pixels
  double ink = 0, paper = 0;               // fitted grey levels
  double blur_px = 0;                      // fitted Gaussian (optics and pixel area) [px]
  double residual_rms = 0;                 // [grey levels]
  int pixels = 0;                          // pixels fitted
  int iterations = 0;
};

// Fits the pattern `code` (the tag's code image, CV_8UC1, one pixel per bit,
// < 128 = ink, kUnknownCodeBit = unknown, else paper; tag_family.h's
// TagCodeImage) to `gray` (CV_8UC1), starting from
// `corners` (TargetCorner order, SPEC 2 pixels, roughly right to ~1 px) of
// the quad of `width_at_border` bits that starts `border_offset` bits into
// the code image. Returns the fit; `converged` is false (and `corners` the
// start) when the tag is cut by the image edge, the fit does not converge or
// fails the residual and contrast checks above.
PatternFitResult FitTagPattern(const cv::Mat& gray, const cv::Mat& code, int border_offset,
                               int width_at_border, const std::array<Eigen::Vector2d, 4>& corners,
                               const PatternFitOptions& options = {});

}  // namespace rtscalib::detect

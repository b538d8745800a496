// Two calibrations side by side (`rtscalib compare`; mrcal's
// "differencing"): how differently they project, and how their parameters
// differ relative to their combined uncertainty.
//
// Projection difference, per zoom z on a cols x rows grid of A's image:
//   v_a(q) = A's unit ray of pixel q (camera frame), v_b(q) = B's;
//   R = argmin sum |R v_a - v_b|^2 over the cells inside both valid regions
//       (all cells when fewer than 3 are): the best rotation from A's camera
//       frame to B's (SVD, no translation: for points at the map's range the
//       parallax of a camera offset between two fits is below the noise);
//   d(q) = |project_B(R v_a(q)) - project_A(v_a(q))| [px].
// The rotation removes what a camera-only comparison cannot observe: how the
// camera frame sits on the flange trades against the kinematic chain, so two
// good fits may turn the camera frame by different amounts; what remains is
// the difference of the intrinsics and distortion, as a user's pixels see it
// (mrcal fits the same kind of transform before differencing). Identical
// cameras (bit for bit) give R = I and d = 0 exactly.
//
// Parameter differences: every coordinate of ParameterLayout both models
// have (same name), d = b - a in tangent coordinates (rotations: the
// manifold's Minus, the inverse of the fit's Plus), with the
// combined sigma sqrt(P_a,ii + P_b,ii) of the two models' covariances (they
// are independent fits) and the normalised difference d / sigma; held
// coordinates (sigma 0) have none. For two fits of independent data of one
// instrument the normalised differences are ~N(0, 1): a mean square far from
// 1 says the stated uncertainties are wrong or the instruments differ. They
// are correlated (a focal length with the distortion), so their mean square
// spreads like chi^2_nu / nu with nu = p^2 / sum_ij rho_ij^2 (Satterthwaite;
// rho the correlations of the differences under P_a + P_b, p of them), not
// with p degrees of freedom: `effective_parameters` is nu.
#pragma once

#include <string>
#include <vector>

#include "libcalib/api/rtscalib.h"

namespace rtscalib {

struct CompareOptions {
  int cols = 24, rows = 18;
  std::string Check() const;
};

struct ZoomDifference {
  int zoom = 0;
  bool compared = false;  // false: a camera not determined in A or B
  int cols = 0, rows = 0, width = 0, height = 0;
  std::vector<double> diff_px;    // row-major from the top-left; NaN: not predictable in A or B
  std::vector<char> inside;       // cell centre inside both valid regions
  double rms_px = 0, max_px = 0;  // over the cells with a value
  double inside_rms_px = 0, inside_max_px = 0;  // ... inside both valid regions (NaN: none)
  double rotation_rad = 0;                      // angle of the fitted rotation
  int fit_cells = 0;                            // cells the rotation was fitted to
  double CellU(int col) const { return (col + 0.5) * width / cols - 0.5; }
  double CellV(int row) const { return (row + 0.5) * height / rows - 0.5; }
};

struct ParameterDifference {
  std::string block;  // ParameterLayout name
  int index = 0;      // coordinate within the block
  std::string unit;
  double a = 0, b = 0;    // values (tangent blocks: 0 for a, the difference for b)
  double difference = 0;  // b - a
  double sigma = 0;       // sqrt(P_a + P_b), 0 when held in both
  double normalised = 0;  // difference / sigma (0 when sigma is 0)
  bool has_sigma = false;
};

struct Comparison {
  std::vector<ZoomDifference> zooms;
  std::vector<ParameterDifference> parameters;
  double mean_square_normalised = 0;  // over parameters with a sigma
  int num_normalised = 0;
  // nu above (0 without both full covariances).
  double effective_parameters = 0;
  bool full_covariance = false;    // both models had their full covariance
  std::vector<std::string> notes;  // blocks only one model has, ...
};

// Throws std::invalid_argument when the models' zoom counts or image sizes
// differ (the caller names the files) or the options are bad.
Comparison CompareInstruments(const CalibratedInstrument& a, const CalibratedInstrument& b,
                              const CompareOptions& options = {});

}  // namespace rtscalib

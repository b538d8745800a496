// Projection uncertainty over the image, per zoom (mrcal's
// "projection uncertainty" maps): how far, at one sigma, the pixel where a
// point is seen may lie from the model's prediction, because the model's
// parameters are uncertain.
//
// For each cell centre (u, v) of a cols x rows grid over zoom z's image:
//   X     = CameraPoint(z, phi, theta, u, v, range)   the point the model sees
//           there at ray length `range` (SPEC 2), at the fixed pointing
//           (phi, theta) of the options
//   S     = PixelWithUncertainty(z, phi, theta, X).covariance = J P J^T over
//           every parameter the pixel depends on: zoom z's intrinsics,
//           distortion and camera tool, and the kinematic chain (base, DH
//           links, effects) that carries the camera to (phi, theta). mrcal
//           propagates intrinsics + extrinsics; here the extrinsics of a
//           camera at a pointing are the tool and the chain together.
//   sigma = sqrt(largest eigenvalue of S) [px], the 1-sigma ellipse's
//           semi-major axis (the worst direction).
// The range matters through the parallax of the uncertain camera position
// (tool translation, links): at infinite range only rotations and the
// camera's own parameters count.
// P is the instrument's (the full covariance when it has one; see
// CalibratedInstrument::HasFullParameterCovariance).
// A camera on its own (model.kinematics: none) has no frame but its own:
// what it measures is used through a pose (solvePnP, a board, another
// camera) that carries any turn of the camera, so a change of its
// parameters that a rotation undoes (the principal point against a small
// turn) moves nothing it measures. Its map, as mrcal's, takes out the
// rotation that best undoes the parameters' change over the cells inside
// the valid region: J* = J - J_w A with J_w the pixel's derivatives by a
// rotation of the point about the camera's centre and A = (sum J_w^T
// J_w)^-1 sum J_w^T J over those cells; S = J* P J*^T (`up_to_rotation`).
// Without it the principal point's sigma alone (about a pixel for OpenCV's
// 13 sample photos) would be the floor of every cell.
// A cell is `inside` when its centre lies in the zoom's valid region (the
// convex hull of the calibration's image points, CameraTool::valid_region):
// outside, the distortion is extrapolated and the map says how little the
// model knows there only to first order.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "libcalib/api/rtscalib.h"

namespace rtscalib {

// What the maps are drawn for: the config's `report.uncertainty_map`
// (docs/config.md, read by libcalib/config) and the report pass it on as it is.
struct UncertaintyMapOptions {
  double range_m = 10.0;    // ray length of the points [m]
  int cols = 24;            // cells across the image
  int rows = 18;            // cells down the image
  double phi = 0.0;         // pointing [rad] (face 1, towards +y)
  double theta = M_PI / 2;  // zenith angle [rad] (horizontal)
  // "" when valid, else what is wrong.
  std::string Check() const;
};

struct UncertaintyMap {
  int zoom = 0;
  bool determined = true;  // false: the zoom's camera had no data; no values
  int cols = 0, rows = 0;
  int width = 0, height = 0;     // image [px]
  std::vector<double> sigma_px;  // cols x rows, row-major from the top-left; NaN: not predictable
  std::vector<char> inside;      // 1: cell centre in the valid region
  // Over the cells with a value: all, and those inside the valid region
  // (NaN when there are none).
  double min_px = 0, median_px = 0, max_px = 0;
  double inside_median_px = 0, inside_max_px = 0;
  int cells_outside = 0;  // cells whose centre is outside the valid region
  // A camera on its own (Kinematics::kNone): the pixels' change up to the
  // camera's rotation that best undoes it inside the valid region (header).
  bool up_to_rotation = false;
  double Cell(int col, int row) const { return sigma_px[row * cols + col]; }
  // Centre of a cell [px].
  double CellU(int col) const { return (col + 0.5) * width / cols - 0.5; }
  double CellV(int row) const { return (row + 0.5) * height / rows - 0.5; }
};

// The derivatives of the pixel at which zoom `zoom` of `model` sees x_ref
// by a small rotation w [rad] of that point about the camera's centre (x ->
// c + (I + [w]x)(x - c)): 2 x 3, central differences of 1e-6 rad. Throws
// PredictionError where the pixel is not defined.
Eigen::Matrix<double, 2, 3> PixelByRotation(const InstrumentModel& model, int zoom, double phi,
                                            double theta, const Eigen::Vector3d& x_ref);

// Takes out of the pixels' derivatives by the parameters the rotation that
// best undoes them (the header's J* = J - J_w A): rows 2k, 2k + 1 of
// `by_parameters` (any number of columns) are cell k's, `by_rotation[k]` its
// PixelByRotation; A is fitted over the cells with `fit[k]` (all cells
// when none has).
void TakeOutRotation(const std::vector<Eigen::Matrix<double, 2, 3>>& by_rotation,
                     const std::vector<char>& fit, Eigen::MatrixXd* by_parameters);

// What the map's pixels are of, in a report's words: "a point at 10 m,
// pointing phi 0, theta 1.571 rad", or for a camera on its own "a
// direction (up to the camera's rotation)".
std::string MapSubject(const UncertaintyMap& map, const UncertaintyMapOptions& options);

// One map per zoom of `inst` (which must have a parameter covariance: throws
// std::logic_error otherwise, std::invalid_argument for bad options).
std::vector<UncertaintyMap> ProjectionUncertaintyMaps(const CalibratedInstrument& inst,
                                                      const UncertaintyMapOptions& options);

}  // namespace rtscalib

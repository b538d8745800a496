// Options of the refinement (libcalib/fit/refine.h): a-priori sigmas, the
// robust loss, iteration limit, bounds and critical regions. A header of its
// own so that readers of these options (the config loader in libcalib/io)
// depend on the options, not on the refinement.
#pragma once

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "libcalib/model/critical_region.h"
#include "libcalib/model/effects.h"

namespace rtscalib {

enum class RobustLoss { kNone, kHuber, kCauchy };

// Gross errors found by a robust fit before the least-squares fit
// (libcalib/fit/robust.h; config `fit.gross_errors`).
struct GrossErrorOptions {
  bool enabled = true;
  double loss_scale = 3.0;    // Cauchy scale [a-priori sigmas]
  double reject = 8.0;        // [robust sigmas] (robust.h says why 8)
  double max_fraction = 0.2;  // of a group's rows
  // Defined beside FindGrossErrorsByFit (robust.cc).
  std::string Check() const;  // empty if valid
};

// Which coefficients of an enabled distortion group the joint refinement
// fits (the config's `model.<group>: {coefficients: [k1, k2], zooms: {2:
// [k1]}}`, docs/config.md); the group's other coefficients are held at their
// start value. A group without a choice fits all its coefficients.
// HoldDistortion (libcalib/fit/parameterization.h) turns choices into the
// model's CameraTool::distortion_held.
struct DistortionChoice {
  Effect group = Effect::kRadialDistortion;
  std::vector<int> coefficients;          // DistortionIndex, fitted at every zoom not in `zooms`
  std::map<int, std::vector<int>> zooms;  // zoom -> the coefficients fitted there
  // The coefficients fitted at `zoom`.
  const std::vector<int>& At(int zoom) const {
    const auto it = zooms.find(zoom);
    return it == zooms.end() ? coefficients : it->second;
  }
};

enum class CovarianceClusters { kShot, kTag, kNone };

struct FitOptions {
  double sigma_edm_m = 1e-5;      // a-priori sigma of an EDM point coordinate
  double sigma_cam_m = 1e-5;      // a-priori sigma of a camera-record coordinate
  double sigma_pixel_px = 0.5;    // a-priori sigma of a pixel coordinate
  bool reestimate_sigmas = true;  // variance-component estimate per group
  RobustLoss loss = RobustLoss::kNone;
  double loss_scale = 3.0;  // in sigmas
  int max_iterations = 200;
  // Klug Eq. 98's |t| <= t_max, here a window of +- this around the start
  // (extraction) value of every translation block. Klug used 1e-2 m around
  // zero; with noisy records the extracted camera translation is itself only
  // good to about (1 m ray) x (rotation error of the 1-px triplet, ~1e-2 rad),
  // so the default window is 0.1 m. 0 disables the bounds.
  double translation_bound_m = 0.1;
  // Whether the cameras' fx, fy, cx, cy are free. Refine fits what it is
  // told; Calibrate decides it (FitIntrinsics, libcalib/calibrate/intrinsics.h).
  bool fit_intrinsics = false;
  // Rows in the critical regions are excluded (libcalib/model/critical_region.h):
  // the calibration's one region, fit.critical_region.
  CriticalRegion critical_region;
  int num_threads = 2;
  bool compute_covariance = true;
  // Which observations' errors the covariance lets be correlated
  // (refine.cc, TangentCovariance): kShot = the pixels of one photo (a
  // detector's errors are: blur, exposure, sampling; each record is alone),
  // kNone = the classical covariance from the sigmas alone (independent
  // errors). Config: fit.covariance_clusters.
  CovarianceClusters covariance_clusters = CovarianceClusters::kShot;
  // Read by Calibrate (not by Refine, which fits what it is given).
  GrossErrorOptions gross_errors;
  bool verbose = false;
  // Defined beside Refine (refine.cc), which enforces it.
  std::string Check() const;
};

}  // namespace rtscalib

// Global numerical refinement with Ceres (Klug Sec. 4.3, extended).
//
// Least squares on point distances (records) and reprojection errors (pixels),
// each group weighted by its sigma. Parameters: all 26 of Klug Eq. 99 (base,
// two DH links, EDM and camera tools) plus enabled effects, per-zoom
// intrinsics and distortion. Gauge freedoms are held fixed (docs/refinement.md):
//   dh: gamma_1 and d_1 (base rotation/translation about/along axis 1 absorb
//       them), link 2 entirely (the tools absorb it), EDM roll about its ray.
//   spherical: EDM rotation (ideal), EDM t_z (edm_offset), EDM roll.
#pragma once

#include <string>
#include <vector>

#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"

namespace rtscalib {

enum class RobustLoss { kNone, kHuber, kCauchy };

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
  bool fit_intrinsics = false;
  // Zenith limits outside of which rows are excluded (critical regions, SPEC 1).
  double min_zenith_rad = 10.0 * M_PI / 180.0;
  double max_zenith_rad = 135.0 * M_PI / 180.0;
  int num_threads = 2;
  bool compute_covariance = true;
  bool verbose = false;
  std::string Check() const;
};

struct FitSummary {
  bool converged = false;
  int iterations = 0;
  double initial_cost = 0, final_cost = 0;
  double seconds = 0;
  int num_residuals = 0, num_parameters = 0;
  int excluded_critical = 0;
  double sigma0_records = 1, sigma0_pixels = 1;                     // a-posteriori / a-priori sigma
  double sigma_edm_m = 0, sigma_cam_m = 0, sigma_pixel_px = 0;      // a-posteriori sigmas
  std::vector<std::string> fixed_gauges;                            // human-readable
  std::vector<std::pair<std::string, double>> strong_correlations;  // "a ~ b", rho
  std::vector<std::string> downweighted;  // robust loss: observations down-weighted
  std::string message;
};

// Refines `model` in place. Throws std::invalid_argument for bad options.
FitSummary Refine(const Observations& obs, const FitOptions& options, InstrumentModel* model);

}  // namespace rtscalib

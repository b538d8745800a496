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

#include "libcalib/fit/options.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"

namespace rtscalib {

// The variance-component estimate has settled when no group's sigma moves by
// more than this fraction in a round.
constexpr double kSigmaSettled = 0.05;

struct FitSummary {
  bool converged = false;
  int iterations = 0;
  double initial_cost = 0, final_cost = 0;
  double seconds = 0;
  int num_residuals = 0, num_parameters = 0;
  int excluded_critical = 0;
  double sigma0_records = 1, sigma0_pixels = 1;                     // a-posteriori / a-priori sigma
  double sigma_edm_m = 0, sigma_cam_m = 0, sigma_pixel_px = 0;      // a-posteriori sigmas
  // The pixels' a-posteriori sigma per zoom (0 where a zoom has no pixels);
  // sigma_pixel_px is their root mean square over the pixels.
  std::vector<double> sigma_pixel_px_zoom;
  // The variance-component estimate (FitOptions::reestimate_sigmas): rounds
  // of solve and re-estimate (the first solve with the start sigmas; 0 when
  // the sigmas were held), and whether the last estimate moved no sigma by
  // more than kSigmaSettled (false when the rounds ran out first).
  int sigma_rounds = 0;
  bool sigmas_converged = false;
  // Clusters of the cluster-robust covariance (0: independent errors).
  int covariance_clusters = 0;
  std::vector<std::string> fixed_gauges;                            // human-readable
  std::vector<std::pair<std::string, double>> strong_correlations;  // "a ~ b", rho
  std::vector<std::string> downweighted;  // robust loss: observations down-weighted
  std::string message;
};

// Refines `model` in place. Throws std::invalid_argument for bad options.
// `earlier` (optional): an earlier fit of the same instrument whose
// a-posteriori sigmas start the variance-component estimate instead of the
// a-priori ones (groups it has no sigma for start a priori).
FitSummary Refine(const Observations& obs, const FitOptions& options, InstrumentModel* model,
                  const FitSummary* earlier = nullptr);

// Iterations a robust Refine of `obs` needs before its residuals separate
// the gross rows, which follows from the residual blocks Refine builds with
// a robust loss: records alone (a block per record, Ceres's LossFunction
// and its Triggs steps) 8, as the solution need not converge to round-off
// (a least-squares fit follows); with photos (ObservationLoss rescales each
// corner inside its photo's block) 15 to 30 Gauss-Newton steps, so the
// fit runs to convergence (50). Stopped at 8, the photos' fit leaves clean
// corners beyond the limit (tests/calibrate/gross_errors_test.cc).
int RobustSearchIterations(const Observations& obs);

}  // namespace rtscalib

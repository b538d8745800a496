// Does each kind of observation fit as well as its a-priori sigma says it
// can? A model that lacks an effect leaves residuals larger than the noise;
// the diagnosis says so first, before any ranking (docs/diagnostics.md).
//
// Cells: EDM points, camera points of each zoom and image points of each
// zoom, each per face. In a cell with `rows` residual coordinates r_i (model
// minus observed, in metres or pixels) and the a-priori sigma s of its kind
// (FitOptions::sigma_edm_m, sigma_cam_m, sigma_pixel_px: what the user says
// the noise is),
//   chi2   = sum r_i^2 / s^2
//   dof    = rows (1 - p / N)        p = the fit's parameters, N = all rows
//                                    (each cell carries its share of them)
//   factor = sqrt(chi2 / dof)        how many times the a-priori sigma the
//                                    residuals are
//   p      = ChiSquareSurvival(chi2, dof)
// A cell exceeds its sigma when p < significance / (number of cells)
// (Bonferroni) and factor > kMinFactor: a nominal a-priori sigma is commonly
// off by tens of per cent, which is not what a missing effect looks like.
#pragma once

#include <string>
#include <vector>

#include "libcalib/diagnose/linearization.h"
#include "libcalib/fit/options.h"
#include "libcalib/model/observations.h"

namespace rtscalib {

constexpr double kMinFactor = 1.5;

struct FitQualityCell {
  ObsGroup group = ObsGroup::kPixel;
  int zoom = -1;  // -1 for EDM points
  int face = 1;
  std::string name;  // "image points of zoom 1, face 2"
  std::string unit;  // "m" or "px"
  int observations = 0, rows = 0;
  double rms = 0;      // per coordinate [unit]
  double apriori = 0;  // the a-priori sigma [unit]
  double dof = 0, chi2 = 0, factor = 0, p_value = 1;
  bool exceeds = false;
};

struct FitQuality {
  std::vector<FitQualityCell> cells;  // EDM, then camera, then image points; by zoom, face
  double level = 0;                   // per-cell test level
  bool Exceeds() const;
};

// `lin` is the linearisation of the fitted model (whitened by the fit's
// a-posteriori sigmas), `num_parameters` the fit's (rank of the base).
FitQuality AssessFitQuality(const Linearization& lin, const Observations& obs,
                            const FitOptions& apriori, int num_parameters, double significance);

}  // namespace rtscalib

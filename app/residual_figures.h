// The figures of a calibration's residual table (CalibrationResult::residuals,
// one row per observation at the final model, boards of unknown pose at their
// estimates), as Vega specs (plot/vega_spec.h): where on the sphere of pointings
// the model fails, where in the image, against which variable, and how the
// residuals are distributed. Nothing here predicts or fits.
#pragma once

#include <set>
#include <string>
#include <vector>

#include "app/plot/vega_spec.h"
#include "libcalib/diagnose/residuals.h"
#include "libcalib/fit/options.h"
#include "libcalib/model/instrument.h"

namespace rtscalib::app {

// Which rows an error map shows, and in what unit.
struct MapSource {
  std::string key, title, unit;
  double scale = 1;  // to the unit shown
  ObsGroup group = ObsGroup::kEdm;
  int zoom = 0;
};

// rms of |observed - model| per pointing and face, the critical regions
// (fit's zenith limits) shaded; `model` names the model in the subtitle.
Figure ErrorMap(const MapSource& src, const std::vector<ObservationResidual>& rows,
                const std::set<int>& faces, const FitOptions& fit, const std::string& model);

// The fitted pixel rows (and camera records) of `zoom` binned over the image:
// mean vector per cell, scaled, the cells with structure beyond the noise
// marked.
Figure ImageResiduals(int zoom, const CameraTool& cam,
                      const std::vector<ObservationResidual>& rows);

// Residuals against each variable the diagnosis tests (binned mean and its
// 2-sigma band), one row of panels per variable.
Figure VariablesFigure(const std::vector<ObservationResidual>& rows);

// Residual coordinates per group against the Gaussian of the fitted sigma.
Figure Histograms(const std::vector<ObservationResidual>& rows);

}  // namespace rtscalib::app

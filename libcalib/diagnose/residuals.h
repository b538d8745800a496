// Residuals of a model, one per observation, in the components a surveyor
// reads: along the ray and across it as horizontal-direction and zenith-angle
// errors (SPEC 1: Hz clockwise from +y, zenith from straight up).
//
// For a record with model point x_calc = o + d u (o the tool origin, u the unit
// ray, Hz/z its direction) and measured point x:
//   delta   = x - x_calc                                  observed - model [m]
//   along   = delta . u                                   [m]
//   dHz     = delta . (cos Hz, -sin Hz, 0) / (d sin z)    [rad]  (= d u / d Hz normalised)
//   dz      = delta . (sin Hz cos z, cos Hz cos z, -sin z) / d   [rad]
// For a pixel observation the observed and the predicted pixel are turned into
// unit rays in the reference frame with the model's camera; dHz and dz are the
// same projections of their difference (d = 1), and delta = (du, dv, 0) [px].
//
// ResidualTable is the one table of a calibration's residuals: every row of
// the observations as given (gross errors and critical-region rows
// included, marked with why they were left out), at the final model with its
// estimated boards and points (SPEC 7, libcalib/fit/unknowns.h
// WithEstimates), with what a picture or a file needs: where the row came
// from (line, shot, placement, target, corner, point), the observed and the
// predicted value, and the residual over the fitted sigma of its group.
// Figures, residuals.csv and report.json draw from it and never recompute a
// prediction.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <string>
#include <vector>

#include "libcalib/diagnose/linearization.h"
#include "libcalib/fit/refine.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"

namespace rtscalib {

// Why a row is or is not in the fit.
enum class ResidualStatus {
  kFitted,          // used by the final fit
  kCriticalRegion,  // zenith angle in a critical region (SPEC 1): not fitted
  kGrossError,      // taken out as a gross error before the fit (reason says why)
  kNotPredicted,    // the model cannot predict it (behind the camera, no such zoom)
};
const char* ResidualStatusName(ResidualStatus s);  // "fitted", "critical_region", ...

struct ObservationResidual {
  ObsGroup group = ObsGroup::kEdm;
  int index = 0;  // into obs.records or obs.pixels
  int face = 1;
  int zoom = 0;
  double phi = 0, theta = 0;
  double d = 0;         // EDM distance or ray length [m]; 0 for pixels
  double u = 0, v = 0;  // observed pixel (cam records and pixels)
  bool valid = false;
  bool critical = false;  // in a critical region (not used by the fit)
  Eigen::Vector3d delta = Eigen::Vector3d::Zero();
  double along = 0;   // [m] (records)
  // Horizontal-direction and zenith components of the residual [rad] (pixels:
  // of the camera ray); NaN for a camera on its own (Kinematics::kNone), whose
  // frame has no vertical.
  double hz = 0;
  double zenith = 0;
  double size = 0;    // |delta| [m] or [px]
  // The observed and the predicted value: records x, y, z [m]; pixels u, v, 0 [px].
  Eigen::Vector3d observed = Eigen::Vector3d::Zero();
  Eigen::Vector3d predicted = Eigen::Vector3d::Zero();
  // Observed minus predicted pixel [px]: pixels (= delta's u, v), and cam
  // records (u, v minus their point projected at the reading); NaN for EDM
  // rows and rows the model cannot project.
  Eigen::Vector2d image_delta = Eigen::Vector2d::Constant(std::nan(""));
  // Variables the diagnosis tests the residuals against, besides phi, theta, d:
  double target_distance = 0;  // camera (pixels) or tool (records) to the point [m]
  double image_radius = -1;    // pixels and cam records: |uv - principal point| [px]; else -1

  // Filled by ResidualTable (ObservationResiduals leaves the defaults):
  ResidualStatus status = ResidualStatus::kFitted;
  std::string reason;            // why the row is not fitted; "" when it is
  int line = 0;                  // line in its file (0: not from a file)
  std::string shot;              // pixels: the photo
  std::string placement;         // pixels: SPEC 7.1
  int target = -1, corner = -1;  // pixels: tag id and corner
  std::string point;             // records of a point of unknown position (SPEC 7)
  double sigma = 0;              // the group's fitted sigma [m] or [px] (pixels: of the zoom)
  double normalised = 0;         // size / sigma
};

// Every observation, critical-region rows marked (zenith limits of `fit`).
std::vector<ObservationResidual> ObservationResiduals(const Observations& obs,
                                                      const InstrumentModel& model,
                                                      const FitOptions& fit);

// Every row of `obs` as given (records, then pixels; `index` into them), at
// `model` with its estimated boards and points; `gross` (CalibrationResult::
// gross_rows) marked kGrossError with their reason; sigmas from `summary`
// (a-posteriori, falling back to `fit`'s a-priori ones).
std::vector<ObservationResidual> ResidualTable(const Observations& obs,
                                               const InstrumentModel& model, const FitOptions& fit,
                                               const FitSummary& summary,
                                               const std::vector<ExcludedRow>& gross);

// "records.csv:17" or "simulated records, row 17 (edm, phi 30.0, theta 80.0 deg, d 2 m)".
std::string Where(const Observations& obs, ObsGroup group, int index);

}  // namespace rtscalib

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
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "libcalib/diagnose/linearization.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"

namespace rtscalib {

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
  double hz = 0;      // [rad]
  double zenith = 0;  // [rad]
  double size = 0;    // |delta| [m] or [px]
};

// Every observation, critical-region rows marked (zenith limits of `fit`).
std::vector<ObservationResidual> ObservationResiduals(const Observations& obs,
                                                      const InstrumentModel& model,
                                                      const FitOptions& fit);

// "records.csv:17" or "simulated records, row 17 (edm, phi 30.0, theta 80.0 deg, d 2 m)".
std::string Where(const Observations& obs, ObsGroup group, int index);

}  // namespace rtscalib

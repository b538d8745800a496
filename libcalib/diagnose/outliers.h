// Outliers: Baarda's standardised-residual test (the w-test of data snooping),
// per observation.
//
// One observation is a record (3 coordinates) or an image point (2). Its
// residual is split into components with their own noise level:
//   records: along the ray (EDM noise) and across it (angle noise, grows with d)
//   pixels:  u and v
// The noise of each component is estimated per stratum (tool, zoom and a
// half-octave bin of the distance for records; zoom for pixels) robustly, from
// the median of the squared components, so that the outliers being looked for
// do not inflate it. With leverage h (from the fit's Jacobian) the test
// statistic of one observation is
//   T = (e_along^2 / s_along^2 + |e_across|^2 / s_across^2) / (1 - h)   ~ chi2(3)
//   T = |e_uv|^2 / s_px^2 / (1 - h)                                      ~ chi2(2)
// and its w value is the normal deviate with the same tail probability (for
// one coordinate this is Baarda's w). An observation is flagged when its tail
// probability is below significance / (number of observations) (Bonferroni:
// the test is applied to every observation).
#pragma once

#include <string>
#include <vector>

#include "libcalib/diagnose/linearization.h"
#include "libcalib/diagnose/residuals.h"

namespace rtscalib {

struct OutlierEntry {
  ObsGroup group = ObsGroup::kEdm;
  int index = 0;
  std::string where;  // file:line or shot/tag
  double w = 0;       // normal deviate of the observation's test statistic
  double p_value = 1;
  bool flagged = false;
  double size = 0;  // |residual| [m] or [px]
};

struct OutlierReport {
  double critical_w = 0;  // w above which an observation is flagged
  int tested = 0;
  int flagged = 0;
  std::vector<OutlierEntry> worst;  // largest w first
};

// `residuals` from ObservationResiduals of the same model; `red.base` gives
// the leverages.
OutlierReport TestOutliers(const Observations& obs, const Linearization& lin, const Reduced& red,
                           const std::vector<ObservationResidual>& residuals, double significance,
                           int max_listed = 12);

}  // namespace rtscalib

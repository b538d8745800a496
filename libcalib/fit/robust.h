// Gross errors found by a robust fit (docs/refinement.md,
// "Gross errors"). After the screening before the fit (libcalib/screen/gross.h)
// has taken out what no instrument could produce, the rest is found so:
//
//  1. Rows the start cannot evaluate (a known point behind the camera) are
//     gross when they are a minority of their group.
//  2. One refinement with a Cauchy loss (scale GrossErrorOptions::loss_scale (fit/options.h)
//     a-priori sigmas) from the start: a row far off costs about log(r^2),
//     so a few rows cannot pull the solution (GNU Gama and JAG3D do the same
//     with their robust re-weighting). It is skipped when steps 3 and 4 at
//     the least-squares solution (grouped residual blocks, a plain
//     refinement's cost) flag no row: the robust fit needs one residual
//     block per row and costs a clean run several times a plain one
//     (calibrate_benchmark: BM_CalibrateClean against
//     BM_CalibrateCleanWithoutGrossErrorHandling, and BM_MillionRecordsFromFile).
//  3. Per group (EDM rows, camera rows of a zoom, pixels of a zoom), the
//     robust sigma of one coordinate: median |r| / median of chi with the
//     row's dimension (3 for points, 2 for pixels), from the robust
//     solution. Records' noise grows with the distance (angle noise times
//     d), so their sigma is taken over runs of 40 rows sorted by d. A
//     sigma never goes below 1 % of the a-priori one (noise-free data
//     leave round-off, which is no gross error).
//  4. A row whose |r| exceeds `reject` robust sigmas is gross. 8 sigmas:
//     chi_3 and chi_2 beyond 6 happen once in 10^7 rows of isotropic
//     Gaussian noise, but a record's noise is not isotropic (angle noise
//     across the ray, EDM noise along it), which lengthens the tail: the
//     largest clean row of tests/calibrate/gross_errors_test.cc's 2,600
//     EDM rows sits at 6.4.
//
// The calibration then starts again without the gross rows and fits by
// least squares, so that the final model and its covariance are those of
// the clean rows. More than `max_fraction` of a group flagged means the
// model, not the rows, is wrong: nothing is excluded and a note says so.
#pragma once

#include <string>
#include <vector>

#include "libcalib/fit/options.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"

namespace rtscalib {

struct RobustFitResult {
  std::vector<ExcludedRow> gross;  // ExcludedRow::index into the observations given
  std::vector<std::string> notes;
  double robust_sigma[3] = {0, 0, 0};  // largest: EDM [m], camera rows [m], pixels [px]
};

// `model` is the start; it is left at the robust solution. Throws what
// Refine throws. `suspect`: gross rows were already found (by the
// screening), so the least-squares trial of step 2 is skipped.
RobustFitResult FindGrossErrorsByFit(const Observations& obs, const FitOptions& options,
                                     const GrossErrorOptions& robust, InstrumentModel* model,
                                     bool suspect = false);

}  // namespace rtscalib

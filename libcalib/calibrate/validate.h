// What the data cannot support is a failure, never a published model: the
// checks run after every fit stage of Calibrate (and on the start of the
// refinement), and what they find is thrown as a CalibrationFailure that names
// the rows to look at.
//
// A fit fails when
//   1. non-finite: its cost, a parameter, or a row's weighted squared
//      residual (r / sigma_a_priori)^2 is not finite;
//   2. not converged: Ceres stopped without convergence (NO_CONVERGENCE,
//      FAILURE: FitSummary::converged false) or did not even evaluate the
//      start (0 iterations). FitSummary does not count successful steps: a
//      bad start from which no step succeeded (Ceres may then still report
//      CONVERGENCE on the trust region radius) is caught by 3, a start that
//      is already the optimum is not a failure;
//   3. absurd: a group's (EDM records, camera records, pixels) a-posteriori
//      sigma0 = sqrt(sum (r / sigma)^2 / (k n)) exceeds FitChecks::max_sigma0
//      (r: a record's 3-D point distance [m] (k = 3) or a pixel's 2-D error
//      [px] (k = 2), sigma: the configured a-priori sigma, n: rows). With a
//      robust loss, outliers are expected and down-weighted, so sigma0 is
//      the robust estimate from the median instead: median(r / sigma) / m_k,
//      m_k the median of a chi distribution with k degrees of freedom.
// Rows inside the critical regions are left out, as the fit leaves them out.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "libcalib/calibrate/options.h"
#include "libcalib/fit/options.h"
#include "libcalib/fit/refine.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"

namespace rtscalib {

// Thrown by Calibrate when a fit's outcome cannot be a model (see above).
// what(): "<stage>: <reason>" and, one per line, the rows named.
struct CalibrationFailure : std::runtime_error {
  enum class Kind { kNonFinite, kNotConverged, kAbsurdResiduals };
  Kind kind;
  std::string stage;   // "refinement on the full set", ...
  std::string reason;  // one sentence, numbers included
  // "records.csv:12: EDM residual 3.1e+02 m (3.1e+07 sigma)", worst first.
  std::vector<std::string> rows;

  CalibrationFailure(Kind kind, std::string stage, std::string reason,
                     std::vector<std::string> rows);
};
const char* FailureKindName(CalibrationFailure::Kind kind);

// Per-group a-posteriori sigma0 (see the header comment); 0 for an empty group.
struct Sigma0 {
  double edm = 0, cam = 0, pixels = 0;
  int n_edm = 0, n_cam = 0, n_pixels = 0;
};
Sigma0 ComputeSigma0(const Observations& obs, const InstrumentModel& model,
                     const FitOptions& options);

// Throws CalibrationFailure for cases 1-3 above, naming up to
// checks.max_rows_named rows (non-finite first, then the largest r / sigma).
void ValidateFit(const std::string& stage, const Observations& obs, const InstrumentModel& model,
                 const FitSummary& fit, const FitOptions& options, const FitChecks& checks);

// Before a fit: the start's parameters and every row's weighted squared
// residual must be finite, else Ceres cannot even evaluate the start (and a
// non-finite parameter block aborts inside Ceres). Throws CalibrationFailure.
void ValidateStart(const std::string& stage, const Observations& obs, const InstrumentModel& start,
                   const FitOptions& options, const FitChecks& checks);

// Sets InstrumentModel::edm_determined and CameraTool::determined from the
// rows outside the critical regions; returns one note per undetermined tool.
std::vector<std::string> MarkUndeterminedTools(const Observations& obs, const FitOptions& options,
                                               InstrumentModel* model);

}  // namespace rtscalib

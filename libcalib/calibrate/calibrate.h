// The calibration of a robotic total station as one call: observations +
// options -> every stage's outcome. Stages (Klug et al. 2018 and the joint
// camera refinement):
//   1. extraction of the DH model (Sec. 3); when it fails for want of Klug's
//      pixel triplets (Eq. 67) and configured intrinsics, again with
//      intrinsics estimated from the view rays;
//   2. simplification (Sec. 4.1) and its closed form (Eq. 90/91);
//   3. the start of the refinement: the extraction (cameras of zooms without
//      camera rows from their pixels), or the pixels alone; the configured
//      kinematics and effects; Table 4 (Eq. 92/93, methods A and B) of the
//      extracted and simplified models on the reduced set;
//   4. the intrinsics decision (model.intrinsics auto: fitted when the
//      camera data span the image), the refinement (Sec. 4.3) on the reduced
//      set and on the full set, Table 5;
//   5. with faces: separate, one model per face and the two-face check;
//   6. the diagnosis (libcalib/diagnose) of the refined model, or with
//      diagnose.auto the forward stepwise ladder that starts from it;
//   7. the final errors of the final model, its residual table (every row,
//      excluded ones marked) and the coverage of the fitted rows.
// Nothing here reads or writes files or prints: progress goes to a
// CalibrationProgress, the caller writes the reports.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "libcalib/calibrate/options.h"
#include "libcalib/calibrate/progress.h"
#include "libcalib/diagnose/diagnose.h"
#include "libcalib/diagnose/stepwise.h"
#include "libcalib/eval/error_measures.h"
#include "libcalib/extract/extract.h"
#include "libcalib/fit/refine.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"

namespace rtscalib {

// Klug Table 4: errors of the extracted and of the simplified model on the
// reduced set.
struct Table4 {
  ModelErrors dh_a, dh_b, simplified_a, simplified_b;
};

// Klug Table 5, method B: the model refined on the reduced set evaluated on
// it, the same model on the full set (cross-validation), and the model
// refined and evaluated on the full set. These are the configured models
// (CalibrationResult::reduced and ::refined), never the stepwise ladder's.
struct Table5 {
  ModelErrors reduced, cross, full;
  bool has_cross = false;  // false when the data hold no rows beyond the sweeps
  int reduced_rows = 0, full_rows = 0;
};

// SPEC 6 `final`: per-tool statistics over every record's point distance
// (Eq. 92/93) and the pixel RMS.
struct FinalErrors {
  ErrorStats edm, cam;
  PixelStats pixels;
};

// `faces: separate`: one model per face and the classical two-face check.
struct FaceComparison {
  InstrumentModel face1, face2;
  FitSummary fit1, fit2;
  // Half the face-2 minus face-1 differences, read off both models with the
  // spherical form (SPEC 4): collimation c, tilting axis i, vertical index v0 [rad].
  double collimation = 0, tilting_axis = 0, vertical_index = 0;
  bool valid = false;
  std::string note;
};

// A refined model and the summary of its fit.
struct Refinement {
  InstrumentModel model;
  FitSummary fit;
};

struct CalibrationResult {
  std::optional<ExtractionResult> extraction;  // absent without records
  std::optional<InstrumentModel> simplified;
  std::string closed_form;       // Eq. 90-style text of the simplified model
  std::optional<Table4> table4;  // of extraction->model and *simplified
  InstrumentModel start;         // what the refinement started from
  bool intrinsics_fitted = false;
  FitOptions fit_options;  // what the full-set refinement used (intrinsics decided)
  Refinement reduced;      // the configured model refined on the reduced set
  Refinement refined;      // the configured model refined on the full set
  Table5 table5;           // of `reduced` and `refined`
  std::optional<FaceComparison> faces;
  // With diagnose.auto: the forward stepwise ladder; its first rung is
  // `refined`, its last rung `final_model`.
  std::vector<LadderStep> ladder;
  std::string ladder_stop;
  // The run's model: `refined`, or the last rung of the ladder when the
  // ladder added effects. The diagnosis and the final errors are of it.
  InstrumentModel model;
  FitSummary fit;
  std::optional<Diagnosis> diagnosis;  // absent when off or failed (see notes)
  FinalErrors final_errors;
  // Every observation as given at `model` (ResidualTable, diagnose/residuals.h):
  // the one table reports, files and figures draw residuals from.
  std::vector<ObservationResidual> residuals;
  // What the fitted rows cover (angles, distances, the image per zoom) and
  // the warnings it gives (CoverageWarnings).
  Coverage coverage;
  std::vector<std::string> coverage_warnings;
  // Per zoom of the model, where its image size came from (SPEC 7: never
  // guessed from where the points fall): "images" (Observations::image_sizes,
  // read from the photos), "config" (model.cameras) or "estimated" (neither:
  // records-only data; the size is the extraction's guess from the principal
  // point and the pixels, and a note says so).
  std::map<int, std::string> size_source;
  // Rows taken out as gross errors (screening before the fit, then the
  // robust fit; ExcludedRow::index into the observations given). Every
  // stage above saw the observations without them.
  std::vector<ExcludedRow> gross_rows;
  std::vector<std::string> notes;

  // True when the ladder extended the model beyond the configured one, so
  // that `model` differs from `refined.model`.
  bool LadderExtendedModel() const { return ladder.size() > 1; }
};

// Runs every stage above, after the screening of the observations
// (libcalib/screen/screen.h), whose warnings start `notes`. Throws InputError
// for the data mistakes the screening finds, ExtractionError when the records
// give no model, std::invalid_argument for invalid options or data the options cannot
// use (a zoom without a camera), CalibrationFailure (validate.h) when a fit
// stage's outcome is not finite, not converged or far beyond the sigmas. A
// tool without rows is kept at its start and marked not determined
// (InstrumentModel::edm_determined, CameraTool::determined), with a note. A
// failing diagnosis (its stepwise refit included) does not fail the
// calibration: it leaves a note (diagnosis absent).
CalibrationResult Calibrate(const Observations& obs, const CalibrationOptions& options,
                            CalibrationProgress* progress = nullptr);

// Calibrate in two parts, for a caller that uses the fitted model while its
// diagnosis runs (the run draws its figures meanwhile). CalibrateModel runs
// every stage but the plain diagnosis of stage 6 and leaves `diagnosis`
// empty; with diagnose.auto it runs the ladder, which makes the model, and
// its diagnosis. DiagnoseCalibration then diagnoses `result` without
// changing it (nothing when DiagnosisPending is false), and AddDiagnosis
// puts the outcome into the result. Calibrate is exactly these three calls.
CalibrationResult CalibrateModel(const Observations& obs, const CalibrationOptions& options,
                                 CalibrationProgress* progress = nullptr);
// Does DiagnoseCalibration have work after CalibrateModel?
bool DiagnosisPending(const CalibrationOptions& options);
struct CalibrationDiagnosis {
  std::optional<Diagnosis> diagnosis;  // absent when off or failed
  std::vector<std::string> notes;      // "diagnosis failed: ..." when it failed
};
CalibrationDiagnosis DiagnoseCalibration(const Observations& obs,
                                         const CalibrationOptions& options,
                                         const CalibrationResult& result,
                                         CalibrationProgress* progress = nullptr);
void AddDiagnosis(CalibrationDiagnosis diagnosis, CalibrationResult* result);

// Rows of the "reduced" set: set labels starting with "sweep" when the file
// has labels, otherwise the rows of the extraction's sweeps poses.
std::vector<Record> ReducedRecords(const std::vector<Record>& records,
                                   const std::optional<ExtractionResult>& extraction);

FinalErrors ComputeFinalErrors(const InstrumentModel& model, const Observations& obs);

}  // namespace rtscalib

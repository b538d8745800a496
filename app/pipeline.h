// The calibration pipeline of `rtscalib --config`: observations -> extraction
// (Klug Sec. 3) -> simplification (Sec. 4.1) -> error measures (Sec. 4.2) ->
// refinement (Sec. 4.3 and the joint camera refinement) -> results. Writes no
// files; app/report_*.cc turn the result into files.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "app/progress.h"
#include "app/render_stage.h"
#include "libcalib/diagnose/diagnose.h"
#include "libcalib/diagnose/stepwise.h"
#include "libcalib/eval/error_measures.h"
#include "libcalib/extract/extract.h"
#include "libcalib/fit/refine.h"
#include "libcalib/io/config.h"
#include "libcalib/model/instrument.h"

namespace rtscalib::app {

// Klug Table 4: errors of the extracted and of the simplified model.
struct Table4 {
  ModelErrors dh_a, dh_b, simplified_a, simplified_b;
};

// Klug Table 5: the refined model fitted on the reduced set and evaluated on
// it, the same model evaluated on the full grid (cross-validation), and a
// model fitted and evaluated on the full set. Method B.
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

struct PipelineResult {
  Observations obs;
  bool simulated = false;
  std::optional<InstrumentModel> truth;  // only for simulated data, for the report
  std::optional<ExtractionResult> extraction;
  std::optional<InstrumentModel> simplified;
  std::string closed_form;  // Eq. 90-style text of the simplified model
  std::optional<Table4> table4;
  InstrumentModel start;          // what the refinement started from
  InstrumentModel reduced_model;  // refined on the reduced set
  FitSummary reduced_fit;
  InstrumentModel model;  // the final model (full set)
  FitSummary fit;
  Table5 table5;
  FinalErrors final_errors;
  std::optional<FaceComparison> faces;
  std::vector<std::string> notes;
  bool intrinsics_fitted = false;
  FitOptions fit_options;  // what the full-set refinement used
  // Diagnosis of `model` (app/diagnosis_report.h); with diagnose.auto the
  // stepwise ladder whose last rung is `model`.
  std::optional<diagnose::Diagnosis> diagnosis;
  std::vector<diagnose::LadderStep> ladder;
  std::string ladder_stop;
  RenderStageResult render;  // synthetic shots, when the config renders
};

// Loads or simulates the observations of a config (the data section, or the
// simulate section when there are no data files).
// `work_dir` receives what acquisition produces (rendered images).
Observations LoadObservations(const RunConfig& config, const std::string& work_dir,
                              PipelineResult* result, Progress* progress);

PipelineResult RunPipeline(const RunConfig& config, const std::string& work_dir,
                           Progress* progress);

// Rows of the "reduced" set: set labels starting with "sweep" when the file
// has labels, otherwise the rows of the extraction's sweeps poses.
std::vector<Record> ReducedRecords(const std::vector<Record>& records,
                                   const std::optional<ExtractionResult>& extraction);

FinalErrors ComputeFinalErrors(const InstrumentModel& model, const Observations& obs);

}  // namespace rtscalib::app

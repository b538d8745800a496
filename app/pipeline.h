// The run of `rtscalib --config`: the config (libcalib/io plus the render
// module's section) -> the observations (data files, or the simulator and,
// with a `render` section, rendered shots and detected tags) -> the
// calibration (Calibrate, libcalib/calibrate). Writes no files besides the
// rendered photo session (<work_dir>/photos); app/report*.cc turn the result
// into files.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "app/photo_session.h"
#include "app/progress.h"
#include "app/render_stage.h"
#include "libcalib/api/uncertainty_map.h"
#include "libcalib/calibrate/calibrate.h"
#include "libcalib/config/config.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"
#include "libcalib/plan/settings.h"
#include "render/settings.h"

namespace rtscalib::app {

// The whole config file of a run: the library's sections and the render
// module's `render` section.
struct RunSettings {
  RunConfig config;
  render::RenderSettings render;
  // The `plan` section (libcalib/plan/settings.h): read so that the config a
  // session was planned with also calibrates it; the run does not use it.
  PlanSettings plan;
};
// Throws InputError for anything wrong in the file, unknown keys inside
// `render:` and `plan:` included (whether or not the run renders).
RunSettings LoadRunSettings(const std::string& path);
// The effective config as YAML (DumpConfig plus the render section).
std::string DumpRunSettings(const RunSettings& settings);

struct PipelineResult {
  Observations obs;
  bool simulated = false;
  std::optional<InstrumentModel> truth;  // only for simulated data, for the report
  RenderStageResult render;              // synthetic shots, when the config renders
  // The photos read (data.shots, or the session the render stage wrote).
  PhotoSessionSummary photos;
  CalibrationResult calibration;
  // Notes of reading or acquiring the observations, then the calibration's.
  std::vector<std::string> notes;
  // Projection uncertainty per zoom (empty when the fit has no covariance),
  // and whether it comes from the full covariance (else model.yaml's sigmas).
  std::vector<UncertaintyMap> uncertainty_maps;
  UncertaintyMapOptions uncertainty_options;
  bool full_covariance = false;
};

// The observations of a config: the data files (records, pixels, and the
// photos of data.shots with data.targets, detected here), or the simulate
// section when there are none. A simulate section with a `render` section
// writes a photo session into <work_dir>/photos (app/render_stage.h) and
// reads it back through the same code as data.shots: its pixels are the
// detected corners, never the simulator's own.
Observations LoadObservations(const RunSettings& settings, const std::string& work_dir,
                              PipelineResult* result, Progress* progress);

// Work on the calibrated result that does not need its diagnosis (the
// run's figures): RunPipeline calls it once, with everything but
// `calibration.diagnosis` (and a failed diagnosis's note) in place.
using Alongside = std::function<void(const PipelineResult&)>;

// LoadObservations, then Calibrate with the config's options (CalibrateModel,
// DiagnoseCalibration), then the projection uncertainty maps. `alongside`,
// when given, runs while the diagnosis does when the diagnosis only reads
// the calibration (DiagnosisPending); with diagnose.auto, after it. It
// comes before the uncertainty maps, `mapped` after them (the figures'
// drawing starts before the maps are computed).
PipelineResult RunPipeline(const RunSettings& settings, const std::string& work_dir,
                           Progress* progress, const Alongside& alongside = nullptr,
                           const Alongside& mapped = nullptr);

}  // namespace rtscalib::app

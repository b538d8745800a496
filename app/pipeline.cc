#include "app/pipeline.h"

#include "libcalib/api/uncertainty_map.h"

#include <filesystem>
#include <future>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>

#include "detect/photos.h"
#include "libcalib/io/records.h"
#include "libcalib/io/targets_io.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib::app {

RunSettings LoadRunSettings(const std::string& path) {
  RunSettings s;
  const std::string dir = std::filesystem::absolute(path).parent_path().string();
  s.config =
      LoadConfig(path, {render::RenderConfigSection(&s.render), PlanConfigSection(&s.plan, dir)});
  return s;
}

std::string DumpRunSettings(const RunSettings& settings) {
  render::RenderSettings render = settings.render;
  PlanSettings plan = settings.plan;
  return DumpConfig(settings.config, {render::RenderConfigSection(&render),
                                      PlanConfigSection(&plan, settings.config.config_dir)});
}

Observations LoadObservations(const RunSettings& settings, const std::string& work_dir,
                              PipelineResult* result, Progress* progress) {
  const RunConfig& config = settings.config;
  Observations obs;
  if (!config.records_path.empty() || !config.pixels_path.empty() || !config.shots_path.empty()) {
    progress->Step("reading observations");
    obs.angle_unit = config.angle_unit;
    if (!config.records_path.empty()) {
      RecordsFile f = ReadRecords(config.records_path, config.angle_unit);
      obs.records = std::move(f.records);
      obs.record_covariates = std::move(f.covariates);
      obs.records_source = config.records_path;
      for (const std::string& n : f.notes) progress->Note(n);
      result->notes.insert(result->notes.end(), f.notes.begin(), f.notes.end());
    }
    if (!config.pixels_path.empty()) {
      PixelsFile f = ReadPixels(config.pixels_path, config.angle_unit);
      obs.pixels = std::move(f.pixels);
      obs.pixel_covariates = std::move(f.covariates);
      obs.image_sizes = std::move(f.image_sizes);
      obs.pixels_source = config.pixels_path;
      for (const std::string& n : f.notes) progress->Note(n);
      result->notes.insert(result->notes.end(), f.notes.begin(), f.notes.end());
    }
    if (!config.shots_path.empty()) {
      result->photos = LoadPhotoSession(config.shots_path, config.targets_path, config.detect_jobs,
                                        &obs, progress, config.angle_unit);
      for (const std::string& w : result->photos.warnings) result->notes.push_back("warning: " + w);
    } else if (!config.targets_path.empty()) {
      // The boards of pixels.csv rows with empty X, Y, Z (SPEC 7), e.g. what
      // `rtscalib detect` wrote from the photos.
      const std::map<std::string, int> families = detect::DetectableCodeCounts();
      obs.targets = ReadTargets(config.targets_path, &families);
    }
    return obs;
  }
  if (!config.simulate) {
    throw std::invalid_argument(
        config.config_path + ": the config needs data.records, data.pixels or a simulate section");
  }
  progress->Step("simulating the instrument");
  SimulationOptions sim = *config.simulate;
  if (config.truth_from_paper) sim.truth = PaperTruth(PlanNumZooms(sim.plan));
  SimulatedData data = Simulate(sim);
  result->simulated = true;
  result->truth = sim.truth;
  progress->Note(std::to_string(data.obs.records.size()) + " records, " +
                 std::to_string(data.obs.pixels.size()) + " pixel observations");
  if (settings.render.enabled && (!sim.targets.boards.empty() || !sim.placements.empty())) {
    result->render = RenderSession(settings.render, sim.truth, sim.Scenes(), data.obs.pixels,
                                   work_dir + "/photos", progress);
    if (!result->render.note.empty()) result->notes.push_back(result->render.note);
    if (result->render.ran) {
      // The user's path: the simulator's exact pixels are dropped, the
      // written photos are detected as data.shots would be.
      data.obs.pixels.clear();
      data.obs.image_sizes.clear();
      result->photos = LoadPhotoSession(result->render.shots_path, result->render.targets_path,
                                        settings.render.jobs, &data.obs, progress);
      for (const std::string& w : result->photos.warnings) result->notes.push_back("warning: " + w);
      result->render.detect_seconds = result->photos.seconds;
      CompareWithExact(data.obs.pixels, &result->render, progress);
    }
  }
  return std::move(data.obs);
}

PipelineResult RunPipeline(const RunSettings& settings, const std::string& work_dir,
                           Progress* progress, const Alongside& alongside,
                           const Alongside& mapped) {
  PipelineResult result;
  result.obs = LoadObservations(settings, work_dir, &result, progress);
  const CalibrationOptions& options = settings.config.calibration;
  try {
    result.calibration = CalibrateModel(result.obs, options, progress);
  } catch (const std::invalid_argument& e) {
    // The library's rejections of the data and options name the data files
    // (Observations' sources); the config that chose them is named here.
    throw std::invalid_argument(settings.config.config_path + ": " + e.what());
  }
  // The plain diagnosis only reads the calibration: it runs on a second
  // thread while this one runs `alongside` (the run draws its figures),
  // computes the uncertainty maps and runs `mapped`, which need everything
  // but the diagnosis. The diagnosis prints its progress; `alongside` and
  // `mapped` must not.
  std::future<CalibrationDiagnosis> diagnosis;
  if (DiagnosisPending(options)) {
    diagnosis = std::async(std::launch::async, [&result, &options, progress] {
      return DiagnoseCalibration(result.obs, options, result.calibration, progress);
    });
  }
  // Projection uncertainty per zoom (libcalib/api/uncertainty_map.h), from
  // the fit's full covariance.
  const CalibratedInstrument inst(result.calibration.model);
  result.full_covariance = inst.HasFullParameterCovariance();
  result.uncertainty_options = settings.config.uncertainty_map;
  if (alongside) alongside(result);
  if (inst.HasParameterCovariance() && inst.NumZooms() > 0) {
    if (progress && !diagnosis.valid()) progress->Step("projection uncertainty maps");
    result.uncertainty_maps = ProjectionUncertaintyMaps(inst, result.uncertainty_options);
  }
  if (mapped) mapped(result);
  // (A future's destructor waits too: an exception from `alongside` leaves
  // only after the diagnosis thread has stopped reading `result`.)
  if (diagnosis.valid()) AddDiagnosis(diagnosis.get(), &result.calibration);
  result.notes.insert(result.notes.end(), result.calibration.notes.begin(),
                      result.calibration.notes.end());
  return result;
}

}  // namespace rtscalib::app

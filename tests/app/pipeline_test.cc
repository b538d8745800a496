// RunPipeline's two-part calibration (app/pipeline.h): the work the run does
// beside the diagnosis (`alongside`: the figures) sees the calibrated model
// with its residual table but not yet its diagnosis, which runs meanwhile
// on a second thread; the returned result then holds the diagnosis that
// Calibrate gives in one call. With diagnose.auto the ladder makes the model,
// so `alongside` comes after it. Klug's paper scene (configs/paper.yaml:
// records only, no photos), diagnosed.
#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>
#include <string>

#include "app/pipeline.h"
#include "libcalib/calibrate/calibrate.h"

namespace rtscalib::app {
namespace {

RunSettings PaperSettings(bool auto_add) {
  RunSettings s = LoadRunSettings(std::string(RTSCALIB_SOURCE_DIR) + "/configs/paper.yaml");
  s.config.calibration.diagnose.enabled = true;
  s.config.calibration.diagnose.auto_add = auto_add;
  return s;
}

// Nothing is rendered for this config: the work folder stays unused.
const std::string kWork = std::filesystem::temp_directory_path().string();

TEST(PipelineAlongside, SeesTheFittedModelWhileTheDiagnosisRuns) {
  const RunSettings s = PaperSettings(false);
  ASSERT_TRUE(DiagnosisPending(s.config.calibration));
  Progress quiet(true);
  int calls = 0;
  bool saw_diagnosis = true;
  size_t saw_residuals = 0;
  const PipelineResult r = RunPipeline(s, kWork, &quiet, [&](const PipelineResult& fitted) {
    ++calls;
    saw_diagnosis = fitted.calibration.diagnosis.has_value();
    saw_residuals = fitted.calibration.residuals.size();
  });
  EXPECT_EQ(calls, 1);
  EXPECT_FALSE(saw_diagnosis);
  EXPECT_EQ(saw_residuals, r.calibration.residuals.size());
  EXPECT_GT(saw_residuals, 0u);
  ASSERT_TRUE(r.calibration.diagnosis.has_value());
  ASSERT_FALSE(r.calibration.diagnosis->verdict.empty());

  // Calibrate in one call on the same observations: the same diagnosis.
  const CalibrationResult c = Calibrate(r.obs, s.config.calibration);
  ASSERT_TRUE(c.diagnosis.has_value());
  EXPECT_EQ(r.calibration.diagnosis->verdict, c.diagnosis->verdict);
  ASSERT_EQ(r.calibration.diagnosis->ranking.entries.size(), c.diagnosis->ranking.entries.size());
  for (size_t i = 0; i < c.diagnosis->ranking.entries.size(); ++i) {
    EXPECT_EQ(r.calibration.diagnosis->ranking.entries[i].name,
              c.diagnosis->ranking.entries[i].name);
    EXPECT_EQ(r.calibration.diagnosis->ranking.entries[i].delta_bic,
              c.diagnosis->ranking.entries[i].delta_bic);
  }
}

TEST(PipelineAlongside, ComesAfterTheStepwiseLadderThatMakesTheModel) {
  const RunSettings s = PaperSettings(true);
  ASSERT_FALSE(DiagnosisPending(s.config.calibration));
  Progress quiet(true);
  bool saw_diagnosis = false;
  const PipelineResult r = RunPipeline(s, kWork, &quiet, [&](const PipelineResult& fitted) {
    saw_diagnosis = fitted.calibration.diagnosis.has_value();
  });
  EXPECT_TRUE(saw_diagnosis);
  EXPECT_TRUE(r.calibration.diagnosis.has_value());
  EXPECT_FALSE(r.calibration.ladder.empty());
}

TEST(PipelineAlongside, ItsErrorLeavesRunPipelineAfterTheDiagnosisThread) {
  // The diagnosis thread reads the result that RunPipeline owns: the error
  // may only leave once that thread has stopped (a future's destructor
  // waits), which ASan would report otherwise.
  const RunSettings s = PaperSettings(false);
  Progress quiet(true);
  EXPECT_THROW(RunPipeline(s, kWork, &quiet,
                           [](const PipelineResult&) {
                             throw std::runtime_error("could not write figures/x.png");
                           }),
               std::runtime_error);
}

}  // namespace
}  // namespace rtscalib::app

#include "libcalib/diagnose/stepwise.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "tests/diagnose/diagnose_fixture.h"

namespace rtscalib {
namespace {

using testing_diagnose::FitBaseline;
using testing_diagnose::Fitted;
using testing_diagnose::PaperNoise;
using testing_diagnose::RecordsRms;
using testing_diagnose::SmallPlan;

// Two hidden effects: the ladder adds exactly those two, the error falls at
// every rung and ends within 10% of the noise floor.
TEST(Stepwise, AddsTheHiddenEffectsOneByOneAndStops) {
  SimulationOptions o;
  o.seed = 51;
  o.truth = PaperTruth(1);
  o.truth.effects.Add(Effect::kHzEccentricity);
  o.truth.EffectValue(Effect::kHzEccentricity) =
      FromReportUnits(Effect::kHzEccentricity, {4.0, 30.0});
  o.truth.effects.Add(Effect::kEdmScale);
  o.truth.EffectValue(Effect::kEdmScale) = FromReportUnits(Effect::kEdmScale, {25.0, 0});
  o.plan = SmallPlan();
  o.noise = PaperNoise();
  const Fitted f = FitBaseline(Simulate(o), o.truth, 52);
  const StepwiseResult s =
      ForwardStepwise(f.data.obs, f.model, f.fit, f.options, DiagnosisSettings{});
  ASSERT_EQ(s.ladder.size(), 3u) << s.stop_reason;
  std::vector<std::string> added = {s.ladder[1].added, s.ladder[2].added};
  std::sort(added.begin(), added.end());
  EXPECT_EQ(added, (std::vector<std::string>{"edm_scale", "hz_eccentricity"}));
  EXPECT_TRUE(s.ladder[0].added.empty());
  for (size_t i = 1; i < s.ladder.size(); ++i) {
    EXPECT_LT(s.ladder[i].rms.records_m, s.ladder[i - 1].rms.records_m) << "rung " << i;
    EXPECT_LT(s.ladder[i].bic, s.ladder[i - 1].bic) << "rung " << i;
  }
  EXPECT_EQ(s.stop_reason, "no catalogue effect is significant and worth adding");
  EXPECT_EQ(s.diagnosis.Next(), nullptr);
  EXPECT_LE(RecordsRms(s.model, f), 1.1 * RecordsRms(f.truth, f));
}

// The stepwise search never loops beyond its limit.
TEST(Stepwise, StopsAtMaxSteps) {
  SimulationOptions o;
  o.seed = 53;
  o.truth = PaperTruth(1);
  o.truth.effects.Add(Effect::kHzEccentricity);
  o.truth.EffectValue(Effect::kHzEccentricity) =
      FromReportUnits(Effect::kHzEccentricity, {4.0, 30.0});
  o.truth.effects.Add(Effect::kEdmScale);
  o.truth.EffectValue(Effect::kEdmScale) = FromReportUnits(Effect::kEdmScale, {25.0, 0});
  o.plan = SmallPlan();
  o.noise = PaperNoise();
  const Fitted f = FitBaseline(Simulate(o), o.truth, 54);
  const StepwiseResult s =
      ForwardStepwise(f.data.obs, f.model, f.fit, f.options, DiagnosisSettings{}, 1);
  EXPECT_EQ(s.ladder.size(), 2u);
  EXPECT_NE(s.stop_reason.find("stopped after 1"), std::string::npos) << s.stop_reason;
}

}  // namespace
}  // namespace rtscalib

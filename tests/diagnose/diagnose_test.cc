// The Diagnose() entry point end to end: simulated data with one hidden
// effect and one gross error, the baseline fitted without the effect, and
// every field of the Diagnosis checked against what the data were built with
// or against an independent computation. (ranking_test.cc covers the ranking
// of each catalogue effect; this file covers what Diagnose assembles.)
#include "libcalib/diagnose/diagnose.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>

#include "tests/diagnose/diagnose_fixture.h"

namespace rtscalib {
namespace {

using testing_diagnose::FitBaseline;
using testing_diagnose::Fitted;
using testing_diagnose::PaperNoise;
using testing_diagnose::SmallPlan;

// A dh baseline (PaperTruth) missing edm_scale (20 ppm: 0.6 mm at 30 m, 60
// times the 10 um noise) plus one EDM row 3 mm off (300 sigma).
struct Scenario {
  Fitted f;
  int outlier = -1;  // index of the spoiled record
  Diagnosis d;
};

const Scenario& TheScenario() {
  static const Scenario s = [] {
    Scenario out;
    SimulationOptions o;
    o.seed = 5;
    o.truth = PaperTruth(1);
    o.truth.effects.Add(Effect::kEdmScale);
    o.truth.EffectValue(Effect::kEdmScale) = FromReportUnits(Effect::kEdmScale, {20.0, 0});
    o.plan = SmallPlan();
    o.noise = PaperNoise();
    SimulatedData data = Simulate(o);
    // The gross error: a 2 m grid EDM row at a usable zenith.
    for (size_t i = 0; i < data.obs.records.size(); ++i) {
      const Record& r = data.obs.records[i];
      if (r.set == "grid" && r.tool == Tool::kEdm && r.d < 3 && std::abs(r.theta - 1.4) < 0.3) {
        out.outlier = static_cast<int>(i);
        break;
      }
    }
    data.obs.records[out.outlier].x += Eigen::Vector3d(3e-3, 0, 0);
    out.f = FitBaseline(std::move(data), o.truth, 11);
    out.d = Diagnose(out.f.data.obs, out.f.model, ContextOf(out.f.options, out.f.fit),
                     DiagnosisSettings());
    return out;
  }();
  return s;
}

TEST(Diagnose, DescribesTheModelItWasGiven) {
  const Scenario& s = TheScenario();
  ASSERT_GE(s.outlier, 0);
  EXPECT_EQ(s.d.kinematics, Kinematics::kDh);
  EXPECT_TRUE(s.d.effects.empty());
  EXPECT_EQ(s.d.model_description, "dh, effects: []");
  // The whitening sigmas are the fit's a-posteriori ones (ContextOf).
  const FitContext ctx = ContextOf(s.f.options, s.f.fit);
  for (int g = 0; g < 3; ++g) EXPECT_EQ(s.d.sigma[g], ctx.sigma[g]) << g;
  EXPECT_GT(s.d.seconds, 0.0);
}

TEST(Diagnose, NamesTheHiddenEffectFirstAndListsTheWholeCatalogue) {
  const Diagnosis& d = TheScenario().d;
  // SPEC 6: the ranking lists every catalogue effect not yet in the model
  // (the model has none), best first.
  std::set<Effect> listed;
  for (const RankedEffect& r : d.ranking.entries) listed.insert(r.effect);
  EXPECT_EQ(listed.size(), d.ranking.entries.size()) << "no effect twice";
  EXPECT_EQ(static_cast<int>(listed.size()), kNumEffects);
  ASSERT_FALSE(d.ranking.entries.empty());
  const RankedEffect& best = d.ranking.entries.front();
  EXPECT_EQ(best.effect, Effect::kEdmScale) << best.name;
  EXPECT_TRUE(best.significant);
  ASSERT_NE(d.Next(), nullptr);
  EXPECT_EQ(d.Next()->effect, Effect::kEdmScale);
  EXPECT_NE(best.config_line.find("model.effects"), std::string::npos) << best.config_line;
  EXPECT_NE(best.config_line.find("edm_scale"), std::string::npos) << best.config_line;
  EXPECT_LT(best.rms_after, best.rms_before);
  // Its estimate in report units: 20 ppm; 10% covers the noise and the
  // gross error's pull on a linear estimate.
  EXPECT_NEAR(best.value.value[0], 20.0, 2.0);
  // dh contains the four surveying terms (SPEC 4): listed, redundant, never next.
  for (const RankedEffect& r : d.ranking.entries) {
    if (Info(r.effect).redundant_in_dh) {
      EXPECT_TRUE(r.redundant) << r.name;
      EXPECT_FALSE(r.significant) << r.name;
    }
  }
  EXPECT_TRUE(d.equivalents.valid) << d.equivalents.message;
}

TEST(Diagnose, CountsRowsAndCriticalRegionsLikeTheFit) {
  const Scenario& s = TheScenario();
  const Diagnosis& d = s.d;
  const Observations& obs = s.f.data.obs;
  // Independent count of the rows in the critical regions (SPEC 1) and the
  // RMS of the point distances over the others (SPEC 6 rms_m).
  int critical = 0;
  double ss = 0;
  int used = 0;
  const std::vector<RecordResidual> res = RecordResiduals(s.f.model, obs.records);
  for (size_t i = 0; i < obs.records.size(); ++i) {
    if (s.f.options.critical_region.Contains(obs.records[i].theta)) {
      ++critical;
      continue;
    }
    ss += res[i].distance * res[i].distance;
    ++used;
  }
  ASSERT_GT(critical, 0) << "the plan's sweeps reach the zenith";
  EXPECT_EQ(d.excluded_critical, critical);
  EXPECT_EQ(d.current.edm_n + d.current.cam_n, used);
  EXPECT_EQ(d.current.pixels_n, 0);
  // Same sums in another order: relative round-off ~1e-12.
  EXPECT_NEAR(d.current.records_m, std::sqrt(ss / used), 1e-9 * d.current.records_m);
  // Three residual rows per record (ranking.h: n_g = 3 per record).
  EXPECT_EQ(d.num_rows, 3 * used);
  EXPECT_GT(d.num_parameters, 0);
  EXPECT_LT(d.num_parameters, d.num_rows);
  // One residual per observation, critical ones marked, with the diagnosis's fit options.
  const std::vector<ObservationResidual> residuals =
      ObservationResiduals(obs, s.f.model, s.f.options);
  ASSERT_EQ(residuals.size(), obs.records.size());
  int marked = 0;
  for (size_t i = 0; i < residuals.size(); ++i) {
    EXPECT_EQ(residuals[i].index, static_cast<int>(i));
    EXPECT_EQ(residuals[i].group,
              obs.records[i].tool == Tool::kEdm ? ObsGroup::kEdm : ObsGroup::kCam);
    marked += residuals[i].critical;
  }
  EXPECT_EQ(marked, critical);
}

TEST(Diagnose, FlagsTheGrossErrorAndSaysSoInTheVerdict) {
  const Scenario& s = TheScenario();
  const Diagnosis& d = s.d;
  EXPECT_GT(d.outliers.tested, 0);
  EXPECT_GE(d.outliers.flagged, 1);
  ASSERT_FALSE(d.outliers.worst.empty());
  EXPECT_EQ(d.outliers.worst.front().group, ObsGroup::kEdm);
  EXPECT_EQ(d.outliers.worst.front().index, s.outlier);
  EXPECT_EQ(d.outliers.worst.front().where, Where(s.f.data.obs, ObsGroup::kEdm, s.outlier));
  // The verdict, most important first: the EDM points fit worse than their
  // a-priori sigma (edm_scale's 0.6 mm at 30 m against 10 um), said first
  // with the factor; the fit; the next effect; ...; the outliers.
  ASSERT_GE(d.verdict.size(), 4u);
  EXPECT_EQ(d.verdict[0].rfind("The model (dh, effects: []) is incomplete", 0), 0u)
      << d.verdict[0];
  EXPECT_NE(d.verdict[0].find("EDM points"), std::string::npos) << d.verdict[0];
  EXPECT_TRUE(d.fit_quality.Exceeds());
  EXPECT_EQ(d.verdict[1].rfind("The model (dh, effects: []) fits", 0), 0u) << d.verdict[1];
  EXPECT_EQ(d.verdict[2].rfind("Add edm_scale next", 0), 0u) << d.verdict[2];
  const bool outlier_line = std::any_of(d.verdict.begin(), d.verdict.end(), [&](const auto& v) {
    return v.find("w-test") != std::string::npos &&
           v.find(d.outliers.worst.front().where) != std::string::npos;
  });
  EXPECT_TRUE(outlier_line);
}

TEST(Diagnose, SettingsAreChecked) {
  EXPECT_EQ(DiagnosisSettings().Check(), "");
  DiagnosisSettings s;
  s.significance = 0.0;
  EXPECT_NE(s.Check().find("significance"), std::string::npos) << s.Check();
  s = DiagnosisSettings();
  s.max_harmonic = 13;
  EXPECT_NE(s.Check().find("max_harmonic"), std::string::npos) << s.Check();
  s = DiagnosisSettings();
  s.refine_top = -1;
  EXPECT_NE(s.Check().find("refine_top"), std::string::npos) << s.Check();
  const Scenario& sc = TheScenario();
  s = DiagnosisSettings();
  s.significance = 1.5;
  EXPECT_THROW(Diagnose(sc.f.data.obs, sc.f.model, ContextOf(sc.f.options, sc.f.fit), s),
               std::invalid_argument);
}

}  // namespace
}  // namespace rtscalib

#include "libcalib/diagnose/equivalents.h"

#include <gtest/gtest.h>

#include <cmath>

#include "libcalib/extract/extract.h"
#include "libcalib/model/kinematics.h"
#include "libcalib/sim/simulator.h"
#include "tests/diagnose/diagnose_fixture.h"

namespace rtscalib {
namespace {

constexpr double kArcsec = M_PI / (180.0 * 3600.0);

int Index(Effect e) { return static_cast<int>(e); }

// A spherical truth with SPEC 4's four surveying terms, and the dh model the
// Klug Sec. 3 extraction makes of its noise-free records (exact: the dh form
// contains those terms in its links and tools).
struct DhOfSpherical {
  InstrumentModel truth, dh;
};

DhOfSpherical Make(double c, double i, double v0, double k0) {
  DhOfSpherical out;
  out.truth = testing_diagnose::SphericalTruth();
  for (const auto& [e, v] : {std::pair<Effect, double>{Effect::kCollimation, c},
                             {Effect::kTiltingAxis, i},
                             {Effect::kVerticalIndex, v0},
                             {Effect::kEdmOffset, k0}}) {
    out.truth.effects.Add(e);
    out.truth.EffectValue(e)[0] = v;
  }
  SimulationOptions o;
  o.truth = out.truth;
  o.plan.edm_distances = {1.0, 2.0, 10.0};
  const SimulatedData data = Simulate(o);
  out.dh = ExtractDhModel(data.obs.records, out.truth.cams).model;
  return out;
}

TEST(EquivalentSurveyingTerms, ReadsTheFourTermsOffADhModel) {
  const double c = 15 * kArcsec, i = -12 * kArcsec, v0 = 20 * kArcsec, k0 = 0.8e-3;
  const DhOfSpherical m = Make(c, i, v0, k0);
  ASSERT_EQ(m.dh.kinematics, Kinematics::kDh);
  // The extracted dh model predicts the truth (else the test below would
  // test the extraction, not the equivalents): noise-free extraction is
  // exact to ~1e-9 m; 1e-7 m at 20 m leaves room.
  for (double t : {0.5, 1.2, 2.0}) {
    for (double p : {0.3, 2.0, 4.5}) {
      ASSERT_LT((PredictEdm(m.dh, p, t, 20.0) - PredictEdm(m.truth, p, t, 20.0)).norm(), 1e-7);
    }
  }
  const EquivalentTerms e = EquivalentSurveyingTerms(m.dh, FitOptions());
  ASSERT_TRUE(e.valid) << e.message;
  // Noise-free fit of a form that contains the dh model exactly: the spherical
  // model reproduces it to the extraction's accuracy (1e-7 m, above), and the
  // terms come out within 1e-7 m / 2 m = 5e-8 rad (0.01") and 1e-6 m.
  EXPECT_LT(e.fit_rms_m, 1e-7);
  EXPECT_NEAR(e.value[Index(Effect::kCollimation)][0], c, 0.01 * kArcsec);
  EXPECT_NEAR(e.value[Index(Effect::kTiltingAxis)][0], i, 0.01 * kArcsec);
  EXPECT_NEAR(e.value[Index(Effect::kVerticalIndex)][0], v0, 0.01 * kArcsec);
  EXPECT_NEAR(e.value[Index(Effect::kEdmOffset)][0], k0, 1e-6);
  // Only the four redundant terms are filled.
  for (int k = 0; k < kNumKinematicEffects; ++k) {
    const Effect eff = static_cast<Effect>(k);
    if (eff == Effect::kCollimation || eff == Effect::kTiltingAxis ||
        eff == Effect::kVerticalIndex || eff == Effect::kEdmOffset)
      continue;
    EXPECT_EQ(e.value[k][0], 0.0) << Info(eff).name;
    EXPECT_EQ(e.value[k][1], 0.0) << Info(eff).name;
  }
}

TEST(EquivalentSurveyingTerms, IdealDhModelHasNone) {
  const InstrumentModel dh =
      IdealModel(Kinematics::kDh, 1, testing_diagnose::SphericalTruth().cams[0]);
  const EquivalentTerms e = EquivalentSurveyingTerms(dh, FitOptions());
  ASSERT_TRUE(e.valid) << e.message;
  // The ideal instrument is exactly spherical: round-off of the fit.
  EXPECT_LT(e.fit_rms_m, 1e-9);
  for (Effect eff : {Effect::kCollimation, Effect::kTiltingAxis, Effect::kVerticalIndex}) {
    EXPECT_NEAR(e.value[Index(eff)][0], 0.0, 1e-3 * kArcsec) << Info(eff).name;
  }
  EXPECT_NEAR(e.value[Index(Effect::kEdmOffset)][0], 0.0, 1e-9);
}

TEST(EquivalentSurveyingTerms, OnlyForDhModels) {
  const EquivalentTerms e =
      EquivalentSurveyingTerms(testing_diagnose::SphericalTruth(), FitOptions());
  EXPECT_FALSE(e.valid);
  EXPECT_FALSE(e.message.empty());
  EXPECT_NE(e.message.find("dh"), std::string::npos) << e.message;
}

}  // namespace
}  // namespace rtscalib

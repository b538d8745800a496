#include "libcalib/export/surveyor_export.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "libcalib/diagnose/equivalents.h"
#include "tests/export/export_fixture.h"

namespace rtscalib {
namespace {

const SurveyorTerm& Find(const SurveyorConstants& c, Effect e, const std::string& symbol) {
  for (const SurveyorTerm& t : c.terms) {
    if (t.effect == e && t.symbol == symbol) return t;
  }
  ADD_FAILURE() << Info(e).name << " " << symbol << " missing";
  return c.terms.front();
}

// spherical: the effect parameters and the sigmas of their stored covariance,
// in report units (ToReportUnits is the conversion model.yaml uses too).
TEST(SurveyorExport, SphericalReadsEffectParametersAndTheirSigmas) {
  std::mt19937 rng(31);
  InstrumentModel m =
      RandomModel(Kinematics::kSpherical, rng,
                  {Effect::kCollimation, Effect::kTiltingAxis, Effect::kVerticalIndex,
                   Effect::kHzEccentricity, Effect::kEdmOffset, Effect::kEdmScale});
  m.sigmas.valid = true;
  for (Effect e : m.effects.List()) {
    m.sigmas.effect_cov[static_cast<int>(e)] = {4e-12, 1e-12, 1e-12, 9e-12};
  }
  m.sigmas.effect_cov[static_cast<int>(Effect::kEdmScale)] = {0, 0, 0, 0};  // held in the fit
  const SurveyorConstants c = ComputeSurveyorConstants(m);
  for (Effect e : {Effect::kCollimation, Effect::kTiltingAxis, Effect::kVerticalIndex,
                   Effect::kHzEccentricity, Effect::kEdmOffset}) {
    const EffectReportValue r =
        ToReportUnits(e, m.EffectValue(e), m.sigmas.effect_cov[static_cast<int>(e)]);
    for (int i = 0; i < Info(e).num_params; ++i) {
      const SurveyorTerm& t = Find(c, e, Info(e).param_names[i]);
      ASSERT_TRUE(t.available);
      EXPECT_EQ(t.value, r.value[i]);
      ASSERT_TRUE(t.sigma.has_value()) << Info(e).name;
      EXPECT_EQ(*t.sigma, r.sigma[i]);
      EXPECT_GT(*t.sigma, 0.0);
    }
  }
  // A zero sigma (held parameter) is not printed as 0.
  const SurveyorTerm& m_term = Find(c, Effect::kEdmScale, "m");
  EXPECT_TRUE(m_term.available);
  EXPECT_FALSE(m_term.sigma.has_value());
  EXPECT_NE(m_term.sigma_note.find("sigma not available"), std::string::npos);
  // Effects the model lacks are reported as such, without a value.
  const SurveyorTerm& w = Find(c, Effect::kAxisWobble, "w");
  EXPECT_FALSE(w.available);
  EXPECT_FALSE(w.sigma.has_value());

  // c in mgon: 1 mgon = 3.24 arcsec.
  EXPECT_DOUBLE_EQ(ArcsecToMgon(3.24), 1.0);
  const nlohmann::json j = nlohmann::json::parse(SurveyorJson(c));
  EXPECT_EQ(j["kinematics"], "spherical");
  bool saw_c = false;
  for (const auto& t : j["terms"]) {
    if (t["term"] == "c") {
      saw_c = true;
      EXPECT_DOUBLE_EQ(t["value_mgon"].get<double>(),
                       Find(c, Effect::kCollimation, "c").value / 3.24);
    }
    if (t["effect"] == "edm_scale") {
      EXPECT_TRUE(t["sigma"].is_null());
    }
    if (t["effect"] == "axis_wobble") {
      EXPECT_TRUE(t["value"].is_null());
    }
  }
  EXPECT_TRUE(saw_c);
  EXPECT_NE(SurveyorText(c).find("collimation"), std::string::npos);
}

TEST(SurveyorExport, WithoutUncertaintiesEverySigmaIsNotAvailable) {
  std::mt19937 rng(32);
  const InstrumentModel m =
      RandomModel(Kinematics::kSpherical, rng, {Effect::kCollimation, Effect::kVerticalIndex});
  ASSERT_FALSE(m.sigmas.valid);
  const SurveyorConstants c = ComputeSurveyorConstants(m);
  for (const SurveyorTerm& t : c.terms) {
    EXPECT_FALSE(t.sigma.has_value()) << Info(t.effect).name;
    EXPECT_NE(t.sigma_note.find("sigma not available"), std::string::npos);
  }
  const std::string text = SurveyorText(c);
  EXPECT_NE(text.find("sigma not available"), std::string::npos);
}

// dh: c, i, v0, k0 are the equivalents of EquivalentSurveyingTerms.
// Their sigmas are propagated from the stored link sigmas. Two of the
// derivatives are known exactly: the zenith index is link 2's gamma offset
// (Z2 = Tz(d2) Rz(theta* + gamma2), so d v0 / d gamma2 = +-1) and the
// tilting-axis error is link 1's alpha off pi/2 (d i / d alpha1 = +-1, to
// first order). With only those two sigmas stored, sigma(v0) = sigma(gamma2)
// and sigma(i) = sigma(alpha1); tolerance 2 %: the second-order terms of a
// +-1e-5 rad step and the equivalents fit's own convergence (~1e-10 rad).
TEST(SurveyorExport, DhEquivalentsAndPropagatedSigmas) {
  InstrumentModel m = IdealModel(Kinematics::kDh, 1, CameraTool{});
  m.links[0].p[kDhAlpha] += 20e-6;
  m.links[1].p[kDhGamma] += 30e-6;

  const SurveyorConstants without = ComputeSurveyorConstants(m);
  const EquivalentTerms eq = EquivalentSurveyingTerms(m, FitOptions());
  ASSERT_TRUE(eq.valid) << eq.message;
  for (Effect e :
       {Effect::kCollimation, Effect::kTiltingAxis, Effect::kVerticalIndex, Effect::kEdmOffset}) {
    const SurveyorTerm& t = Find(without, e, Info(e).param_names[0]);
    ASSERT_TRUE(t.available);
    EXPECT_EQ(t.source, "dh equivalent");
    EXPECT_EQ(t.value, ToReportUnits(e, eq.value[static_cast<int>(e)], {0, 0, 0, 0}).value[0]);
    EXPECT_FALSE(t.sigma.has_value());
  }
  // The offsets show up whole in v0 and i (up to sign), and c stays 0.
  // Tolerance 0.01 arcsec: the equivalents fit is exact to ~1e-10 rad.
  constexpr double kArcsecPerRad = 180.0 * 3600.0 / M_PI;
  EXPECT_NEAR(std::fabs(Find(without, Effect::kVerticalIndex, "v0").value), 30e-6 * kArcsecPerRad,
              0.01);
  EXPECT_NEAR(std::fabs(Find(without, Effect::kTiltingAxis, "i").value), 20e-6 * kArcsecPerRad,
              0.01);
  EXPECT_NEAR(Find(without, Effect::kCollimation, "c").value, 0.0, 0.01);

  m.sigmas.valid = true;
  const double s_gamma = 10e-6, s_alpha = 5e-6;
  m.sigmas.links[1][kDhGamma] = s_gamma;
  m.sigmas.links[0][kDhAlpha] = s_alpha;
  const SurveyorConstants with = ComputeSurveyorConstants(m);
  const SurveyorTerm& v0 = Find(with, Effect::kVerticalIndex, "v0");
  const SurveyorTerm& i = Find(with, Effect::kTiltingAxis, "i");
  ASSERT_TRUE(v0.sigma.has_value()) << v0.sigma_note;
  ASSERT_TRUE(i.sigma.has_value()) << i.sigma_note;
  EXPECT_NEAR(*v0.sigma, s_gamma * kArcsecPerRad, 0.02 * s_gamma * kArcsecPerRad);
  EXPECT_NEAR(*i.sigma, s_alpha * kArcsecPerRad, 0.02 * s_alpha * kArcsecPerRad);
  EXPECT_NE(SurveyorText(with).find("correlations"), std::string::npos);
}

}  // namespace
}  // namespace rtscalib

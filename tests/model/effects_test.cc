#include "libcalib/model/effects.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace rtscalib {
namespace {

// The tables derived from RTSCALIB_EFFECT_LIST hold the values the catalogue
// had when each was kept by hand (SPEC 4, docs/effects.md).
TEST(EffectCatalogue, DerivedCountsAndOrder) {
  EXPECT_EQ(kNumEffects, 18);
  EXPECT_EQ(kNumKinematicEffects, 11);
  EXPECT_EQ(kNumDistortionGroups, 5);
  ASSERT_EQ(static_cast<int>(EffectCatalogue().size()), kNumEffects);
  for (int i = 0; i < kNumEffects; ++i) {
    const Effect e = static_cast<Effect>(i);
    EXPECT_EQ(Info(e).effect, e);
    EXPECT_EQ(EffectFromName(Info(e).name), e);
    EXPECT_EQ(IsKinematic(e), i < kNumKinematicEffects);
  }
  EXPECT_EQ(std::string(Info(Effect::kEdmCyclic).name), "edm_cyclic");
  // The per-zoom camera effects: the distortion groups, then focus (SPEC 4.1).
  EXPECT_TRUE(IsCameraEffect(Effect::kFocus));
  EXPECT_FALSE(IsDistortion(Effect::kFocus));
  EXPECT_TRUE(IsDistortion(Effect::kSensorTilt));
  EXPECT_EQ(std::string(Info(Effect::kFocus).name), "focus");
  EXPECT_TRUE(Info(Effect::kFocus).distortion_indices.empty());
  // The per-board effect, last: neither kinematic nor a camera's.
  EXPECT_EQ(std::string(Info(Effect::kBoardWarp).name), "board_warp");
  EXPECT_TRUE(IsBoardEffect(Effect::kBoardWarp));
  EXPECT_FALSE(IsCameraEffect(Effect::kBoardWarp));
  EXPECT_FALSE(IsKinematic(Effect::kBoardWarp));
  EXPECT_FALSE(IsBoardEffect(Effect::kFocus));
  EXPECT_EQ(ReportScale(Effect::kBoardWarp), 1e3);  // mm per metre
  EXPECT_EQ(Info(Effect::kBoardWarp).needs, static_cast<unsigned>(kNeedManyPoses));
  EXPECT_FALSE(EffectFromName("no_such_effect").has_value());
}

TEST(EffectCatalogue, DistortionGroupsOwnTheirCoefficients) {
  EXPECT_EQ(Info(Effect::kRadialDistortion).distortion_indices, (std::vector<int>{0, 1, 4}));
  EXPECT_EQ(Info(Effect::kTangentialDistortion).distortion_indices, (std::vector<int>{2, 3}));
  EXPECT_EQ(Info(Effect::kRationalDistortion).distortion_indices, (std::vector<int>{5, 6, 7}));
  EXPECT_EQ(Info(Effect::kThinPrism).distortion_indices, (std::vector<int>{8, 9, 10, 11}));
  EXPECT_EQ(Info(Effect::kSensorTilt).distortion_indices, (std::vector<int>{12, 13}));
  EXPECT_TRUE(Info(Effect::kHzScale).distortion_indices.empty());
  const std::vector<std::string> names(std::begin(kDistortionCoefficientNames),
                                       std::end(kDistortionCoefficientNames));
  EXPECT_EQ(names, (std::vector<std::string>{"k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6", "s1",
                                             "s2", "s3", "s4", "taux", "tauy"}));
  EXPECT_EQ(DistortionGroupOf(kTauY), Effect::kSensorTilt);
}

// Report scales follow from the report units: arcsec per radian (exact by
// definition, compared to 1e-12 relative), 1e6 ppm, 1e3 mm per metre.
TEST(EffectCatalogue, ReportScaleFromUnits) {
  const double arcsec = 180.0 * 3600.0 / M_PI;
  EXPECT_NEAR(ReportScale(Effect::kCollimation), arcsec, 1e-12 * arcsec);
  EXPECT_NEAR(ReportScale(Effect::kAxisWobble), arcsec, 1e-12 * arcsec);
  EXPECT_EQ(ReportScale(Effect::kHzScale), 1e6);
  EXPECT_EQ(ReportScale(Effect::kVScale), 1e6);
  EXPECT_EQ(ReportScale(Effect::kEdmScale), 1e6);
  EXPECT_EQ(ReportScale(Effect::kEdmOffset), 1e3);
  EXPECT_EQ(ReportScale(Effect::kEdmCyclic), 1e3);
  // A polar pair in report units round-trips through SI (1e-12 relative:
  // one hypot/atan2 and one cos/sin in double precision).
  const std::array<double, 2> report = {2.5, 30.0};
  const std::array<double, 2> si = FromReportUnits(Effect::kEdmCyclic, report);
  const EffectReportValue back = ToReportUnits(Effect::kEdmCyclic, si, {0, 0, 0, 0});
  EXPECT_NEAR(back.value[0], report[0], 1e-12 * report[0]);
  EXPECT_NEAR(back.value[1], report[1], 1e-12 * report[1]);
}

TEST(EffectCatalogue, EveryEffectSaysWhatDataDetermineIt) {
  for (const EffectInfo& info : EffectCatalogue()) {
    EXPECT_NE(info.needs, kNeedNone) << info.name;
  }
  EXPECT_EQ(Info(Effect::kAxisWobble).needs, kNeedFullTurn | kNeedSteepSights);
  EXPECT_EQ(Info(Effect::kThinPrism).needs, kNeedImageCorners);
}

}  // namespace
}  // namespace rtscalib

#include "libcalib/diagnose/coverage.h"

#include <gtest/gtest.h>

#include "libcalib/sim/simulator.h"

namespace rtscalib {
namespace {

bool Mentions(const std::vector<std::string>& needs, const std::string& what) {
  for (const std::string& n : needs) {
    if (n.find(what) != std::string::npos) return true;
  }
  return false;
}

// The paper's plan (one face, sweeps only, EDM at 1 and 2 m, camera rows at
// the principal point): what it lacks for each effect.
TEST(Coverage, PaperSweepsLackTheOtherFaceDistancesAndCorners) {
  AcquisitionPlan plan;
  Observations obs;
  const InstrumentModel truth = PaperTruth(1);
  obs.records = PlanRecords(plan, truth);
  const FitOptions fit;
  const Coverage c = MeasureCoverage(obs, truth, fit);
  EXPECT_EQ(c.faces, std::set<int>{1});
  EXPECT_NEAR(c.min_edm_m, 1.0, 1e-12);
  EXPECT_NEAR(c.max_edm_m, 2.0, 1e-12);
  EXPECT_TRUE(Mentions(WhatWouldHelp(Effect::kCollimation, c, truth), "the other face"));
  EXPECT_TRUE(Mentions(WhatWouldHelp(Effect::kEdmScale, c, truth), "longer EDM distances"));
  EXPECT_TRUE(Mentions(WhatWouldHelp(Effect::kEdmCyclic, c, truth), "finer than U/4"));
  EXPECT_TRUE(Mentions(WhatWouldHelp(Effect::kRadialDistortion, c, truth), "image corners"));
  // Both sweeps cover a full turn in phi and zenith angles beyond 60 deg.
  EXPECT_TRUE(WhatWouldHelp(Effect::kHzEccentricity, c, truth).empty());
  EXPECT_FALSE(Mentions(WhatWouldHelp(Effect::kTiltingAxis, c, truth), "steep"));
}

TEST(Coverage, AGridInBothFacesLacksNothingForTheAngles) {
  AcquisitionPlan plan;
  plan.grid_phi_steps = 8;
  plan.grid_theta_steps = 5;
  plan.faces = {1, 2};
  plan.grid_edm_distances = {1.0, 1.3, 1.7, 2.1, 2.6, 5.0, 12.0};
  Observations obs;
  const InstrumentModel truth = PaperTruth(1);
  obs.records = PlanRecords(plan, truth);
  const Coverage c = MeasureCoverage(obs, truth, FitOptions{});
  for (Effect e :
       {Effect::kCollimation, Effect::kTiltingAxis, Effect::kVerticalIndex, Effect::kHzEccentricity,
        Effect::kVEccentricity, Effect::kAxisWobble, Effect::kEdmScale, Effect::kEdmCyclic}) {
    EXPECT_TRUE(WhatWouldHelp(e, c, truth).empty())
        << Info(e).name << ": " << WhatWouldHelp(e, c, truth)[0];
  }
}

}  // namespace
}  // namespace rtscalib

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

// Where the fitted image points fell: 8 x 8 cells over the image (pixel
// centres at integers, SPEC 2), the corner ninths, and the warning when a
// corner of the image holds no points.
TEST(Coverage, ImageGridCountsTheFittedPointsPerCell) {
  const InstrumentModel m = IdealModel(Kinematics::kSpherical, 1, CameraTool{});  // 1280 x 960
  const FitOptions fit;
  Observations obs;
  auto add = [&](double u, double v, double theta) {
    PixelObservation p;
    p.theta = theta;
    p.uv = Eigen::Vector2d(u, v);
    obs.pixels.push_back(p);
  };
  // Cells are 160 x 120 px: (-0.5 + 160 i, -0.5 + 120 j) starts cell (i, j).
  add(10, 10, M_PI / 2);        // cell (0, 0), top-left ninth
  add(1270, 10, M_PI / 2);      // cell (7, 0), top-right ninth
  add(10, 950, M_PI / 2);       // cell (0, 7), bottom-left ninth
  add(1270, 950, M_PI / 2);     // cell (7, 7), bottom-right ninth
  add(159.4, 119.4, M_PI / 2);  // still cell (0, 0): its last pixel centre
  add(640, 480, M_PI / 2);      // cell (4, 4)
  add(640, 480, 0.05);          // critical region: not fitted, not counted
  const Coverage c = MeasureCoverage(obs, m, fit);
  ASSERT_EQ(c.images.size(), 1u);
  const ImageCoverage& g = c.images[0];
  EXPECT_EQ(g.points, 6);
  ASSERT_EQ(g.counts.size(), 64u);
  EXPECT_EQ(g.counts[0], 2);
  EXPECT_EQ(g.counts[7], 1);
  EXPECT_EQ(g.counts[7 * 8], 1);
  EXPECT_EQ(g.counts[63], 1);
  EXPECT_EQ(g.counts[4 * 8 + 4], 1);
  EXPECT_DOUBLE_EQ(g.covered_fraction, 5.0 / 64);
  EXPECT_TRUE(g.corners_covered);
  for (const std::string& w : CoverageWarnings(c, m)) {
    EXPECT_EQ(w.find("extrapolated"), std::string::npos) << w;
  }
  // Without the bottom-right corner: extrapolated there.
  obs.pixels.erase(obs.pixels.begin() + 3);
  const Coverage c2 = MeasureCoverage(obs, m, fit);
  EXPECT_FALSE(c2.images[0].corners_covered);
  EXPECT_TRUE(Mentions(CoverageWarnings(c2, m), "zoom 0: distortion extrapolated"));
}

}  // namespace
}  // namespace rtscalib

// The planner's design on the example sessions, without calibrating: the
// greedy choice only adds information, a goal met stops it, a constant
// these targets cannot determine is reported as such, the order groups the
// faces and placements. (plan_simulation_test.cc calibrates planned shots.)
#include "libcalib/plan/planner.h"

#include <gtest/gtest.h>

#include <set>

#include "libcalib/plan/shot_order.h"
#include "tests/plan/plan_test_util.h"

namespace rtscalib::testing_plan {
namespace {

// configs/plan.yaml's session made small for the quick tier: its sweeps'
// records only (not the grid), zoom 0, 6 candidate pointings per board.
LoadedSession SmallSession(PlanOptions* o) {
  LoadedSession s = LoadSession("plan.yaml");
  std::vector<Record> sweeps;
  for (const Record& r : s.session.fixed.records) {
    if (r.set != "grid") sweeps.push_back(r);
  }
  s.session.fixed.records = sweeps;
  *o = s.settings.options;
  o->zooms = {0};
  o->candidates_per_board = 6;
  o->goal.sigmas.clear();
  return s;
}

const PredictedConstant* Find(const PlanResult& r, const std::string& name) {
  for (const PredictedConstant& c : r.constants) {
    if (c.name == name) return &c;
  }
  return nullptr;
}

TEST(Planner, GreedyStepsOnlyAddInformationAndReduceTheCriterion) {
  PlanOptions o;
  LoadedSession s = SmallSession(&o);
  o.goal.projection_px = 0.02;  // more than the records give: many steps
  o.exchange = false;           // the greedy sequence as chosen
  const PlanResult r = PlanShots(s.session, o);
  ASSERT_GE(r.log_det.size(), 3u);
  ASSERT_EQ(r.log_det.size(), r.criterion.size());
  // Each step adds a positive semi-definite J_c^T J_c of full rank in some
  // direction: log det strictly grows, Phi (all goals' A-criterion) never
  // grows. Round-off of a log det of ~60 terms: 1e-9 relative.
  for (size_t k = 1; k < r.log_det.size(); ++k) {
    EXPECT_GT(r.log_det[k], r.log_det[k - 1]) << "step " << k;
    EXPECT_LE(r.criterion[k], r.criterion[k - 1] * (1 + 1e-9)) << "step " << k;
  }
  EXPECT_EQ(r.shots.size(), r.log_det.size());
}

TEST(Planner, StopsWhenTheGoalIsMetAndNotBefore) {
  PlanOptions o;
  LoadedSession s = SmallSession(&o);
  o.goal.projection_px = 0.03;
  const PlanResult r = PlanShots(s.session, o);
  ASSERT_TRUE(r.goal_met);
  EXPECT_TRUE(r.limits.empty());
  for (const PredictedProjection& p : r.projection) EXPECT_LE(p.worst_px, 0.03) << p.zoom;
  // Without any planned shot (the records alone) the goal is not met: the
  // plan is needed, and with the exchange pass no shot of it is redundant.
  PlanOptions none = o;
  none.max_shots = 0;
  const PlanResult records_only = PlanShots(s.session, none);
  EXPECT_FALSE(records_only.goal_met);
  EXPECT_TRUE(records_only.shots.empty());
  ASSERT_FALSE(r.shots.empty());
  for (const PlanShot& shot : r.shots) {
    EXPECT_FALSE(shot.determines.empty());
  }
}

TEST(Planner, BudgetLimitsAnUnreachableGoalAndSaysSo) {
  PlanOptions o;
  LoadedSession s = SmallSession(&o);
  o.goal.projection_px = 0.02;
  o.max_shots = 2;
  const PlanResult r = PlanShots(s.session, o);
  EXPECT_FALSE(r.goal_met);
  EXPECT_EQ(r.shots.size(), 2u);
  ASSERT_FALSE(r.limits.empty());
  EXPECT_NE(r.limits[0].find("budget"), std::string::npos) << r.limits[0];
}

TEST(Planner, ReportsAConstantTheTargetsCannotDetermine) {
  // A photo session without an EDM row cannot determine an EDM scale: its
  // column is zero in every candidate's information.
  LoadedSession s = LoadSession("plan.yaml");
  s.session.fixed = Observations();
  s.session.calibration.model.effects.Add(Effect::kEdmScale);
  PlanOptions o = s.settings.options;
  o.zooms = {0};
  o.candidates_per_board = 6;
  o.goal.sigmas = {{"edm_scale.m", 1.0}, {"hz_eccentricity.e", 20.0}};
  o.goal.projection_px = 0;
  const PlanResult r = PlanShots(s.session, o);
  const PredictedConstant* m = Find(r, "edm_scale.m");
  ASSERT_NE(m, nullptr);
  EXPECT_FALSE(m->determined);
  EXPECT_TRUE(std::isnan(m->sigma));
  EXPECT_FALSE(r.goal_met);
  bool named = false;
  for (const std::string& l : r.limits) {
    named = named || (l.find("edm_scale.m") != std::string::npos &&
                      l.find("cannot determine") != std::string::npos);
  }
  EXPECT_TRUE(named);
  // The other goal is still planned for and met.
  const PredictedConstant* e = Find(r, "hz_eccentricity.e");
  ASSERT_NE(e, nullptr);
  EXPECT_TRUE(e->determined);
  EXPECT_LE(e->sigma, 20.0);
}

TEST(Planner, UnknownGoalNameIsAnErrorListingTheConstants) {
  PlanOptions o;
  LoadedSession s = SmallSession(&o);
  o.goal.sigmas = {{"hz_excentricity.e", 1.0}};
  try {
    PlanShots(s.session, o);
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("plan.goal.sigmas.hz_excentricity.e"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("hz_eccentricity.e"), std::string::npos);
  }
}

TEST(ShotOrder, OneWalkPerPlacementFacesGroupedNearestNeighbourTour) {
  PlacedScenes scenes;
  for (const char* p : {"a", "b"}) scenes[p] = TargetScene();
  std::vector<PlanShot> shots;
  const double phis[] = {0.1, 3.0, 0.2, 2.9, 0.15, 3.1};
  for (int k = 0; k < 12; ++k) {
    PlanShot s;
    s.pointing.placement = k % 2 ? "a" : "b";
    s.pointing.face = (k / 2) % 2 ? 2 : 1;
    s.pointing.zoom = 0;
    s.pointing.phi = phis[k % 6];
    s.pointing.theta = s.pointing.face == 1 ? 1.5 : 4.7;
    shots.push_back(s);
  }
  const double travel = OrderShots(scenes, &shots);
  ASSERT_EQ(shots.size(), 12u);
  int placement_changes = 0, face_changes = 0;
  for (size_t k = 1; k < shots.size(); ++k) {
    placement_changes += shots[k].pointing.placement != shots[k - 1].pointing.placement;
    face_changes += shots[k].pointing.face != shots[k - 1].pointing.face;
  }
  EXPECT_EQ(placement_changes, 1);
  EXPECT_LE(face_changes, 3);  // 1 -> 2 in each placement, 2 -> 1 between them
  double sum = 0;
  PlannedShot from;
  from.theta = M_PI / 2;
  for (const PlanShot& s : shots) {
    sum += MotorTravel(from, s.pointing);
    from = s.pointing;
  }
  EXPECT_DOUBLE_EQ(travel, sum);
}

}  // namespace
}  // namespace rtscalib::testing_plan

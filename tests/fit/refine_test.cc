#include "libcalib/fit/refine.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include "libcalib/eval/error_measures.h"
#include "libcalib/model/kinematics.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib {
namespace {

// Starts from PerturbedStart (libcalib/sim): this test is about the
// refinement alone. End-to-end tests start from the extraction.
InstrumentModel Perturbed(const InstrumentModel& truth, std::uint64_t seed) {
  return PerturbedStart(truth, seed);
}

AcquisitionPlan PaperPlanWithGrid() {
  AcquisitionPlan plan;
  plan.grid_phi_steps = 8;
  plan.grid_theta_steps = 5;
  plan.faces = {1, 2};
  return plan;
}

// Held-out rows: other angles, distances and pixels than the training plan.
std::vector<Record> HeldOut(const InstrumentModel& truth) {
  AcquisitionPlan plan;
  plan.sweeps = false;
  plan.grid_phi_steps = 7;
  plan.grid_theta_steps = 4;
  plan.grid_edm_distances = {3.3, 47.0};
  plan.grid_cam_ray_lengths = {2.2};
  plan.grid_pixels_per_axis = 4;
  plan.faces = {1, 2};
  return PlanRecords(plan, truth);
}

double MaxHeldOutError(const InstrumentModel& model, const InstrumentModel& truth) {
  double worst = 0;
  for (const RecordResidual& r : RecordResiduals(model, HeldOut(truth))) {
    EXPECT_TRUE(r.valid);
    worst = std::max(worst, r.distance);
  }
  return worst;
}

TEST(Refine, NoiseFreeDhRecoversPredictionsExactly) {
  SimulationOptions o;
  o.truth = PaperTruth(1);
  o.plan = PaperPlanWithGrid();
  const SimulatedData data = Simulate(o);
  InstrumentModel model = Perturbed(o.truth, 3);
  FitOptions fo;
  fo.fit_intrinsics = true;
  const FitSummary s = Refine(data.obs, fo, &model);
  EXPECT_TRUE(s.converged) << s.message;
  // 1e-9 m (the goal): residuals of exact data are round-off, ~1e-15 m
  // per unit of distance; the held-out distances reach 47 m.
  EXPECT_LT(MaxHeldOutError(model, o.truth), 1e-9);
}

// Every row in the critical region: the refusal names the files, their row
// counts and the window that took the rows out.
TEST(Refine, NothingToFitNamesTheFilesAndTheCriticalRegion) {
  SimulationOptions o;
  o.truth = PaperTruth(1);
  o.plan = PaperPlanWithGrid();
  Observations obs = Simulate(o).obs;
  obs.records_source = "r.csv";
  obs.pixels_source = "p.csv";
  FitOptions fo;
  fo.critical_region.min_zenith_rad = 170 * M_PI / 180;
  fo.critical_region.max_zenith_rad = 175 * M_PI / 180;
  InstrumentModel model = o.truth;
  const std::string n = std::to_string(obs.records.size());
  try {
    Refine(obs, fo, &model);
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "nothing to fit: r.csv gave " + n + " rows and p.csv 0 rows; " + n +
                  " of them lie in the critical region (zenith angle outside "
                  "fit.critical_region's 170 to 175 deg)");
  }
  obs.records.clear();
  try {
    Refine(obs, fo, &model);
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "nothing to fit: r.csv gave 0 rows and p.csv 0 rows (give data.records, "
              "data.pixels or data.shots rows)");
  }
}

TEST(Refine, NoiseFreeSphericalRecoversSphericalTruth) {
  SimulationOptions o;
  o.truth = IdealModel(Kinematics::kSpherical, 1, PaperTruth(1).cams[0]);
  o.truth.cams[0].flange_from_cam =
      PoseBlock::FromRigid(Rigid3::FromEuler({2e-3, -1e-3, 4e-3}, {1e-4, -2e-4, 3e-4}));
  o.truth.edm.t = {2e-4, -1e-4, 0.0};
  o.truth.base = PoseBlock::FromRigid(Rigid3::FromEuler({1e-4, -2e-4, 0.3}, {1.0, 2.0, 0.5}));
  o.plan = PaperPlanWithGrid();
  const SimulatedData data = Simulate(o);
  InstrumentModel model = Perturbed(o.truth, 5);
  const FitSummary s = Refine(data.obs, FitOptions{}, &model);
  EXPECT_TRUE(s.converged) << s.message;
  EXPECT_LT(MaxHeldOutError(model, o.truth), 1e-9);
}

struct EffectCase {
  Effect effect;
  Kinematics kinematics;
  std::array<double, 2> report_value;  // report units (arcsec, mm, ppm, deg)
};

class RefineEffect : public ::testing::TestWithParam<EffectCase> {};

// Each kinematic/EDM effect hidden in noisy data and enabled in the model is
// recovered within 3 of its own sigmas, and the error falls to the noise floor.
TEST_P(RefineEffect, RecoveredWithinThreeSigma) {
  const EffectCase c = GetParam();
  SimulationOptions o;
  o.seed = 11;
  if (c.kinematics == Kinematics::kDh) {
    o.truth = PaperTruth(1);
  } else {
    o.truth = IdealModel(Kinematics::kSpherical, 1, PaperTruth(1).cams[0]);
    o.truth.cams[0].flange_from_cam =
        PoseBlock::FromRigid(Rigid3::FromEuler({2e-3, -1e-3, 4e-3}, {1e-4, -2e-4, 3e-4}));
  }
  o.truth.effects.Add(c.effect);
  o.truth.EffectValue(c.effect) = FromReportUnits(c.effect, c.report_value);
  o.plan = PaperPlanWithGrid();
  o.plan.edm_distances = {1.0, 2.0, 7.0, 30.0};
  o.plan.grid_edm_distances = {1.0, 1.4, 2.3, 5.0, 12.0, 31.0};
  o.noise.point_m = 2e-5;
  const SimulatedData data = Simulate(o);

  InstrumentModel model = Perturbed(o.truth, 9);
  FitOptions fo;
  fo.sigma_edm_m = fo.sigma_cam_m = 2e-5;
  const FitSummary s = Refine(data.obs, fo, &model);
  ASSERT_TRUE(model.sigmas.valid) << s.message;
  const auto& truth_si = o.truth.EffectValue(c.effect);
  const auto& fit_si = model.EffectValue(c.effect);
  const auto& cov = model.sigmas.effect_cov[static_cast<int>(c.effect)];
  // Compare in SI per parameter: |fit - truth| <= 3 sigma.
  const int np = Info(c.effect).num_params;
  for (int i = 0; i < np; ++i) {
    const double sigma = std::sqrt(cov[i * 3]);
    EXPECT_LE(std::abs(fit_si[i] - truth_si[i]), 3.0 * sigma)
        << Info(c.effect).name << " param " << i << " fit " << fit_si[i] << " truth " << truth_si[i]
        << " sigma " << sigma;
  }
  // The error falls to the noise floor: the truth's own error on the same
  // data; the fit may not be worse than it by more than 10 %.
  const ModelErrors fit_err = EvaluateRecords(model, data.obs.records, ErrorMethod::kA);
  const ModelErrors truth_err = EvaluateRecords(o.truth, data.obs.records, ErrorMethod::kA);
  EXPECT_LE(fit_err.compound.mean_m, 1.1 * truth_err.compound.mean_m);
}

INSTANTIATE_TEST_SUITE_P(
    Catalogue, RefineEffect,
    ::testing::Values(EffectCase{Effect::kCollimation, Kinematics::kSpherical, {15.0, 0}},
                      EffectCase{Effect::kTiltingAxis, Kinematics::kSpherical, {12.0, 0}},
                      EffectCase{Effect::kVerticalIndex, Kinematics::kSpherical, {20.0, 0}},
                      EffectCase{Effect::kHzEccentricity, Kinematics::kDh, {10.0, 40.0}},
                      EffectCase{Effect::kVEccentricity, Kinematics::kDh, {10.0, -30.0}},
                      EffectCase{Effect::kHzScale, Kinematics::kDh, {30.0, 0}},
                      EffectCase{Effect::kVScale, Kinematics::kDh, {40.0, 0}},
                      EffectCase{Effect::kAxisWobble, Kinematics::kDh, {8.0, 70.0}},
                      EffectCase{Effect::kEdmOffset, Kinematics::kSpherical, {1.5, 0}},
                      EffectCase{Effect::kEdmScale, Kinematics::kDh, {50.0, 0}},
                      EffectCase{Effect::kEdmCyclic, Kinematics::kDh, {0.8, 25.0}}),
    [](const auto& info) { return std::string(Info(info.param.effect).name); });

}  // namespace
}  // namespace rtscalib

// Ground-truth tests of the whole workflow: records of a seeded
// random truth -> extraction (Klug Sec. 3) -> refinement (Sec. 4.3) -> held-out
// predictions compared with the truth. No starting value comes from the truth.
#include <gtest/gtest.h>

#include <random>

#include "libcalib/eval/error_measures.h"
#include "libcalib/extract/extract.h"
#include "libcalib/fit/refine.h"
#include "libcalib/model/critical_region.h"
#include "libcalib/model/kinematics.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib {
namespace {

// A random dh instrument near the PLT 300: axis offsets and tool offsets of a
// fraction of a millimetre, misalignments of a fraction of a milliradian, a
// station anywhere within 2 m and turned arbitrarily about the vertical.
InstrumentModel RandomTruth(std::uint64_t seed, int zooms) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  InstrumentModel m = PaperTruth(zooms);
  m.base =
      PoseBlock::FromRigid(Rigid3::FromEuler({M_PI + 2e-4 * n(rng), 2e-4 * n(rng), M_PI * u(rng)},
                                             {2.0 * u(rng), 2.0 * u(rng), 1.5 + 0.2 * u(rng)}));
  m.links[0].p = {3e-4 * n(rng), -M_PI / 2 + 0.01 * n(rng), M_PI / 2 + 3e-4 * n(rng),
                  3e-4 * n(rng)};
  m.links[1].p = {2e-4 * n(rng), 3e-4 * n(rng), 3e-4 * n(rng), 2e-4 * n(rng)};
  auto jitter = [&](PoseBlock* p) {
    Rigid3 r = p->ToRigid();
    r.rotation =
        r.rotation * RotationFromEuler<double>({5e-4 * n(rng), 5e-4 * n(rng), 5e-3 * n(rng)});
    r.translation += 3e-4 * Eigen::Vector3d(n(rng), n(rng), n(rng));
    *p = PoseBlock::FromRigid(r);
  };
  jitter(&m.edm);
  for (CameraTool& c : m.cams) {
    jitter(&c.flange_from_cam);
    c.intrinsics[0] *= 1.0 + 0.01 * n(rng);
    c.intrinsics[1] = c.intrinsics[0] * (1.0 + 1e-3 * n(rng));
    c.intrinsics[2] += 5.0 * n(rng);
    c.intrinsics[3] += 5.0 * n(rng);
  }
  return m;
}

AcquisitionPlan TrainingPlan() {
  AcquisitionPlan plan;      // Klug's sweeps ...
  plan.grid_phi_steps = 10;  // ... plus a grid that spans the image
  plan.grid_theta_steps = 6;
  return plan;
}

std::vector<Record> HeldOut(const InstrumentModel& truth) {
  AcquisitionPlan plan;
  plan.sweeps = false;
  plan.grid_phi_steps = 7;
  plan.grid_theta_steps = 5;
  plan.grid_edm_distances = {3.3, 47.0};
  plan.grid_cam_ray_lengths = {2.2, 9.0};
  plan.grid_pixels_per_axis = 4;
  std::vector<Record> out;
  for (const Record& r : PlanRecords(plan, truth)) {
    if (!CriticalRegion().Contains(r.theta)) out.push_back(r);
  }
  return out;
}

// The configured camera: what the device API reports (image size and
// principal point); the focal length is only a rough start.
std::vector<CameraTool> ApiCameras(const InstrumentModel& truth) {
  std::vector<CameraTool> cams = truth.cams;
  for (CameraTool& c : cams) {
    c.flange_from_cam = PoseBlock();
    c.intrinsics[0] = c.intrinsics[1] = 1500.0;
  }
  return cams;
}

class ExtractThenRefine : public ::testing::TestWithParam<int> {};

TEST_P(ExtractThenRefine, NoiseFreeHeldOutPredictionsExact) {
  SimulationOptions o;
  o.seed = GetParam();
  o.truth = RandomTruth(GetParam(), 1);
  o.plan = TrainingPlan();
  const SimulatedData data = Simulate(o);
  const ExtractionResult ex = ExtractDhModel(data.obs.records, ApiCameras(o.truth));
  InstrumentModel model = ex.model;
  FitOptions fo;
  fo.fit_intrinsics = true;
  const FitSummary s = Refine(data.obs, fo, &model);
  EXPECT_TRUE(s.converged) << s.message;
  double worst = 0;
  for (const RecordResidual& r : RecordResiduals(model, HeldOut(o.truth))) {
    ASSERT_TRUE(r.valid);
    worst = std::max(worst, r.distance);
  }
  // Held-out points (other angles, distances up to 47 m, other
  // pixels) to 1e-9 m; exact data leave round-off only (~1e-15 m per metre).
  EXPECT_LT(worst, 1e-9);
}

TEST_P(ExtractThenRefine, NoisyErrorWithinTenPercentOfNoiseFloor) {
  SimulationOptions o;
  o.seed = 100 + GetParam();
  o.truth = RandomTruth(GetParam(), 1);
  o.plan = TrainingPlan();
  o.noise.point_m = 2e-5;
  o.noise.angle_rad = 1.0 / 206265.0;
  const SimulatedData data = Simulate(o);
  const ExtractionResult ex = ExtractDhModel(data.obs.records, ApiCameras(o.truth));
  InstrumentModel model = ex.model;
  FitOptions fo;
  fo.fit_intrinsics = true;
  fo.sigma_edm_m = fo.sigma_cam_m = 2e-5;
  Refine(data.obs, fo, &model);
  // Noise floor: the truth's own error on the same noisy records (Eq. 92).
  const ModelErrors fit = EvaluateRecords(model, data.obs.records, ErrorMethod::kA);
  const ModelErrors floor = EvaluateRecords(o.truth, data.obs.records, ErrorMethod::kA);
  EXPECT_LE(fit.compound.mean_m, 1.1 * floor.compound.mean_m);
  EXPECT_LE(fit.edm.mean_m, 1.1 * floor.edm.mean_m);
  EXPECT_LE(fit.cam.mean_m, 1.1 * floor.cam.mean_m);
}

INSTANTIATE_TEST_SUITE_P(Seeds, ExtractThenRefine, ::testing::Values(1, 2, 3));

}  // namespace
}  // namespace rtscalib

// Every combination of enabled distortion groups (radial, tangential,
// rational, thin_prism, sensor_tilt: 32 subsets) fits noise-free pixels
// exactly: truth with those groups, start from InitFromPixels (as the
// pipeline does) and then perturbed: focal lengths 1 % off, principal point
// 3 px off, every distortion coefficient zero (up to ~12 px at the image
// corners); joint refinement with the groups enabled, judged on held-out
// pixels (other shots, other pointings).
#include <gtest/gtest.h>

#include "libcalib/eval/error_measures.h"
#include "libcalib/fit/init_from_pixels.h"
#include "libcalib/fit/refine.h"
#include "tests/fit/joint_scene.h"

namespace rtscalib {
namespace {

using testing_scene::AddDistortion;
using testing_scene::DhTruth;
using testing_scene::PixelsOnly;

constexpr Effect kGroups[5] = {Effect::kRadialDistortion, Effect::kTangentialDistortion,
                               Effect::kRationalDistortion, Effect::kThinPrism,
                               Effect::kSensorTilt};

EffectSet Subset(int mask) {
  EffectSet s;
  for (int i = 0; i < 5; ++i) {
    if (mask & (1 << i)) s.Add(kGroups[i]);
  }
  return s;
}

std::string SubsetName(int mask) {
  std::string out;
  for (int i = 0; i < 5; ++i) {
    if (mask & (1 << i)) out += (out.empty() ? "" : "_") + std::string(Info(kGroups[i]).name);
  }
  return out.empty() ? "none" : out;
}

class JointDistortionSubsets : public ::testing::TestWithParam<int> {};

TEST_P(JointDistortionSubsets, NoiseFreePixelsFitExactly) {
  const EffectSet groups = Subset(GetParam());
  InstrumentModel truth = DhTruth(1);
  AddDistortion(groups, &truth);
  SimulatedData train = Simulate(PixelsOnly(truth, 4, 11, 0.0));
  train.obs.records.clear();
  SimulatedData held_out = Simulate(PixelsOnly(truth, 3, 12, 0.0));

  InitFromPixelsOptions io;
  io.kinematics = Kinematics::kDh;
  io.distortion = DistortionGroupsOf(groups);
  io.cameras.resize(1);
  io.cameras[0].width = truth.cams[0].width;
  io.cameras[0].height = truth.cams[0].height;
  InstrumentModel model = InitFromPixels(train.obs.pixels, io).model;
  for (Effect e : groups.List()) model.effects.Add(e);
  CameraTool& cam = model.cams[0];
  cam.intrinsics = {1.01 * cam.intrinsics[0], 0.99 * cam.intrinsics[1], cam.intrinsics[2] + 3.0,
                    cam.intrinsics[3] - 3.0};
  cam.distortion.fill(0.0);

  FitOptions fo;
  fo.fit_intrinsics = true;
  fo.compute_covariance = false;
  const FitSummary s = Refine(train.obs, fo, &model);
  const PixelStats fit = EvaluatePixels(model, train.obs.pixels);
  const PixelStats test = EvaluatePixels(model, held_out.obs.pixels);
  // Exact data: only round-off remains (~1e-12 px, tests/fit/joint_init_test.cc);
  // 1e-6 px is the bound, far below any detector's noise.
  // Known exception (docs/refinement.md): tangential + thin_prism without
  // radial stalls at ~6e-6 px ("minimum trust region radius"), whatever the
  // number of shots: p2 r^2 and s1 r^2 are the same term in x (p1 r^2 and
  // s3 r^2 in y), so J is nearly singular there; where along that direction
  // it stalls depends on the start: 6e-6 px from the hand-written LM start,
  // 2.6e-5 px from the Ceres one (CalibrateViews). 5e-5 px for that subset,
  // still 1/1000 of a detector's noise.
  const double bound = GetParam() == 0b01010 ? 5e-5 : 1e-6;
  EXPECT_LT(fit.rms_px, bound) << s.message;
  EXPECT_LT(test.rms_px, bound) << s.message;
  EXPECT_EQ(test.failed, 0);
}

INSTANTIATE_TEST_SUITE_P(AllSubsets, JointDistortionSubsets, ::testing::Range(0, 32),
                         [](const auto& info) { return SubsetName(info.param); });

}  // namespace
}  // namespace rtscalib

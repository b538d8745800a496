// Initialisation without the truth: pixels only -> InitFromPixels
// (OpenCV per zoom, closed-form chain) -> joint refinement.
#include "libcalib/fit/init_from_pixels.h"

#include <gtest/gtest.h>

#include "libcalib/eval/error_measures.h"
#include "libcalib/fit/refine.h"
#include "libcalib/model/kinematics.h"
#include "tests/fit/joint_scene.h"

namespace rtscalib {
namespace {

using testing_scene::DhTruth;
using testing_scene::PixelsOnly;

// Maximum distance between the predictions of two models on a grid of
// pointings, pixels and ray lengths: equal models predict equally.
double MaxCamDifference(const InstrumentModel& a, const InstrumentModel& b, int zoom) {
  double worst = 0;
  for (double phi = 0.1; phi < 6.2; phi += 0.7) {
    for (double theta = 0.4; theta < 2.3; theta += 0.3) {
      for (double u : {10.0, 320.0, 600.0}) {
        for (double v : {20.0, 240.0, 470.0}) {
          const Eigen::Vector3d pa = PredictCam(a, zoom, phi, theta, u, v, 5.0);
          const Eigen::Vector3d pb = PredictCam(b, zoom, phi, theta, u, v, 5.0);
          worst = std::max(worst, (pa - pb).norm());
        }
      }
    }
  }
  return worst;
}

// The camera layer's OpenCV groups free exactly the coefficients the effect
// catalogue gives each distortion group.
TEST(DistortionGroupsOf, FreesTheCataloguesCoefficients) {
  for (const EffectInfo& info : EffectCatalogue()) {
    if (!IsDistortion(info.effect)) continue;
    EffectSet one;
    one.Add(info.effect);
    EXPECT_EQ(DistortionGroupsOf(one).FreeCoefficients(), info.distortion_indices) << info.name;
  }
  EXPECT_TRUE(DistortionGroupsOf(EffectSet()).FreeCoefficients().empty());
}

TEST(DhFromSpherical, PredictsLikeTheSphericalModel) {
  InstrumentModel s = IdealModel(Kinematics::kSpherical, 2, CameraTool{});
  s.base = PoseBlock::FromRigid(Rigid3::FromEuler({0.01, -0.02, 1.3}, {1.0, -2.0, 0.4}));
  s.cams[0].flange_from_cam =
      PoseBlock::FromRigid(Rigid3::FromEuler({0.003, 0.002, -0.01}, {0.01, 0.05, 0.1}));
  s.cams[1].flange_from_cam =
      PoseBlock::FromRigid(Rigid3::FromEuler({-0.001, 0.004, 0.02}, {0.02, 0.04, 0.1}));
  s.cams[1].intrinsics = {2000, 2001, 330, 250};
  const InstrumentModel d = DhFromSpherical(s);
  EXPECT_EQ(d.kinematics, Kinematics::kDh);
  // Round-off of a few rotations at 5 m: 1e-12 m.
  EXPECT_LT(MaxCamDifference(s, d, 0), 1e-12);
  EXPECT_LT(MaxCamDifference(s, d, 1), 1e-12);
}

TEST(InitFromPixels, NoiseFreePixelsOnlyStartThenJointFitIsExact) {
  const InstrumentModel truth = DhTruth(2);
  SimulationOptions o = PixelsOnly(truth, 6, 7, 0.0);
  SimulatedData data = Simulate(o);
  data.obs.records.clear();
  ASSERT_GT(data.obs.pixels.size(), 500u);
  InitFromPixelsOptions io;
  io.kinematics = Kinematics::kDh;
  io.distortion = DistortionGroups{};
  io.distortion.radial = false;
  for (const CameraTool& c : truth.cams) {
    CameraTool size;
    size.width = c.width;
    size.height = c.height;
    io.cameras.push_back(size);
  }
  const InitFromPixelsResult init = InitFromPixels(data.obs.pixels, io);
  for (const std::string& n : init.notes) std::cout << n << "\n";
  InstrumentModel model = init.model;
  FitOptions fo;
  fo.fit_intrinsics = true;
  const PixelStats before = EvaluatePixels(model, data.obs.pixels);
  const FitSummary s = Refine(data.obs, fo, &model);
  const PixelStats after = EvaluatePixels(model, data.obs.pixels);
  std::cout << "before " << before.rms_px << " after " << after.rms_px << " " << s.message
            << " iters " << s.iterations << " seconds " << s.seconds << "\n";
  EXPECT_TRUE(s.converged) << s.message;
  EXPECT_LT(after.rms_px, 1e-6);
  for (int z = 0; z < 2; ++z) {
    for (int i = 0; i < 4; ++i) {
      EXPECT_NEAR(model.cams[z].intrinsics[i], truth.cams[z].intrinsics[i], 1e-6);
    }
  }
}

}  // namespace
}  // namespace rtscalib

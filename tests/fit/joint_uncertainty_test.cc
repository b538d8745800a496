// Consistency of the reported uncertainties: over 20 seeds of noisy
// pixel data, the normalised errors (fit - truth) / sigma of fx, fy, cx, cy
// have a mean square between 0.5 and 2 (1 if the sigmas are right).
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

TEST(JointUncertainty, NormalisedIntrinsicsErrorsHaveUnitMeanSquare) {
  constexpr int kSeeds = 20;
  constexpr double kNoisePx = 0.3;
  EffectSet groups;
  groups.Add(Effect::kRadialDistortion);
  groups.Add(Effect::kTangentialDistortion);
  InstrumentModel truth = DhTruth(1);
  AddDistortion(groups, &truth);
  double sum_sq = 0;
  int n = 0;
  for (int seed = 0; seed < kSeeds; ++seed) {
    // Small scenes: 2 boards x 3 shots x 2 faces, ~2,000 corners.
    SimulatedData data = Simulate(PixelsOnly(truth, 3, 1000 + seed, kNoisePx));
    data.obs.records.clear();
    InitFromPixelsOptions io;
    io.kinematics = Kinematics::kDh;
    io.distortion.tangential = true;
    io.cameras.resize(1);
    io.cameras[0].width = truth.cams[0].width;
    io.cameras[0].height = truth.cams[0].height;
    InstrumentModel model = InitFromPixels(data.obs.pixels, io).model;
    for (Effect e : groups.List()) model.effects.Add(e);
    FitOptions fo;
    fo.fit_intrinsics = true;
    fo.sigma_pixel_px = 1.0;  // deliberately wrong: the variance factor re-estimates it
    const FitSummary s = Refine(data.obs, fo, &model);
    ASSERT_TRUE(model.sigmas.valid) << s.message;
    // The re-estimated pixel sigma is the noise (within ~5 % for ~4,000 residuals).
    EXPECT_NEAR(s.sigma_pixel_px, kNoisePx, 0.05 * kNoisePx);
    for (int i = 0; i < 4; ++i) {
      const double err = model.cams[0].intrinsics[i] - truth.cams[0].intrinsics[i];
      const double sigma = model.sigmas.intrinsics[0][i];
      ASSERT_GT(sigma, 0.0);
      sum_sq += (err / sigma) * (err / sigma);
      ++n;
    }
  }
  const double mean_square = sum_sq / n;
  // 80 normalised errors, correlated within a seed (fx ~ fy): the mean square
  // of ~40 independent unit normals has a standard deviation of ~0.22, so
  // [0.5, 2] (the bounds) is wide of chance and tight against a sigma
  // off by a factor of 1.4.
  EXPECT_GT(mean_square, 0.5);
  EXPECT_LT(mean_square, 2.0);
  std::cout << "mean square of normalised intrinsics errors: " << mean_square << " (" << n
            << " values)\n";
}

}  // namespace
}  // namespace rtscalib

// The diagnosis of a camera on a bench (SPEC 7.1): every photo's board pose
// is estimated with the camera, and the diagnosis must see that freedom as
// the fit had it (LocalColumns, linearization.h), or the board's own tilt
// and distance would pass for lens structure and for effects.
//   - Nothing hidden (the truth in the model's family, 0.2 px of noise):
//     the diagnosis counts the boards' poses among the fit's parameters, its
//     distortion sigmas are the fit's own (the same normal matrix, the poses
//     marginalised), and nothing is recommended or reported as structure.
//   - A wide lens that needs the rational group (mrcal's tour lens scaled to
//     640 x 480), fitted with k1 k2 p1 p2 k3: rational_distortion is
//     recommended, and the fall it states is a refit's, the one a
//     calibration with rational_distortion from its own start gives.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "libcalib/diagnose/diagnose.h"
#include "libcalib/fit/init_from_pixels.h"
#include "libcalib/fit/refine.h"
#include "tests/calibrate/camera_only_session.h"

namespace rtscalib {
namespace {

using testing_camera_only::CameraOnlySession;
using testing_camera_only::TrueCamera;

constexpr double kNoisePx = 0.2;

struct BenchFit {
  InstrumentModel model;
  FitOptions options;
  FitSummary summary;
};

// The calibration's route for pixels alone: the start from OpenCV per zoom
// (InitFromPixels), the effects enabled, the refinement.
BenchFit CalibratedBench(const Observations& obs, const std::vector<Effect>& effects,
               CovarianceClusters clusters = CovarianceClusters::kShot) {
  EffectSet set;
  for (Effect e : effects) set.Add(e);
  InitFromPixelsOptions io;
  io.kinematics = Kinematics::kNone;
  io.distortion = DistortionGroupsOf(set);
  io.cameras.resize(1);
  io.cameras[0].width = obs.image_sizes.at(0).width;
  io.cameras[0].height = obs.image_sizes.at(0).height;
  io.targets = obs.targets;
  BenchFit f;
  f.model = InitFromPixels(obs.pixels, io).model;
  for (Effect e : effects) f.model.effects.Add(e);
  f.options.fit_intrinsics = true;
  f.options.sigma_pixel_px = kNoisePx;
  f.options.covariance_clusters = clusters;
  f.summary = Refine(obs, f.options, &f.model);
  return f;
}

std::string BenchVerdict(const Diagnosis& d) {
  std::string out;
  for (const std::string& v : d.verdict) out += "  " + v + "\n";
  return out;
}

TEST(CameraOnlyDiagnosis, SeesTheBoardPosesAsTheFitDid) {
  const Observations obs = CameraOnlySession(TrueCamera(), 15, kNoisePx, 21);
  // The classical covariance (no clusters), as the diagnosis's (J^T J)^-1.
  const BenchFit f = CalibratedBench(obs, {Effect::kRadialDistortion, Effect::kTangentialDistortion},
                           CovarianceClusters::kNone);
  ASSERT_TRUE(f.summary.converged);
  ASSERT_EQ(f.model.boards.size(), 15u);
  const Diagnosis d = Diagnose(obs, f.model, ContextOf(f.options, f.summary), DiagnosisSettings());
  // fx fy cx cy, k1 k2 p1 p2 k3, and 6 per board pose.
  EXPECT_EQ(d.num_parameters, 9 + 6 * 15);
  // The distortion sigmas from the diagnosis's normal matrix (the poses
  // marginalised block by block) are the refinement's: the same Jacobian,
  // the same whitening; 1 % for the refinement's own round-off and its
  // Jacobi-scaled eigen-decomposition.
  ASSERT_TRUE(f.model.sigmas.valid);
  ASSERT_EQ(d.distortion_terms.terms.size(), 5u);
  for (const DistortionTerm& t : d.distortion_terms.terms) {
    const double fit_sigma = f.model.sigmas.distortion[0][t.index];
    EXPECT_NEAR(t.sigma, fit_sigma, 0.01 * fit_sigma) << t.name;
  }
  // Nothing hidden: nothing to add, no structure.
  EXPECT_EQ(d.Next(), nullptr) << BenchVerdict(d);
  EXPECT_TRUE(d.structure.unexplained.empty()) << BenchVerdict(d);
}

// mrcal's tour lens (LENSMODEL_OPENCV8 of the set's PROVENANCE.md) on a
// 640 x 480 sensor with the same field: fx 2074 px over 6016 px wide.
CameraTool WideCamera() {
  CameraTool c = TrueCamera();
  const double scale = 640.0 / 6016.0;
  c.intrinsics = {2073.87 * scale, 2077.45 * scale, 320.0, 240.0};
  c.distortion = {};
  c.distortion[kK1] = 0.4792;
  c.distortion[kK2] = 0.02668;
  c.distortion[kK3] = 8.96e-5;
  c.distortion[kK4] = 0.7667;
  c.distortion[kK5] = 0.09634;
  c.distortion[kK6] = 0.001408;
  return c;
}

TEST(CameraOnlyDiagnosis, HiddenRationalDistortionIsRecommendedWithItsRefitFall) {
  // Shifted three times as far sideways: the boards reach the image corners.
  const Observations obs = CameraOnlySession(WideCamera(), 20, kNoisePx, 22, 3.0);
  const BenchFit f = CalibratedBench(obs, {Effect::kRadialDistortion, Effect::kTangentialDistortion});
  const Diagnosis d = Diagnose(obs, f.model, ContextOf(f.options, f.summary), DiagnosisSettings());
  const RankedEffect* next = d.Next();
  ASSERT_NE(next, nullptr) << BenchVerdict(d);
  EXPECT_EQ(next->effect, Effect::kRationalDistortion) << BenchVerdict(d);
  EXPECT_EQ(next->after_source, "refined");
  EXPECT_GE(next->gain, d.min_gain);
  // The user's next run, rational_distortion in the config from its own
  // start: the rms the diagnosis stated, to 2 % (the refit holds the fit's
  // sigma, the calibration re-estimates it; one group, so only where each
  // stopped differs).
  const BenchFit with = CalibratedBench(
      obs, {Effect::kRadialDistortion, Effect::kTangentialDistortion, Effect::kRationalDistortion});
  const double calibrated = RmsOfModel(obs, with.model, with.options).Main();
  std::printf("hidden rational: %.4g -> %.4g px stated (%s; linear %.4g), %.4g px calibrated\n",
              next->rms_before, next->rms_after, next->after_source.c_str(),
              next->linear_after.Main(), calibrated);
  EXPECT_NEAR(next->rms_after, calibrated, 0.02 * calibrated) << BenchVerdict(d);
  // The noise floor: 0.2 px per coordinate less what the ~130 parameters
  // take of ~1,000 corners.
  EXPECT_LT(next->rms_after, 1.2 * kNoisePx * std::sqrt(2.0));
}

}  // namespace
}  // namespace rtscalib

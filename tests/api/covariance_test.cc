// The full parameter covariance: the fit keeps it
// (ModelSigmas::covariance, covariance.yaml beside model.yaml), the API loads
// it, and with it the predicted pixel uncertainty matches the scatter of the
// predictions of fits to independent noisy data of one simulated truth,
// where the diagonal approximation from model.yaml's sigmas does not.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <filesystem>
#include <iostream>

#include "libcalib/api/rtscalib.h"
#include "libcalib/fit/init_from_pixels.h"
#include "libcalib/fit/parameter_layout.h"
#include "libcalib/fit/refine.h"
#include "libcalib/io/covariance_io.h"
#include "libcalib/text/errors.h"
#include "libcalib/io/model_io.h"
#include "libcalib/model/kinematics.h"
#include "tests/api/pixel_calibration.h"

namespace rtscalib {
namespace {

namespace fs = std::filesystem;

fs::path CovarianceDir(const std::string& name) { return testing_api::TestDir("api_covariance", name); }

constexpr double kNoisePx = 0.3;

InstrumentModel CovarianceTruth() { return testing_api::DistortedTruth(); }

// One calibration from pixels of seed `seed` (joint_uncertainty_test's scene:
// 2 boards x 3 shots x 2 faces, ~2,000 corners).
InstrumentModel CovarianceFit(const InstrumentModel& truth, int seed, Observations* obs_out = nullptr) {
  return testing_api::FitFromPixels(truth, 5000 + seed, kNoisePx, obs_out);
}

// The fit fills the covariance in ParameterLayout order; its diagonal is the
// square of the per-parameter sigmas model.yaml states (same numbers, two
// routes), and a covariance.yaml round-trips it bit for bit (%.17g).
TEST(FullCovariance, FitKeepsItAndTheFileRoundTripsExactly) {
  const InstrumentModel truth = CovarianceTruth();
  InstrumentModel model = CovarianceFit(truth, 0);
  model.cams[0].valid_region = {{0.25, 1.5}, {600.125, 3}, {630, 470.0625}, {2, 460}};
  const std::vector<LayoutBlock> layout = ParameterLayout(model);
  const int n = LayoutSize(layout);
  ASSERT_EQ(model.sigmas.covariance.rows(), n);
  ASSERT_EQ(model.sigmas.covariance.cols(), n);
  EXPECT_EQ(model.sigmas.covariance, model.sigmas.covariance.transpose());
  for (const LayoutBlock& b : layout) {
    if (b.name != "cam[0].intrinsics") continue;
    for (int i = 0; i < b.size; ++i) {
      // sqrt of the same floating-point number: equal to rounding.
      EXPECT_NEAR(std::sqrt(model.sigmas.covariance(b.offset + i, b.offset + i)),
                  model.sigmas.intrinsics[0][i], 1e-12 * model.sigmas.intrinsics[0][i]);
    }
  }

  const fs::path dir = CovarianceDir("round_trip");
  WriteModelYaml((dir / "model.yaml").string(), model);
  WriteCovarianceYaml((dir / "covariance.yaml").string(), model);
  const CalibratedInstrument inst = CalibratedInstrument::Load((dir / "model.yaml").string());
  ASSERT_TRUE(inst.HasParameterCovariance());
  ASSERT_TRUE(inst.HasFullParameterCovariance());
  EXPECT_EQ(inst.ParameterCovariance(), model.sigmas.covariance);  // exact
  EXPECT_EQ(inst.Model().cams[0].valid_region, model.cams[0].valid_region);
  ASSERT_EQ(inst.NumParameters(), n);

  // Through a symlink (the output folder's top): the file beside the target.
  const fs::path top = CovarianceDir("top");
  fs::create_symlink(dir / "model.yaml", top / "model.yaml");
  EXPECT_TRUE(
      CalibratedInstrument::Load((top / "model.yaml").string()).HasFullParameterCovariance());

  // Without the file: the diagonal approximation, as before.
  fs::remove(dir / "covariance.yaml");
  const CalibratedInstrument diag = CalibratedInstrument::Load((dir / "model.yaml").string());
  EXPECT_TRUE(diag.HasParameterCovariance());
  EXPECT_FALSE(diag.HasFullParameterCovariance());
}

// A covariance.yaml beside another model's model.yaml is refused, naming the
// file and the block, never paired silently.
TEST(FullCovariance, AForeignCovarianceFileIsRefused) {
  const InstrumentModel truth = CovarianceTruth();
  InstrumentModel model = CovarianceFit(truth, 1);
  const fs::path dir = CovarianceDir("foreign");
  WriteCovarianceYaml((dir / "covariance.yaml").string(), model);
  model.cams[0].intrinsics[0] += 1e-9;
  WriteModelYaml((dir / "model.yaml").string(), model);
  try {
    CalibratedInstrument::Load((dir / "model.yaml").string());
    FAIL() << "a foreign covariance.yaml was accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find((dir / "covariance.yaml").string()), std::string::npos) << what;
    EXPECT_NE(what.find("cam[0].intrinsics"), std::string::npos) << what;
  }
}

// Ground truth: kSeeds fits to independent noisy pixels of one truth. For
// query points at 10 m seen at a fixed pointing (image centre, the four
// corner regions), the prediction errors e = Pixel_fit - Pixel_truth are
// compared with each fit's predicted 2x2 covariance S through the normalised
// square e^T S^-1 e, whose mean is 2 (chi-square, 2 degrees of freedom) when
// S is right. Its mean over seeds and points, halved, is the "mean square
// normalised error" (1 if right).
//
// Tolerance: 20 seeds x 5 points = 100 values of a chi-square(2)/2 (std 1),
// correlated within a seed (the points share one fit): the mean's standard
// deviation is 0.1 for independent values and up to ~0.22 for 20
// independent seeds, so [0.5, 2] is wide of chance yet fails an S off by a
// factor of 1.4 in sigma. The diagonal approximation ignores the fit's
// correlations (camera rotation vs principal point, fx vs distortion), which
// are strong here, so its mean square is far from 1; the test requires the
// full covariance's to be closer to 1 in log scale, and prints both.
TEST(FullCovariance, PredictedPixelCovarianceMatchesTheScatterBetterThanTheDiagonal) {
  constexpr int kSeeds = 20;
  const InstrumentModel truth = CovarianceTruth();
  Observations obs0;
  CovarianceFit(truth, 100, &obs0);
  const double phi = obs0.pixels.front().phi, theta = obs0.pixels.front().theta;
  const CameraTool& cam = truth.cams[0];
  const Rigid3 ref_from_cam = RefFromCam(truth, 0, phi, theta);
  std::vector<Eigen::Vector3d> points;
  for (const auto& [fu, fv] : std::vector<std::pair<double, double>>{
           {0.5, 0.5}, {0.1, 0.1}, {0.9, 0.1}, {0.1, 0.9}, {0.9, 0.9}}) {
    const double pixel[2] = {fu * (cam.width - 1), fv * (cam.height - 1)};
    double ray[3] = {0, 0, 0};
    ASSERT_TRUE(PixelToRay(cam.intrinsics.data(), cam.distortion.data(), pixel, ray));
    const Eigen::Vector3d r = Eigen::Vector3d(ray[0], ray[1], ray[2]).normalized();
    points.push_back(ref_from_cam * (10.0 * r));
  }
  const CalibratedInstrument truth_inst(truth);
  double full_sum = 0, diag_sum = 0, full_sigma = 0, diag_sigma = 0, err2 = 0;
  int n = 0;
  for (int seed = 0; seed < kSeeds; ++seed) {
    const InstrumentModel model = CovarianceFit(truth, seed);
    ASSERT_GT(model.sigmas.covariance.rows(), 0);
    const CalibratedInstrument full(model);
    InstrumentModel without = model;
    without.sigmas.covariance.resize(0, 0);
    const CalibratedInstrument diag(without);
    ASSERT_TRUE(full.HasFullParameterCovariance());
    ASSERT_FALSE(diag.HasFullParameterCovariance());
    for (const Eigen::Vector3d& x : points) {
      const Eigen::Vector2d e = full.Pixel(0, phi, theta, x) - truth_inst.Pixel(0, phi, theta, x);
      const Eigen::Matrix2d sf = full.PixelWithUncertainty(0, phi, theta, x).covariance;
      const Eigen::Matrix2d sd = diag.PixelWithUncertainty(0, phi, theta, x).covariance;
      full_sum += e.dot(sf.ldlt().solve(e)) / 2;
      diag_sum += e.dot(sd.ldlt().solve(e)) / 2;
      full_sigma += sf.trace();
      diag_sigma += sd.trace();
      err2 += e.squaredNorm();
      ++n;
    }
  }
  const double full_ms = full_sum / n, diag_ms = diag_sum / n;
  std::cout << "pixel errors at 10 m, " << kSeeds << " seeds x " << points.size() << " points: RMS "
            << std::sqrt(err2 / n) << " px; predicted RMS, full P " << std::sqrt(full_sigma / n)
            << " px, diagonal P " << std::sqrt(diag_sigma / n)
            << " px; mean square normalised error, full " << full_ms << ", diagonal " << diag_ms
            << "\n";
  EXPECT_GT(full_ms, 0.5);
  EXPECT_LT(full_ms, 2.0);
  EXPECT_LT(std::abs(std::log(full_ms)), std::abs(std::log(diag_ms)));
}

}  // namespace
}  // namespace rtscalib

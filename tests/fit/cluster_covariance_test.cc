// The cluster-robust covariance (FitOptions::covariance_clusters, refine.cc)
// against errors that are correlated within a photo. A real photo's pixels
// share the error of the photo's angle reading (the instrument reads phi,
// theta but points at phi + e, theta + e: every corner of the photo moves
// together) and of its detection (blur, exposure). Here each simulated photo
// gets such a reading error on top of independent pixel noise. Over several
// seeds the normalised intrinsics errors (fit - truth) / sigma must have a
// mean square in [0.5, 2] (joint_uncertainty_test's bounds) with the photo clusters, while
// the independent-error covariance, which counts every corner as independent
// evidence, claims far more than it has (mean square > 4 here).
#include <gtest/gtest.h>

#include <map>
#include <random>

#include "libcalib/fit/init_from_pixels.h"
#include "libcalib/fit/refine.h"
#include "tests/fit/joint_scene.h"

namespace rtscalib {
namespace {

using testing_scene::AddDistortion;
using testing_scene::DhFromPixels;
using testing_scene::DhTruth;
using testing_scene::PixelsOnly;


constexpr int kShotsPerBoard = 6;
struct Outcome {
  double mean_square_independent = 0, mean_square_clustered = 0;
  std::vector<double> pixel_sigma_zoom;
  int clusters = 0;
};

// Reading errors of `reading_rad` per photo and `pixel_px` per corner.
Outcome NormalisedErrors(int seeds, double reading_rad, double pixel_px) {
  EffectSet groups;
  groups.Add(Effect::kRadialDistortion);
  InstrumentModel truth = DhTruth(1);
  AddDistortion(groups, &truth);
  Outcome out;
  double sum_sq[2] = {0, 0};
  int n = 0;
  for (int seed = 0; seed < seeds; ++seed) {
    SimulatedData data = Simulate(PixelsOnly(truth, kShotsPerBoard, 2000 + seed, pixel_px));
    data.obs.records.clear();
    std::mt19937_64 rng(77 + seed);
    std::normal_distribution<double> normal(0.0, reading_rad);
    std::map<std::string, std::pair<double, double>> reading_error;
    for (PixelObservation& p : data.obs.pixels) {
      auto it = reading_error.find(p.shot);
      if (it == reading_error.end()) {
        const double d_phi = normal(rng), d_theta = normal(rng);
        it = reading_error.emplace(p.shot, std::make_pair(d_phi, d_theta)).first;
      }
      p.phi += it->second.first;
      p.theta += it->second.second;
    }
    InitFromPixelsOptions io;
    io.kinematics = Kinematics::kDh;
    io.cameras.resize(1);
    io.cameras[0].width = truth.cams[0].width;
    io.cameras[0].height = truth.cams[0].height;
    const InstrumentModel start = InitFromPixels(data.obs.pixels, io).model;
    for (int mode = 0; mode < 2; ++mode) {
      InstrumentModel model = start;
      for (Effect e : groups.List()) model.effects.Add(e);
      FitOptions fo;
      fo.fit_intrinsics = true;
      fo.covariance_clusters = mode == 0 ? CovarianceClusters::kNone : CovarianceClusters::kShot;
      const FitSummary s = Refine(data.obs, fo, &model);
      EXPECT_TRUE(model.sigmas.valid) << s.message;
      if (!model.sigmas.valid) return out;
      if (mode == 1) {
        out.clusters = s.covariance_clusters;
        out.pixel_sigma_zoom = s.sigma_pixel_px_zoom;
      }
      for (int i = 0; i < 4; ++i) {
        const double err = model.cams[0].intrinsics[i] - truth.cams[0].intrinsics[i];
        const double sigma = model.sigmas.intrinsics[0][i];
        sum_sq[mode] += (err / sigma) * (err / sigma);
      }
    }
    n += 4;
  }
  out.mean_square_independent = sum_sq[0] / n;
  out.mean_square_clustered = sum_sq[1] / n;
  return out;
}

TEST(ClusterCovariance, PhotoReadingErrorsAreCountedOncePerPhoto) {
  // 12 seeds x 4 intrinsics; a reading error of 1e-4 rad moves a photo by
  // 0.08 px at f = 800 px, against 0.05 px of independent noise per corner
  // (36 photos of ~100 corners per seed: the sandwich needs clusters well
  // beyond the parameters they inform; with 16 photos it still claims ~1.5x
  // too much, mean square 2.3).
  const Outcome o = NormalisedErrors(12, 1e-4, 0.05);
  std::cout << "mean square normalised intrinsics errors: independent "
            << o.mean_square_independent << ", clustered by photo " << o.mean_square_clustered
            << " (" << o.clusters << " clusters)\n";
  EXPECT_GT(o.clusters, 10);
  // 48 normalised errors, correlated within a seed (fx ~ fy, cx ~ tool):
  // ~24 independent ones, whose mean square has a standard deviation of
  // ~0.3: [0.5, 2] is wide of chance and tight against a sigma off by 1.4.
  EXPECT_GT(o.mean_square_clustered, 0.5);
  EXPECT_LT(o.mean_square_clustered, 2.0);
  // The independent-error covariance is overconfident by the photos'
  // common error (the test would fail without the clusters).
  EXPECT_GT(o.mean_square_independent, 4.0);
}

TEST(ClusterCovariance, WithIndependentErrorsItAgreesWithTheClassicalCovariance) {
  // No reading error: the clustered covariance is never below the classical
  // one and the scatter it measures is the assumed one, so both hold.
  const Outcome o = NormalisedErrors(6, 0.0, 0.2);
  std::cout << "independent errors only: mean square independent " << o.mean_square_independent
            << ", clustered " << o.mean_square_clustered << "\n";
  EXPECT_GT(o.mean_square_independent, 0.4);
  EXPECT_LT(o.mean_square_independent, 2.0);
  EXPECT_GT(o.mean_square_clustered, 0.4);
  EXPECT_LT(o.mean_square_clustered, 2.0);
  EXPECT_LE(o.mean_square_clustered, o.mean_square_independent * (1 + 1e-9));
}

// The pixels' variance components are per zoom: a detector's noise differs
// between zoom levels (the rendered demo: 0.013 px at zoom 0, 0.031 px at
// zoom 2), and one pooled sigma would overstate the precision of the noisier
// zoom and understate that of the other.
TEST(ClusterCovariance, PixelSigmasAreEstimatedPerZoom) {
  InstrumentModel truth = DhTruth(2);
  SimulatedData data = Simulate(PixelsOnly(truth, 3, 4242, 0.0));
  data.obs.records.clear();
  const double noise[2] = {0.1, 0.4};
  std::mt19937_64 rng(5);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (PixelObservation& p : data.obs.pixels) {
    p.uv += noise[p.zoom] * Eigen::Vector2d(normal(rng), normal(rng));
  }
  InstrumentModel model = InitFromPixels(data.obs.pixels, DhFromPixels(truth)).model;
  FitOptions fo;
  fo.fit_intrinsics = true;
  const FitSummary s = Refine(data.obs, fo, &model);
  ASSERT_EQ(s.sigma_pixel_px_zoom.size(), 2u);
  // ~2,000 residuals per zoom: the estimate's relative standard deviation
  // is ~1/sqrt(2 x 2,000) = 1.6 %; 6 % is ~4 of them.
  for (int z = 0; z < 2; ++z) {
    EXPECT_NEAR(s.sigma_pixel_px_zoom[z], noise[z], 0.06 * noise[z]) << "zoom " << z;
  }
  // The pooled figure is the root mean square over the pixels, between the two.
  EXPECT_GT(s.sigma_pixel_px, s.sigma_pixel_px_zoom[0]);
  EXPECT_LT(s.sigma_pixel_px, s.sigma_pixel_px_zoom[1]);
}

}  // namespace
}  // namespace rtscalib

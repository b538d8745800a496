// The variance-component estimate of the refinement (Refine,
// FitOptions::reestimate_sigmas): every observation group gets the sigma
// its residuals show, by a fixed-point iteration (solve, re-estimate) that
// stops once no sigma moves by more than 5 %. Records of both tools and the
// pixels of two zooms, each with its own noise, the a-priori sigmas
// FitOptions' defaults (records 1e-5 m against 5e-5, pixels 0.5 px against
// 0.05 and 0.2). Started at an
// earlier fit's estimate (Refine's `earlier`; Calibrate starts the full set
// so from the reduced set) the iteration converges at once, to the same
// sigmas; a start with the zooms' sigmas swapped does not.
#include <gtest/gtest.h>

#include <random>
#include <utility>

#include "libcalib/fit/init_from_pixels.h"
#include "libcalib/fit/refine.h"
#include "tests/fit/joint_scene.h"

namespace rtscalib {
namespace {

using testing_scene::DhFromPixels;
using testing_scene::DhTruth;
using testing_scene::PixelsOnly;

constexpr double kNoise[2] = {0.05, 0.2};  // px, zoom 0 and 1
constexpr double kRecordNoise = 5e-5;      // m per coordinate, EDM and camera records

struct Scene {
  Observations obs;
  InstrumentModel start;
};

Scene MakeScene() {
  const InstrumentModel truth = DhTruth(2);
  SimulationOptions so = PixelsOnly(truth, 3, 777, 0.0);
  so.noise.point_m = kRecordNoise;
  SimulatedData data = Simulate(so);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (PixelObservation& p : data.obs.pixels) {
    p.uv += kNoise[p.zoom] * Eigen::Vector2d(normal(rng), normal(rng));
  }
  Scene s;
  s.start = InitFromPixels(data.obs.pixels, DhFromPixels(truth)).model;
  s.obs = std::move(data.obs);
  return s;
}

TEST(VarianceComponents, AnEarlierFitsSigmasStartTheEstimateAndItConvergesAtOnce) {
  const Scene scene = MakeScene();
  ASSERT_FALSE(scene.obs.records.empty());
  FitOptions fo;
  fo.fit_intrinsics = true;
  InstrumentModel a = scene.start;
  const FitSummary from_apriori = Refine(scene.obs, fo, &a);
  ASSERT_EQ(from_apriori.sigma_pixel_px_zoom.size(), 2u);
  // 0.5 px a priori against 0.05 and 0.2: the first estimate moves them by
  // far more than 5 %, so at least one more round.
  EXPECT_GE(from_apriori.sigma_rounds, 2);

  InstrumentModel b = scene.start;
  const FitSummary from_earlier = Refine(scene.obs, fo, &b, &from_apriori);
  EXPECT_TRUE(from_earlier.sigmas_converged);
  EXPECT_EQ(from_earlier.sigma_rounds, 1);
  // ~2,000 residuals per zoom: an estimate's relative standard deviation is
  // ~1/sqrt(2 x 2,000) = 1.6 %; 6 % is ~4 of them.
  for (int z = 0; z < 2; ++z) {
    EXPECT_NEAR(from_earlier.sigma_pixel_px_zoom[z], kNoise[z], 0.06 * kNoise[z]) << "zoom " << z;
  }
  // The same fixed point: within the 5 % the iteration stops at.
  if (from_apriori.sigmas_converged) {
    for (int z = 0; z < 2; ++z) {
      EXPECT_NEAR(from_earlier.sigma_pixel_px_zoom[z], from_apriori.sigma_pixel_px_zoom[z],
                  0.05 * from_apriori.sigma_pixel_px_zoom[z])
          << "zoom " << z;
    }
  }

  // The zooms' sigmas swapped: a factor of 4 off each, more than one round.
  FitSummary swapped = from_apriori;
  std::swap(swapped.sigma_pixel_px_zoom[0], swapped.sigma_pixel_px_zoom[1]);
  InstrumentModel c = scene.start;
  const FitSummary from_swapped = Refine(scene.obs, fo, &c, &swapped);
  EXPECT_GE(from_swapped.sigma_rounds, 2);
}

// Held sigmas (reestimate_sigmas false): no estimate, and an earlier fit
// does not replace the given sigmas.
TEST(VarianceComponents, HeldSigmasAreOneSolveAndIgnoreAnEarlierFit) {
  const Scene scene = MakeScene();
  FitOptions fo;
  fo.fit_intrinsics = true;
  fo.reestimate_sigmas = false;
  fo.sigma_pixel_px = 0.1;
  FitSummary earlier;
  earlier.sigma_pixel_px_zoom = {0.01, 0.01};
  InstrumentModel m = scene.start;
  const FitSummary s = Refine(scene.obs, fo, &m, &earlier);
  EXPECT_EQ(s.sigma_rounds, 0);
  EXPECT_FALSE(s.sigmas_converged);
  for (int z = 0; z < 2; ++z) EXPECT_EQ(s.sigma_pixel_px_zoom[z], 0.1) << "zoom " << z;
}

}  // namespace
}  // namespace rtscalib

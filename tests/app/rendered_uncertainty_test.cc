// Uncertainties that hold on rendered and detected photos (issue 10 item 1,
// issue 9's first "done when"): the zoom3 demo's scene rendered for four
// seeds, its hidden effect put into the model, calibrated (1) as the demo
// does, with the records, and (2) from the photo folder alone, as a user
// without a laser tracker would (`data: {shots, targets}`, boards of unknown
// pose, no simulate section). Over the seeds, the normalised errors
// (fit - truth) / sigma of every zoom's fx, fy, cx, cy, k1, k2, p1, p2 and of
// the effect must have a mean square in [0.5, 2] (1 if the sigmas are right;
// the issues' bounds). 104 values per calibration, correlated within a seed
// (fx ~ fy, k1 ~ k2): ~50 independent ones, whose mean square has a standard
// deviation of ~0.2, so [0.5, 2] is wide of chance and fails a sigma off by
// 1.5x. Measured (Release): with records 1.38, photos alone 0.94; before
// the renderer resampled at exact coordinates and the covariance knew the
// photos' clusters, 12.2 with the records (the full demo grid).
#include <gtest/gtest.h>

#include <unistd.h>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>

#include "app/pipeline.h"
#include "libcalib/io/config.h"

namespace rtscalib::app {
namespace {

struct Sums {
  double sum_sq = 0;
  int n = 0;
  void Add(double err, double sigma) {
    ASSERT_GT(sigma, 0.0);
    sum_sq += (err / sigma) * (err / sigma);
    ++n;
  }
  double MeanSquare() const { return n ? sum_sq / n : 0.0; }
};

void AddErrors(const InstrumentModel& m, const InstrumentModel& truth, Sums* s) {
  ASSERT_TRUE(m.sigmas.valid);
  for (int z = 0; z < truth.NumZooms(); ++z) {
    for (int i = 0; i < 4; ++i) {
      s->Add(m.cams[z].intrinsics[i] - truth.cams[z].intrinsics[i], m.sigmas.intrinsics[z][i]);
    }
    for (int k : {kK1, kK2, kP1, kP2}) {
      s->Add(m.cams[z].distortion[k] - truth.cams[z].distortion[k], m.sigmas.distortion[z][k]);
    }
  }
  const Effect e = Effect::kHzEccentricity;
  const auto& cov = m.sigmas.effect_cov[static_cast<int>(e)];
  for (int i = 0; i < 2; ++i) {
    s->Add(m.EffectValue(e)[i] - truth.EffectValue(e)[i], std::sqrt(cov[3 * i]));
  }
}

TEST(RenderedUncertainty, NormalisedErrorsOverSeedsHaveUnitMeanSquare) {
#ifndef RTSCALIB_WITH_RENDER
  GTEST_SKIP() << "built without the renderer";
#endif
  unsetenv("DISPLAY");
  const std::filesystem::path work = std::filesystem::temp_directory_path() /
                                     ("rtscalib_rendered_uncertainty_" + std::to_string(::getpid()));
  Sums with_records, photos_only;
  for (const int seed : {3, 4, 5, 6}) {
    RunSettings settings =
        LoadRunSettings(std::string(RTSCALIB_SOURCE_DIR) + "/configs/zoom3.yaml");
    RunConfig& c = settings.config;
    c.simulate->seed = seed;
    // Fewer grid records than the demo (the photos are what is tested).
    c.simulate->plan.grid_phi_steps = 8;
    c.simulate->plan.grid_theta_steps = 4;
    c.model.effects.Add(Effect::kHzEccentricity);  // the hidden effect, found by the diagnosis
    c.diagnose.enabled = false;
    const std::filesystem::path dir = work / std::to_string(seed);
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    Progress progress(true);
    const PipelineResult r = RunPipeline(settings, dir.string(), &progress);
    ASSERT_TRUE(r.truth.has_value());
    AddErrors(r.calibration.model, *r.truth, &with_records);

    // The same photo folder alone, as a user's (no simulate, no records).
    RunSettings user = settings;
    user.config.simulate.reset();
    user.config.shots_path = (dir / "photos" / "shots.csv").string();
    user.config.targets_path = (dir / "photos" / "targets.yaml").string();
    ASSERT_TRUE(std::filesystem::exists(user.config.shots_path));
    const std::filesystem::path dir2 = work / (std::to_string(seed) + "_photos");
    std::filesystem::create_directories(dir2);
    const PipelineResult p = RunPipeline(user, dir2.string(), &progress);
    EXPECT_TRUE(p.obs.records.empty());
    AddErrors(p.calibration.model, *r.truth, &photos_only);
  }
  std::filesystem::remove_all(work);
  std::cout << "mean square normalised errors over seeds 3-6: with records "
            << with_records.MeanSquare() << " (" << with_records.n << "), photos alone "
            << photos_only.MeanSquare() << " (" << photos_only.n << ")\n";
  EXPECT_GT(with_records.MeanSquare(), 0.5);
  EXPECT_LT(with_records.MeanSquare(), 2.0);
  EXPECT_GT(photos_only.MeanSquare(), 0.5);
  EXPECT_LT(photos_only.MeanSquare(), 2.0);
}

}  // namespace
}  // namespace rtscalib::app

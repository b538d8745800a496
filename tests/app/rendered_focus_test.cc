// The camera that refocuses (SPEC 4.1) in rendered photos: the session of
// configs/one_board.yaml (one board moved to six placements, both faces,
// three zooms, no records) with its farthest placement moved out to 27 m
// (3 to 27 m) and, instead of the demo's hidden hz_eccentricity, each zoom's
// camera refocusing on every photo (kf, au, av per zoom). The render stage
// draws each photo with the intrinsics at its focus distance and writes that
// distance into shots.csv, as an instrument would report it; the photos are
// detected and calibrated through the user's photo path (RunPipeline). One
// rendering, shared by every check:
//   - the run's diagnosis (model without focus) names focus first,
//     significant and worth adding, with the fall a refit gives, and
//     recommends nothing else (no thin_prism for a gain within the scatter);
//   - the same fit diagnosed without focus among the candidates says first
//     that the image points fit worse than their a-priori sigma, and reports
//     structure against the target (or focus) distance that points to focus;
//   - with focus in the model (Calibrate on the same detected corners): no
//     structure against the target or focus distance is left to report; kf,
//     au, av of every zoom within 3 of their sigmas of the truth, and
//     held-out corners at other pointings (each pointing turned by (0.01,
//     0.005) rad, the camera focused at the board's distance) predicted
//     within 0.05 px RMS per coordinate, the floor of the other hidden
//     effects.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <set>
#include <string>

#include "app/pipeline.h"
#include "libcalib/config/config.h"
#include "libcalib/model/focus.h"
#include "libcalib/model/kinematics.h"
#include "tests/app/held_out.h"

namespace rtscalib::app {
namespace {

// The truth's focus per zoom [kf m, au px m, av px m]: from the nearest to
// the farthest board a zoom sees, the image scale changes by 0.05-0.1 % and
// the principal point by 0.3-0.6 px, 10-30 times the detection noise.
constexpr std::array<std::array<double, 3>, 3> kFocus = {
    {{0.005, 3.0, -2.0}, {0.008, -4.0, 2.5}, {0.012, 6.0, 3.0}}};

std::string Verdict(const Diagnosis& d) {
  std::string out;
  for (const std::string& v : d.verdict) out += "  " + v + "\n";
  return out;
}

TEST(RenderedFocus, RefocusingCameraInRenderedPhotosIsFoundAndCalibrated) {
#ifndef RTSCALIB_WITH_RENDER
  GTEST_SKIP() << "built without the renderer";
#endif
  unsetenv("DISPLAY");  // the render stage starts its own X server
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("rtscalib_rendered_focus_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  RunSettings settings =
      LoadRunSettings(std::string(RTSCALIB_SOURCE_DIR) + "/configs/one_board.yaml");
  RunConfig& c = settings.config;
  c.simulate->seed = 3;
  InstrumentModel& truth = c.simulate->truth;
  truth.effects.Remove(Effect::kHzEccentricity);
  truth.EffectValue(Effect::kHzEccentricity) = {0.0, 0.0};
  truth.effects.Add(Effect::kFocus);
  ASSERT_EQ(truth.NumZooms(), 3);
  for (int z = 0; z < 3; ++z) truth.cams[z].focus = kFocus[z];
  // The farthest placement (p6, 24.8 m) moved out along its direction to
  // 27 m: the farthest at which the 1.46 m board still spans a quarter of
  // zoom 2's view, which the shot planner asks of a board (at 30 m it
  // would take p6 into no zoom's photos).
  TagBoard& far = c.simulate->placements.at("p6").boards.at(0);
  const Eigen::Vector3d centre = far.CentreInRef();
  far.ref_from_board.translation += (27.0 / centre.norm() - 1.0) * centre;
  // The a-priori sigma of a corner as the detector delivers it on these
  // photos (1 grey level of sensor noise: ~0.02 px per coordinate), not the
  // config's loose 0.1 px: against 0.1 px no misfit of a few hundredths
  // could show.
  c.calibration.fit.sigma_pixel_px = 0.025;

  Progress progress(true);
  const PipelineResult r = RunPipeline(settings, dir.string(), &progress);
  ASSERT_TRUE(r.render.ran) << r.render.note;
  std::set<double> distances;
  for (const PixelObservation& p : r.obs.pixels) {
    ASSERT_GT(p.focus_distance, 0.0);  // shots.csv's column, copied by the detection
    distances.insert(p.focus_distance);
  }
  EXPECT_LT(*distances.begin(), 4.0);
  EXPECT_GT(*distances.rbegin(), 25.0);

  // The run: focus ranks first and is significant.
  ASSERT_TRUE(r.calibration.diagnosis.has_value());
  const Diagnosis& with = *r.calibration.diagnosis;
  ASSERT_FALSE(with.ranking.entries.empty());
  EXPECT_EQ(with.ranking.entries.front().effect, Effect::kFocus) << Verdict(with);
  EXPECT_TRUE(with.ranking.entries.front().significant) << Verdict(with);
  EXPECT_TRUE(with.ranking.entries.front().recommended) << Verdict(with);
  EXPECT_EQ(with.ranking.entries.front().after_source, "refined") << Verdict(with);
  for (const RankedEffect& e : with.ranking.entries) {
    if (e.effect != Effect::kFocus) {
      EXPECT_FALSE(e.recommended) << e.name << "\n" << Verdict(with);
    }
  }
  std::cout << "rendered focus, without focus in the model:\n" << Verdict(with);

  // The same fit without focus among the candidates.
  const InstrumentModel& fitted = r.calibration.model;
  DiagnosisSettings untested;
  untested.untested = {Effect::kFocus};
  const Diagnosis without =
      Diagnose(r.obs, fitted,
               ContextOf(r.calibration.fit_options, r.calibration.fit), untested);
  bool pixels_exceed = false;
  for (const FitQualityCell& q : without.fit_quality.cells) {
    pixels_exceed = pixels_exceed || (q.group == ObsGroup::kPixel && q.exceeds);
  }
  EXPECT_TRUE(pixels_exceed) << Verdict(without);
  EXPECT_NE(without.verdict.at(0).find("image points of zoom"), std::string::npos)
      << Verdict(without);
  bool distance = false;
  for (const StructureFinding& s : without.structure.unexplained) {
    if (s.probe.kind == ProbeKind::kImageMotion &&
        (s.variable == "target distance" || s.variable == "focus distance")) {
      distance = true;
      EXPECT_NE(s.points_to.find("focus"), std::string::npos) << s.points_to;
    }
  }
  EXPECT_TRUE(distance) << Verdict(without);

  // Focus in the model, on the same detected corners.
  CalibrationOptions options = c.calibration;
  options.model.effects.Add(Effect::kFocus);
  const CalibrationResult fit = Calibrate(r.obs, options);
  const InstrumentModel& m = fit.model;
  ASSERT_TRUE(fit.diagnosis.has_value());
  std::cout << "rendered focus, focus in the model:\n" << Verdict(*fit.diagnosis);
  for (const StructureFinding& s : fit.diagnosis->structure.unexplained) {
    EXPECT_FALSE(s.probe.kind == ProbeKind::kImageMotion &&
                 (s.variable == "target distance" || s.variable == "focus distance"))
        << s.description;
  }
  ASSERT_TRUE(m.sigmas.valid);
  ASSERT_EQ(m.sigmas.focus.size(), 3u);
  double sum_sq = 0;
  int n = 0;
  for (int z = 0; z < 3; ++z) {
    for (int i = 0; i < kNumFocus; ++i) {
      const double err = m.cams[z].focus[i] - kFocus[z][i];
      const double sigma = m.sigmas.focus[z][i];
      ASSERT_GT(sigma, 0.0);
      EXPECT_LT(std::abs(err), 3 * sigma)
          << "zoom " << z << " " << kFocusParamNames[i] << " = " << m.cams[z].focus[i]
          << " +- " << sigma << ", truth " << kFocus[z][i];
      sum_sq += (err / sigma) * (err / sigma);
      ++n;
    }
  }

  // Held-out pointings of every placement, every corner the truth sees, the
  // camera focused at the board's distance from it.
  testing_held_out::HeldOut held;
  testing_held_out::AddHeldOutPlacements(m, truth, c.simulate->placements, r.obs.pixels, &held);
  std::filesystem::remove_all(dir);
  ASSERT_GT(held.n, 1000);
  const double held_rms = held.RmsPerCoordinate();
  std::cout << "rendered focus: focus terms mean square normalised error " << sum_sq / n
            << " over " << n << " values; held-out RMS " << held_rms << " px per coordinate over "
            << held.n << " corners (detection noise "
            << r.render.detection_rms_px / std::sqrt(2.0) << " px); diagnosis "
            << with.seconds << " s\n";
  EXPECT_LT(held_rms, 0.05);
}

}  // namespace
}  // namespace rtscalib::app

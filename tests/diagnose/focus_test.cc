// The camera that refocuses (SPEC 4.1, catalogue effect `focus`) hidden in
// simulated records and image points of boards at 3 to 30 m: without focus
// among the candidates the diagnosis must say that the image points fit
// worse than their a-priori sigma and show structure against the target
// distance; with it, focus ranks first, and the model with it predicts
// held-out data to the noise-free floor and recovers kf, au, av within their
// sigmas.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "libcalib/diagnose/diagnose.h"
#include "libcalib/model/focus.h"
#include "tests/diagnose/diagnose_fixture.h"

namespace rtscalib {
namespace {

using testing_diagnose::PaperNoise;
using testing_diagnose::Perturbed;
using testing_diagnose::SmallPlan;

// Pixel noise per coordinate, as in the session that showed the effect.
constexpr double kPixelNoise = 0.15;

// Two zooms whose cameras refocus: the camera constant grows by kf / D and
// the principal point moves by (au, av) / D, so that from 3 to 30 m the
// image scale changes by 0.15 % (0.9 px at the image corner of zoom 0) and
// the principal point by 0.9 px.
InstrumentModel FocusTruth() {
  InstrumentModel t = PaperTruth(2);
  t.effects.Add(Effect::kFocus);
  t.cams[0].focus = {0.005, 3.0, -2.0};
  t.cams[1].focus = {0.008, -4.0, 2.5};
  return t;
}

// Per zoom, boards at 3, 6.5, 14 and 30 m around the station, each spanning
// about half the view of its zoom (tags scale with the distance).
TargetScene NearAndFar(const InstrumentModel& truth) {
  TargetScene scene;
  const Eigen::Vector3d station = RefFromFlange(truth, 0.0, M_PI / 2).translation;
  const double distances[] = {3.0, 6.5, 14.0, 30.0};
  for (int z = 0; z < truth.NumZooms(); ++z) {
    const CameraTool& cam = truth.cams[z];
    for (int k = 0; k < 4; ++k) {
      const double d = distances[k];
      const double half_view = d * 0.5 * cam.width / cam.intrinsics[0];
      const double tag = half_view / (5 * 1.25);
      scene.boards.push_back(FacingBoard(station, 1000 * z + 100 * k, 4, 5, tag, d,
                                         0.5 + 1.45 * k + 0.7 * z, -0.1 + 0.05 * k,
                                         k % 2 ? 0.4 : -0.4));
    }
  }
  return scene;
}

SimulationOptions Session(std::uint64_t seed, bool report_focus_distance) {
  SimulationOptions o;
  o.seed = seed;
  o.truth = FocusTruth();
  o.plan = SmallPlan();
  o.plan.zooms = {0, 1};
  o.targets = NearAndFar(o.truth);
  o.shots.shots_per_board = 2;
  o.shots.report_focus_distance = report_focus_distance;
  o.noise = PaperNoise();
  o.noise.pixel_px = kPixelNoise;
  return o;
}

struct FocusFit {
  SimulatedData data;
  InstrumentModel model;
  FitOptions options;
  FitSummary summary;
};

// The a-priori sigmas a user states: the noise of each kind, per coordinate
// (records: the truth's own error on these data, which the angle noise
// makes grow with distance).
FitOptions AprioriOf(const SimulatedData& data, const InstrumentModel& truth) {
  FitOptions o;
  o.fit_intrinsics = true;
  o.num_threads = 1;
  const GroupRms floor = RmsOfModel(data.obs, truth, o);
  o.sigma_edm_m = floor.edm_m / std::sqrt(3.0);
  o.sigma_cam_m = floor.cam_m / std::sqrt(3.0);
  o.sigma_pixel_px = kPixelNoise;
  return o;
}

FocusFit FitModel(SimulatedData data, const InstrumentModel& truth, const EffectSet& effects,
             std::uint64_t seed) {
  FocusFit f;
  f.data = std::move(data);
  f.options = AprioriOf(f.data, truth);
  f.model = Perturbed(truth, seed);  // effects removed, focus terms zeroed
  f.model.effects = effects;
  f.summary = Refine(f.data.obs, f.options, &f.model);
  return f;
}

// RMS of exact (noise-free) held-out pixels and records predicted by `model`.
double HeldOutPixelsRms(const InstrumentModel& model, const SimulatedData& exact) {
  return EvaluatePixels(model, exact.obs.pixels).rms_px;
}
double HeldOutRecordsRms(const InstrumentModel& model, const std::vector<Record>& records) {
  double ss = 0;
  int n = 0;
  for (const RecordResidual& r : RecordResiduals(model, records)) {
    if (!r.valid) continue;
    ss += r.distance * r.distance;
    ++n;
  }
  return n > 0 ? std::sqrt(ss / n) : 0.0;
}

std::string Verdict(const Diagnosis& d) {
  std::string out;
  for (const std::string& v : d.verdict) out += "  " + v + "\n";
  return out;
}

TEST(Focus, HiddenInRecordsAndPixelsIsFoundAndPredictsHeldOutData) {
  const SimulationOptions o = Session(31, /*report_focus_distance=*/true);
  FocusFit f = FitModel(Simulate(o), o.truth, EffectSet(), 32);
  ASSERT_GT(f.data.obs.pixels.size(), 3000u);

  // Without focus among the candidates: the image points fit worse than the
  // a-priori sigma allows (said first), and their scale and principal point
  // change with the target distance.
  DiagnosisSettings without;
  without.untested = {Effect::kFocus};
  const Diagnosis d0 = Diagnose(f.data.obs, f.model, ContextOf(f.options, f.summary), without);
  bool pixels_exceed = false;
  for (const FitQualityCell& c : d0.fit_quality.cells) {
    if (c.group == ObsGroup::kPixel && c.exceeds) pixels_exceed = true;
  }
  EXPECT_TRUE(pixels_exceed) << Verdict(d0);
  ASSERT_FALSE(d0.verdict.empty());
  EXPECT_NE(d0.verdict[0].find("image points of zoom"), std::string::npos) << Verdict(d0);
  bool distance = false;
  for (const StructureFinding& s : d0.structure.unexplained) {
    if (s.probe.kind == ProbeKind::kImageMotion && s.variable == "target distance") {
      distance = true;
      EXPECT_NE(s.points_to.find("focus"), std::string::npos) << s.points_to;
    }
  }
  EXPECT_TRUE(distance) << Verdict(d0);
  for (const RankedEffect& r : d0.ranking.entries) EXPECT_NE(r.effect, Effect::kFocus);

  // With it: focus ranks first and is significant.
  const Diagnosis d1 =
      Diagnose(f.data.obs, f.model, ContextOf(f.options, f.summary), DiagnosisSettings());
  ASSERT_FALSE(d1.ranking.entries.empty());
  const RankedEffect& top = d1.ranking.entries.front();
  EXPECT_EQ(top.effect, Effect::kFocus) << Verdict(d1);
  EXPECT_TRUE(top.significant);
  EXPECT_EQ(top.focus.size(), 6u);  // kf, au, av of both zooms

  // Added (the ranking's config line), the model predicts exact held-out
  // data at other pointings (another seed's jitter, the grid moved) to the
  // floor of the other hidden effects: 0.05 px and 1e-5 m (the noise of the
  // fitted data averages out over the ~3,000 points each parameter sees).
  InstrumentModel with = f.model;
  AddAtEstimate(top, &with);
  Refine(f.data.obs, f.options, &with);
  SimulationOptions held = Session(131, true);
  held.noise = NoiseOptions();
  held.plan.grid_phi_steps = 7;
  held.plan.grid_theta_steps = 4;
  const SimulatedData exact = Simulate(held);
  const double pixels_rms = HeldOutPixelsRms(with, exact);
  const double records_rms = HeldOutRecordsRms(with, exact.obs.records);
  EXPECT_LE(pixels_rms, 0.05) << "without focus " << HeldOutPixelsRms(f.model, exact) << " px";
  EXPECT_LE(records_rms, 1e-5) << "without focus " << HeldOutRecordsRms(f.model, exact.obs.records)
                               << " m";
  std::printf("held-out: pixels %.4f px (without focus %.4f), records %.2e m (without %.2e)\n",
              pixels_rms, HeldOutPixelsRms(f.model, exact), records_rms,
              HeldOutRecordsRms(f.model, exact.obs.records));

  // Nothing else is missing once it is in.
  const Diagnosis d2 =
      Diagnose(f.data.obs, with, ContextOf(f.options, f.summary), DiagnosisSettings());
  EXPECT_FALSE(d2.fit_quality.Exceeds()) << Verdict(d2);
  EXPECT_EQ(d2.Next(), nullptr) << Verdict(d2);
}

// kf, au, av of both zooms against the truth over seeds, with the focus
// distance reported by the photos and computed from the model (the centroid
// of each photo's points): each within 3 of its sigma, and the mean square
// of the normalised errors below 2 (its expectation is 1 for honest sigmas;
// the photo-clustered covariance is conservative, docs/refinement.md).
TEST(Focus, TermsAreRecoveredWithinTheirSigmas) {
  const InstrumentModel truth = FocusTruth();
  double sum_sq = 0;
  int n = 0;
  for (std::uint64_t seed : {41u, 42u, 43u}) {
    const bool reported = seed % 2 == 1;
    const SimulationOptions o = Session(seed, reported);
    EffectSet effects;
    effects.Add(Effect::kFocus);
    const FocusFit f = FitModel(Simulate(o), o.truth, effects, seed + 50);
    ASSERT_TRUE(f.model.sigmas.valid);
    ASSERT_EQ(f.model.sigmas.focus.size(), 2u);
    for (int z = 0; z < 2; ++z) {
      for (int i = 0; i < kNumFocus; ++i) {
        const double sigma = f.model.sigmas.focus[z][i];
        const double err = f.model.cams[z].focus[i] - truth.cams[z].focus[i];
        ASSERT_GT(sigma, 0.0);
        EXPECT_LT(std::abs(err), 3 * sigma)
            << "seed " << seed << " zoom " << z << " " << kFocusParamNames[i] << " = "
            << f.model.cams[z].focus[i] << " truth " << truth.cams[z].focus[i];
        sum_sq += (err / sigma) * (err / sigma);
        ++n;
      }
    }
  }
  std::printf("focus terms: mean square normalised error %.2f over %d values\n", sum_sq / n, n);
  EXPECT_LT(sum_sq / n, 2.0);
}

// The photos' D from the model is the centroid distance of each photo's
// points, which the simulator made the photo's focus distance: the two
// agree to round-off.
TEST(Focus, PhotoDistanceIsTheCentroidTheSimulatorFocusedAt) {
  const SimulationOptions o = Session(7, true);
  const SimulatedData data = Simulate(o);
  const std::vector<double> computed = PhotoFocusDistances(o.truth, data.obs.pixels, nullptr,
                                                           /*use_given=*/false);
  double lo = 1e9, hi = 0;
  for (size_t i = 0; i < data.obs.pixels.size(); ++i) {
    ASSERT_GT(data.obs.pixels[i].focus_distance, 0.0);
    EXPECT_NEAR(computed[i], data.obs.pixels[i].focus_distance, 1e-9);
    lo = std::min(lo, computed[i]);
    hi = std::max(hi, computed[i]);
  }
  // The boards are 3 to 30 m away.
  EXPECT_LT(lo, 4.0);
  EXPECT_GT(hi, 25.0);
}

}  // namespace
}  // namespace rtscalib

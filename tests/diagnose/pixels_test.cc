// Diagnosis from image observations (pixels.csv) alone: distortion hidden in
// the pixels of known AprilTag corners.
#include <gtest/gtest.h>

#include "libcalib/diagnose/diagnose.h"
#include "tests/diagnose/diagnose_fixture.h"

namespace rtscalib {
namespace {

using testing_diagnose::FitBaseline;
using testing_diagnose::Fitted;
using testing_diagnose::PaperNoise;

// Four boards of 6 x 8 tags, 2.5 m around the station, facing it: each spans
// about half the image, the shots move it around.
TargetScene Boards() {
  TargetScene scene;
  TagBoard board;
  board.rows = 6;
  board.cols = 8;
  board.tag_size = 0.1;
  board.spacing = 0.025;
  for (int i = 0; i < 4; ++i) {
    TagBoard b = board;
    b.first_id = i * board.NumTags();
    const double yaw = M_PI / 2 * i;
    b.ref_from_board =
        Rigid3::FromEuler({M_PI / 2, 0.0, yaw}, {2.5 * std::sin(yaw), 2.5 * std::cos(yaw), 0.0});
    scene.boards.push_back(b);
  }
  return scene;
}

TEST(Pixels, RadialDistortionInImagePointsRanksFirst) {
  SimulationOptions o;
  o.seed = 61;
  o.truth = PaperTruth(1);
  // Pincushion (k1 > 0): with k1 < 0 the simulator's projection folds corners
  // far outside the field of view back into the image (it does not check the
  // trusted region of the distortion), which no model could fit.
  o.truth.cams[0].distortion[kK1] = 0.05;
  o.truth.effects.Add(Effect::kRadialDistortion);
  o.plan = testing_diagnose::SmallPlan();
  o.targets = Boards();
  o.shots.shots_per_board = 4;
  o.noise = PaperNoise();
  o.noise.pixel_px = 0.2;
  SimulatedData data = Simulate(o);
  // Only EDM records: the distortion is seen in the pixels alone.
  std::vector<Record> edm;
  for (const Record& r : data.obs.records) {
    if (r.tool == Tool::kEdm) edm.push_back(r);
  }
  data.obs.records = edm;
  ASSERT_GT(data.obs.pixels.size(), 500u);
  const Fitted f = FitBaseline(data, o.truth, 62);
  const Diagnosis d = testing_diagnose::DiagnoseFitted(f);
  const RankedEffect& top = d.ranking.entries.front();
  EXPECT_EQ(top.name, "radial_distortion");
  EXPECT_TRUE(top.significant);
  EXPECT_EQ(top.rms_unit, "m");  // records present: the headline is in metres
  EXPECT_LT(top.after.pixels_px, top.before.pixels_px);
  // k1, k2, k3 and the focal length trade off over the field of view, so the
  // check is the image error after adding it: within 10% of the noise floor
  // (the truth's own error on these pixels).
  EXPECT_EQ(top.after_source, "refined");
  EXPECT_LE(top.after.pixels_px, 1.1 * RmsOfModel(f.data.obs, f.truth, f.options).pixels_px);
  EXPECT_EQ(top.distortion.size(), 3u);  // k1, k2, k3 of zoom 0
}

}  // namespace
}  // namespace rtscalib

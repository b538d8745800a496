// Per-zoom model generation and `rtscalib predict --pixels` (issue 3), run
// in-process: pixels.csv of a 3-zoom instrument seen in both faces (no
// records) -> `rtscalib --config` (start from the pixels alone, joint fit) ->
// model.yaml with every zoom's tool, intrinsics and distortion and their
// sigmas -> `rtscalib predict --pixels` on held-out shots of every zoom and
// face, compared with the exact projections.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "app/commands.h"
#include "libcalib/io/model_io.h"
#include "libcalib/io/records.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib {
namespace {

namespace fs = std::filesystem;

InstrumentModel Truth() {
  InstrumentModel m = PaperTruth(3);
  for (int z = 0; z < 3; ++z) {
    CameraTool& c = m.cams[z];
    c.width = 640;
    c.height = 480;
    const double f = 800.0 * std::pow(1.6, z);
    c.intrinsics = {f, f * (1 + 3e-4), 324.0 - z, 237.0 + z};
    c.distortion[kK1] = -0.1 / (1 + z);
    c.distortion[kK2] = 0.04 / (1 + z);
    c.distortion[kP1] = 4e-4;
    c.distortion[kP2] = -3e-4;
  }
  m.effects.Add(Effect::kRadialDistortion);
  m.effects.Add(Effect::kTangentialDistortion);
  return m;
}

SimulationOptions Shots(const InstrumentModel& truth, std::uint64_t seed, int shots) {
  SimulationOptions o;
  o.seed = seed;
  o.truth = truth;
  o.targets = ZoomScene(truth, 5, 6, 3.0);
  o.shots.shots_per_board = shots;
  o.plan.faces = {1, 2};
  o.plan.zooms = {0, 1, 2};
  return o;
}

TEST(PredictPixels, PixelsOnlyRunThenPredictEveryZoomAndFace) {
  const fs::path dir = fs::path(RTSCALIB_BINARY_DIR) / "test_tmp" / "predict_pixels";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const InstrumentModel truth = Truth();
  WritePixels((dir / "pixels.csv").string(), Simulate(Shots(truth, 1, 3)).obs.pixels);
  {
    std::ofstream cfg(dir / "run.yaml");
    cfg << "data:\n  pixels: pixels.csv\n"
           "model:\n  kinematics: dh\n  effects: [radial_distortion, tangential_distortion]\n"
           "  intrinsics: fit\n  cameras:\n";
    for (int z = 0; z < 3; ++z) {
      // Only the image size is used by the start from pixels; the rest is nominal.
      cfg << "    - {width: 640, height: 480, fx: 1000, fy: 1000, cx: 320, cy: 240}\n";
    }
    cfg << "output: out\n";
  }
  app::RunArgs run;
  run.config = (dir / "run.yaml").string();
  run.quiet = true;
  ASSERT_EQ(app::RunCalibration(run), 0);

  const std::string model_path = (dir / "out" / "model.yaml").string();
  const InstrumentModel model = ReadModelYaml(model_path);
  ASSERT_EQ(model.NumZooms(), 3);
  ASSERT_TRUE(model.sigmas.valid);
  for (int z = 0; z < 3; ++z) {
    for (int i = 0; i < 4; ++i) EXPECT_GT(model.sigmas.intrinsics[z][i], 0.0) << "zoom " << z;
    for (int i : {kK1, kK2, kP1, kP2}) {
      EXPECT_GT(model.sigmas.distortion[z][i], 0.0) << "zoom " << z << " coefficient " << i;
    }
    EXPECT_GT(model.sigmas.cam_tools[z].t[0], 0.0) << "zoom " << z;
  }

  // Held-out shots of every zoom and face (other seed, other pointings).
  const SimulatedData held_out = Simulate(Shots(truth, 2, 2));
  WritePixels((dir / "held_out.csv").string(), held_out.obs.pixels);
  app::PredictArgs predict;
  predict.model = model_path;
  predict.pixels = (dir / "held_out.csv").string();
  predict.out = (dir / "predicted.csv").string();
  ASSERT_EQ(app::RunPredict(predict), 0);
  const PixelsFile predicted = ReadPixels(predict.out);
  ASSERT_EQ(predicted.pixels.size(), held_out.exact_pixels.size());
  double worst[3][2] = {};
  int rows[3][2] = {};
  for (size_t i = 0; i < predicted.pixels.size(); ++i) {
    const PixelObservation& p = predicted.pixels[i];
    const double err = (p.uv - held_out.exact_pixels[i]).norm();
    worst[p.zoom][p.face - 1] = std::max(worst[p.zoom][p.face - 1], err);
    ++rows[p.zoom][p.face - 1];
  }
  for (int z = 0; z < 3; ++z) {
    for (int f = 0; f < 2; ++f) {
      // Noise-free data fit to round-off; CSV text keeps 17 digits. 1e-6 px
      // is the bound for exact data.
      EXPECT_LT(worst[z][f], 1e-6) << "zoom " << z << " face " << f + 1;
      EXPECT_GT(rows[z][f], 0) << "zoom " << z << " face " << f + 1 << " has no rows";
    }
  }
}

}  // namespace
}  // namespace rtscalib

// Per-zoom model generation and `rtscalib predict --pixels`, run
// in-process: pixels.csv of a 3-zoom instrument seen in both faces (no
// records) -> `rtscalib --config` (start from the pixels alone, joint fit) ->
// model.yaml with every zoom's tool, intrinsics and distortion and their
// sigmas -> `rtscalib predict --pixels` on held-out shots of every zoom and
// face, compared with the exact projections.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "app/commands.h"
#include "libcalib/text/errors.h"
#include "libcalib/io/model_io.h"
#include "libcalib/model/kinematics.h"
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

// SPEC 7.1: rows with empty X, Y, Z are predicted from the pose of their
// board in their row's placement; a placement the model has no pose for is
// refused by line (or left out with --skip-bad).
TEST(PredictPixels, PlacementsPredictFromTheirOwnBoardPose) {
  const fs::path dir = fs::path(RTSCALIB_BINARY_DIR) / "test_tmp" / "predict_placements";
  fs::remove_all(dir);
  fs::create_directories(dir);
  CameraTool cam;
  cam.width = 640;
  cam.height = 480;
  cam.intrinsics = {800, 800, 320, 240};
  InstrumentModel m = IdealModel(Kinematics::kSpherical, 1, cam);
  for (const auto& [name, y] : std::vector<std::pair<std::string, double>>{{"a", 5.0}, {"b", 9.0}}) {
    EstimatedBoard b;
    b.board.first_id = 0;
    b.board.rows = 3;
    b.board.cols = 4;
    b.board.pose_known = false;
    b.placement = name;
    // Facing the instrument at phi = 0 (+y), upright (board x = ref x, y = -z).
    b.pose = PoseBlock::FromRigid(Rigid3{Rx(-M_PI / 2), Eigen::Vector3d(-0.2, y, 0.15)});
    b.board.ref_from_board = b.pose.ToRigid();
    m.boards.push_back(b);
  }
  WriteModelYaml((dir / "model.yaml").string(), m, {});
  std::vector<PixelObservation> rows;
  for (const std::string placement : {"a", "b", "c"}) {
    PixelObservation p;
    p.phi = 0.01;
    p.theta = M_PI / 2 + 0.02;
    p.shot = "s" + placement;
    p.placement = placement;
    p.target = 5;
    p.corner = 2;
    p.X_known = false;
    rows.push_back(p);
  }
  WritePixels((dir / "in.csv").string(), rows);
  app::PredictArgs predict;
  predict.model = (dir / "model.yaml").string();
  predict.pixels = (dir / "in.csv").string();
  predict.out = (dir / "out.csv").string();
  try {
    app::RunPredict(predict);
    FAIL() << "placement c (no pose in the model) predicted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line, 4);  // header, a, b, c
    EXPECT_NE(std::string(e.what()).find("placement 'c'"), std::string::npos) << e.what();
  }
  predict.skip_bad = true;
  ASSERT_EQ(app::RunPredict(predict), 0);
  const PixelsFile out = ReadPixels(predict.out);
  ASSERT_EQ(out.pixels.size(), 2u);
  for (int k = 0; k < 2; ++k) {
    const EstimatedBoard& b = m.boards[k];
    EXPECT_EQ(out.pixels[k].placement, b.placement);
    Eigen::Vector2d expected;
    ASSERT_TRUE(PredictPixel(m, 0, 0.01, M_PI / 2 + 0.02,
                             b.pose.ToRigid() * b.board.CornersInBoard(5)[2], &expected));
    // Written with 17 digits: the same double.
    EXPECT_LT((out.pixels[k].uv - expected).norm(), 1e-9) << b.placement;
  }
  // The two placements are 4 m apart along the line of sight: different pixels.
  EXPECT_GT((out.pixels[0].uv - out.pixels[1].uv).norm(), 1.0);
}

}  // namespace
}  // namespace rtscalib

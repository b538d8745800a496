// One code path for simulated and real photos (SPEC 7): a small version of
// the zoom3 demo is rendered as a photo session (shots.csv, images,
// targets.yaml), then calibrated from that folder through data.shots and
// data.targets, exactly as a user's photos would be. Ground truth from the
// simulator.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include <unistd.h>

#include "app/commands.h"
#include "app/output_folder.h"
#include "app/pipeline.h"
#include "app/reports.h"
#include "libcalib/text/errors.h"
#include "libcalib/io/records.h"
#include "libcalib/io/targets_io.h"
#include "libcalib/sim/simulator.h"

#include "tests/app/figure_checks.h"

namespace rtscalib::app {
namespace {

namespace fs = std::filesystem;

class PhotoSession : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
#ifndef RTSCALIB_WITH_RENDER
    GTEST_SKIP() << "built without the renderer";
#endif
    unsetenv("DISPLAY");  // the render stage starts its own X server
    work_ = fs::temp_directory_path() / ("rtscalib_photos_test_" + std::to_string(::getpid()));
    fs::remove_all(work_);
    fs::create_directories(work_);
    try {
      RunSettings demo = LoadRunSettings(std::string(RTSCALIB_SOURCE_DIR) + "/configs/zoom3.yaml");
      SimulationOptions sim = *demo.config.simulate;
      // Small: zoom 0 only, 2 shots per board (the plan adds the positions
      // the image's middle needs), a coarse grid of records.
      sim.shots.shots_per_board = 2;
      sim.plan.zooms = {0};
      sim.plan.grid_phi_steps = 8;
      sim.plan.grid_theta_steps = 4;
      // The demo's truth (from the config) restricted to zoom 0.
      sim.truth.cams.resize(1);
      truth_ = new InstrumentModel(sim.truth);
      const SimulatedData data = Simulate(sim);
      Progress progress(true);
      photos_ = work_ / "photos";
      // Surveyed boards here (targets.yaml with poses); the test of unknown
      // boards below leaves them out.
      demo.render.board_poses_known = true;
      const RenderStageResult r = RenderSession(demo.render, sim.truth, sim.Scenes(),
                                                data.obs.pixels, photos_.string(), &progress);
      if (!r.ran) {
        error_ = "render stage did not run: " + r.note;
        return;
      }
      shots_ = r.shots;
      WriteRecords((work_ / "records.csv").string(), data.obs.records);
      // The user's config: the folder's files, the demo's model and fit.
      std::ofstream(work_ / "photos.yaml")
          << "data:\n  records: records.csv\n  shots: photos/shots.csv\n"
             "  targets: photos/targets.yaml\n"
             "model:\n  kinematics: dh\n  effects: [radial_distortion, tangential_distortion]\n"
             "  intrinsics: fit\n"
             "fit:\n  sigmas: {edm_m: 1.0e-5, cam_m: 1.0e-5, pixel_px: 0.1}\n"
             "output: out\n";
      const RunSettings user = LoadRunSettings((work_ / "photos.yaml").string());
      result_ = new PipelineResult(RunPipeline(user, (work_ / "run").string(), &progress));
    } catch (const std::exception& e) {
      error_ = e.what();
    }
  }
  void SetUp() override {
#ifndef RTSCALIB_WITH_RENDER
    GTEST_SKIP() << "built without the renderer";
#endif
    ASSERT_NE(result_, nullptr) << "the photo session failed: " << error_;
  }
  static void TearDownTestSuite() {
    delete result_;
    delete truth_;
    fs::remove_all(work_);
  }
  static PipelineResult* result_;
  static InstrumentModel* truth_;
  static std::string error_;
  static fs::path work_, photos_;
  static int shots_;
};
PipelineResult* PhotoSession::result_ = nullptr;
InstrumentModel* PhotoSession::truth_ = nullptr;
std::string PhotoSession::error_;
fs::path PhotoSession::work_, PhotoSession::photos_;
int PhotoSession::shots_ = 0;

TEST_F(PhotoSession, TheFolderIsWhatAUserHas) {
  EXPECT_TRUE(fs::is_regular_file(photos_ / "shots.csv"));
  EXPECT_TRUE(fs::is_regular_file(photos_ / "targets.yaml"));
  EXPECT_TRUE(fs::is_regular_file(photos_ / "truth_targets.yaml"));
  EXPECT_FALSE(result_->simulated);
  ASSERT_TRUE(result_->photos.ran);
  EXPECT_EQ(static_cast<int>(result_->photos.photos.size()), shots_);
  EXPECT_EQ(result_->photos.boards_with_pose, 4);
  EXPECT_GT(result_->photos.corners, 16 * shots_);  // many tags per photo
  // Image sizes from the images, never guessed.
  ASSERT_EQ(result_->obs.image_sizes.count(0), 1u);
  EXPECT_EQ(result_->obs.image_sizes.at(0).width, 1280);
  EXPECT_EQ(result_->obs.image_sizes.at(0).height, 960);
  EXPECT_EQ(result_->calibration.size_source.at(0), "images");
  EXPECT_EQ(result_->calibration.model.cams[0].width, 1280);
  EXPECT_EQ(result_->calibration.model.cams[0].height, 960);
  // Every observation names its photo's shots.csv line.
  for (const PixelObservation& p : result_->obs.pixels) {
    EXPECT_TRUE(p.X_known);
    EXPECT_GE(p.line, 2);
  }
}

TEST_F(PhotoSession, CalibrationFromThePhotosMatchesTheTruth) {
  const CameraTool& cam = result_->calibration.model.cams[0];
  const CameraTool& t = truth_->cams[0];
  std::printf("fx %.6g (truth %.6g), cx %.4f (%.4f), k1 %.5f (%.5f), k2 %.5f (%.5f), rms %.3f px\n",
              cam.intrinsics[0], t.intrinsics[0], cam.intrinsics[2], t.intrinsics[2],
              cam.distortion[0], t.distortion[0], cam.distortion[1], t.distortion[1],
              result_->calibration.final_errors.pixels.rms_px);
  // Focal lengths: 2e-4 relative. Detection bias (~0.03 px over a 640 px half
  // width, 5e-5) plus the noise of a small session (sigmas ~5e-5 here).
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(cam.intrinsics[i] / t.intrinsics[i], 1.0, 2e-4) << "intrinsic " << i;
  }
  // Principal point within 1 px (sigma ~0.2 px for this session).
  for (int i = 2; i < 4; ++i) EXPECT_NEAR(cam.intrinsics[i], t.intrinsics[i], 1.0);
  // k1 = -0.08, k2 = 0.05: within 5e-3, the coefficients' spread over
  // sessions this small with the image corners covered.
  EXPECT_NEAR(cam.distortion[0], t.distortion[0], 5e-3);
  EXPECT_NEAR(cam.distortion[1], t.distortion[1], 2e-2);
  // Pixels fit to the detection noise (~0.05-0.1 px): below 0.3 px.
  EXPECT_LT(result_->calibration.final_errors.pixels.rms_px, 0.3);
}

TEST_F(PhotoSession, FiguresDrawTheResidualTable) {
  const std::vector<Figure> figs = testing_figures::CheckFiguresAgainstResidualFile(*result_);
  // The worst photos are drawn on the photo itself.
  int photos = 0;
  for (const Figure& f : figs) {
    if (f.section != "photos") continue;
    ++photos;
    EXPECT_TRUE(f.summary["photo"].get<bool>()) << f.name << ": the photo file was not found";
  }
  EXPECT_GT(photos, 0);
}

// `rtscalib show --shot ID`: any photo of a run, from the run's files alone.
TEST_F(PhotoSession, ShowDrawsAnyPhotoFromTheRunFiles) {
  OutputFolder out((work_ / "show_run").string());
  RunConfig config;
  config.config_path = (work_ / "photos.yaml").string();
  out.Write("residuals.csv", ResidualsCsv(*result_));
  out.Write("report.json", ReportJson(config, *result_, out, HistoryJson(out)).dump());
  // The last photo with corners (the worst ones are in report.html already).
  std::string shot;
  int corners = 0;
  for (const ObservationResidual& o : result_->calibration.residuals) {
    if (o.group != ObsGroup::kPixel) continue;
    if (o.shot != shot) corners = 0;
    shot = o.shot;
    ++corners;
  }
  ASSERT_FALSE(shot.empty());
  ShowArgs args;
  args.output = out.run_dir();
  args.shot = shot;
  args.out = (work_ / "show").string();
  ::testing::internal::CaptureStdout();
  EXPECT_EQ(RunShow(args), 0);
  const std::string printed = ::testing::internal::GetCapturedStdout();
  EXPECT_NE(printed.find("shot " + shot), std::string::npos) << printed;
  const fs::path spec = work_ / "show" / ("photo_" + shot + ".vg.json");
  ASSERT_TRUE(fs::exists(spec));
  EXPECT_TRUE(fs::exists(work_ / "show" / ("photo_" + shot + ".html")));
  std::ifstream in(spec);
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(testing_figures::Data(j, "corners").size(), static_cast<size_t>(corners));
  bool photo = false;
  for (const nlohmann::json& m : j["marks"]) photo = photo || m["type"] == "image";
  EXPECT_TRUE(photo) << "the photo is drawn under its corners";
  // Existing files are kept; an unknown shot names the run's shots.
  EXPECT_THROW(RunShow(args), std::invalid_argument);
  args.force = true;
  args.shot = "no-such-shot";
  try {
    RunShow(args);
    ADD_FAILURE() << "an unknown shot was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(shot.substr(0, 3)), std::string::npos) << e.what();
  }
}

TEST_F(PhotoSession, BoardsWithoutPoseAreEstimatedWithEverythingElse) {
  // The same folder with the boards' poses left out (SPEC 7): the corners are
  // points of boards without pose (X_known = false), estimated with
  // everything else; the records (known points) fix the reference frame.
  std::ofstream(photos_ / "targets_unknown.yaml")
      << "boards:\n"
         "  - {family: tag36h11, first_id: 0, rows: 6, cols: 8, tag_size: 0.06, spacing: 0.015}\n"
         "  - {family: tag36h11, first_id: 48, rows: 6, cols: 8, tag_size: 0.06, spacing: 0.015}\n"
         "  - {family: tag36h11, first_id: 96, rows: 6, cols: 8, tag_size: 0.06, spacing: 0.015}\n"
         "  - {family: tag36h11, first_id: 144, rows: 6, cols: 8, tag_size: 0.06, spacing: "
         "0.015}\n";
  std::ofstream(work_ / "photos_unknown.yaml")
      << "data:\n  records: records.csv\n  shots: photos/shots.csv\n"
         "  targets: photos/targets_unknown.yaml\n"
         "model:\n  kinematics: dh\n  effects: [radial_distortion, tangential_distortion]\n"
         "  intrinsics: fit\n"
         "fit:\n  sigmas: {edm_m: 1.0e-5, cam_m: 1.0e-5, pixel_px: 0.1}\n"
         "output: out_unknown\n";
  Progress progress(true);
  const PipelineResult r = RunPipeline(LoadRunSettings((work_ / "photos_unknown.yaml").string()),
                                       (work_ / "run_unknown").string(), &progress);
  EXPECT_EQ(r.photos.boards_without_pose, 4);
  ASSERT_FALSE(r.obs.pixels.empty());
  for (const PixelObservation& p : r.obs.pixels) EXPECT_FALSE(p.X_known);
  {
    // The figures of boards without pose: every corner's residual at the
    // board's estimated pose, none left unpredicted.
    SCOPED_TRACE("figures, boards without pose");
    testing_figures::CheckFiguresAgainstResidualFile(r);
    for (const ObservationResidual& o : r.calibration.residuals) {
      if (o.group == ObsGroup::kPixel) {
        EXPECT_TRUE(o.valid) << o.shot << " " << o.target;
      }
    }
  }

  // Unknown poses cost little: the same tolerances as the surveyed session
  // above, and both errors printed side by side.
  const CameraTool& cam = r.calibration.model.cams[0];
  const CameraTool& surveyed = result_->calibration.model.cams[0];
  const CameraTool& t = truth_->cams[0];
  std::printf(
      "fx error: surveyed boards %.3f px, unknown boards %.3f px; cx error %.3f / %.3f px\n",
      surveyed.intrinsics[0] - t.intrinsics[0], cam.intrinsics[0] - t.intrinsics[0],
      surveyed.intrinsics[2] - t.intrinsics[2], cam.intrinsics[2] - t.intrinsics[2]);
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(cam.intrinsics[i] / t.intrinsics[i], 1.0, 2e-4) << "intrinsic " << i;
  }
  for (int i = 2; i < 4; ++i) EXPECT_NEAR(cam.intrinsics[i], t.intrinsics[i], 1.0);

  // The boards land where the renderer put them: within 5 mm at 2-4 m (the
  // corners' sigma is ~0.1 px at f = 1000 px, 0.3 mm at 3 m; 5 mm is far
  // inside a wrong scale, frame or corner order).
  const TargetScene truth_boards = ReadTargets((photos_ / "truth_targets.yaml").string());
  // One estimate per board the photos show (a zoom-0 session this small may
  // not see every board).
  std::set<int> seen;
  for (const PixelObservation& p : r.obs.pixels) {
    for (const TagBoard& tb : truth_boards.boards) {
      if (tb.HasId(p.target)) seen.insert(tb.first_id);
    }
  }
  ASSERT_FALSE(seen.empty());
  ASSERT_EQ(r.calibration.model.boards.size(), seen.size());
  for (const EstimatedBoard& b : r.calibration.model.boards) {
    bool found = false;
    for (const TagBoard& tb : truth_boards.boards) {
      if (tb.first_id != b.board.first_id) continue;
      found = true;
      EXPECT_LT((b.pose.ToRigid().translation - tb.ref_from_board.translation).norm(), 5e-3)
          << "board " << b.board.first_id;
    }
    EXPECT_TRUE(found) << "board " << b.board.first_id;
  }
}

}  // namespace
}  // namespace rtscalib::app

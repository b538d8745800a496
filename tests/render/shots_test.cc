// Shot lists -> images and tables -> pixel observations.
#include "render/shots.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <opencv2/imgcodecs.hpp>

#include "tests/render/render_fixture.h"

namespace rtscalib::render {
namespace {

namespace fs = std::filesystem;
using testing::AimAt;
using testing::EnsureDisplay;
using testing::FrontBoard;
using testing::SceneOf;
using testing::TestCamera;

// A fresh folder under the build tree, removed at the end.
class TempDir {
 public:
  explicit TempDir(const std::string& name)
      : path_(fs::path(RTSCALIB_BINARY_DIR) / "tests" / "render_tmp" /
              (name + "-" + std::to_string(::getpid()))) {
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  std::string operator/(const std::string& sub) const { return (path_ / sub).string(); }
  std::string str() const { return path_.string(); }

 private:
  fs::path path_;
};

std::vector<std::string> Lines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> out;
  std::string line;
  while (std::getline(in, line)) out.push_back(line);
  return out;
}

std::vector<Shot> MakeShots(const TargetScene& scene, int n) {
  const CameraTool cam = TestCamera(true);
  std::vector<Shot> shots;
  for (int i = 0; i < n; ++i) {
    Shot s;
    s.face = 1 + i % 2;
    s.zoom = i % 3;
    s.phi = 0.1 * i;
    s.theta = 1.5 + 0.01 * i;
    s.id = "s" + std::to_string(i);
    s.cam = cam;
    s.ref_from_cam = AimAt(Eigen::Vector3d(0.05 * i, 0, 0), scene.boards[0].CentreInRef(),
                           400 + 60 * i, 300 + 40 * i, 0.1 * i, cam);
    shots.push_back(s);
  }
  return shots;
}

TEST(ShotsTest, RenderInWorkersThenDetect) {
  EnsureDisplay();
  const TargetScene scene = SceneOf(FrontBoard(3, 4, 2.0));
  const std::vector<Shot> shots = MakeShots(scene, 5);
  TempDir dir("workers");
  RenderShotsOptions options;
  options.out_dir = dir.str();
  options.jobs = 2;
  const RenderShotsResult r = RenderShots(scene, shots, options);
  EXPECT_EQ(r.rendered, 5);
  for (const Shot& s : shots) EXPECT_TRUE(fs::exists(dir / (s.id + ".png"))) << s.id;

  const std::vector<std::string> table = Lines(dir / "shots.csv");
  ASSERT_EQ(table.size(), 6u);
  EXPECT_EQ(table[0], "index,shot,face,zoom,phi,theta,image");
  EXPECT_EQ(table[1].substr(0, 9), "0,s0,1,0,");
  const std::vector<std::string> exact = Lines(dir / "exact.csv");
  EXPECT_EQ(exact[0], "face,zoom,phi,theta,shot,target,corner,X,Y,Z,u,v,status");
  EXPECT_EQ(static_cast<int>(exact.size()) - 1, r.exact_corners);
  EXPECT_EQ(r.exact_corners, 5 * 12 * 4);  // every corner of every shot in view

  DetectShotsOptions dopt;
  dopt.jobs = 2;
  const DetectShotsResult d = DetectShots(scene, shots, dir.str(), dopt);
  ASSERT_EQ(d.stats.size(), 5u);
  EXPECT_EQ(d.total.expected, 60);
  EXPECT_EQ(d.total.found, 60);
  EXPECT_EQ(d.pixels.size(), 240u);
  EXPECT_LE(d.total.rms_error_px, 0.1);
  // Observations carry the shot's metadata and the exact corner positions.
  const PixelObservation& p = d.pixels.front();
  EXPECT_EQ(p.shot, "s0");
  EXPECT_EQ(p.face, 1);
  EXPECT_EQ(p.zoom, 0);
  const auto corners = scene.AllCorners();
  bool matched = false;
  for (const TargetCorner& c : corners) {
    if (c.target == p.target && c.corner == p.corner) matched = (c.X - p.X).norm() < 1e-12;
  }
  EXPECT_TRUE(matched);
}

// ChArUco and chessboards through the same shots: one exact.csv row and one
// observation (corner 0) per inner corner, chessboards oriented by the
// shot's face.
TEST(ShotsTest, PointBoardsRenderAndDetect) {
  EnsureDisplay();
  TargetScene scene;
  TagBoard charuco;
  charuco.kind = BoardKind::kCharuco;
  charuco.family = "DICT_5X5_50";
  charuco.first_id = 100;
  charuco.rows = 5;
  charuco.cols = 7;
  charuco.square_size = 0.04;
  charuco.marker_size = 0.03;
  charuco.ref_from_board.translation = Eigen::Vector3d(-0.3, -0.1, 0.6);
  TagBoard chessboard;
  chessboard.kind = BoardKind::kChessboard;
  chessboard.family = "chessboard";
  chessboard.first_id = 200;
  chessboard.rows = 6;
  chessboard.cols = 9;
  chessboard.square_size = 0.025;
  chessboard.ref_from_board.translation = Eigen::Vector3d(0.03, -0.075, 0.6);
  scene.boards = {charuco, chessboard};
  const CameraTool cam = TestCamera(true);
  std::vector<Shot> shots;
  for (int face : {1, 2}) {
    Shot s;
    s.face = face;
    s.id = "f" + std::to_string(face);
    s.cam = cam;
    s.ref_from_cam = AimAt(Eigen::Vector3d(0.02, 0, 0), Eigen::Vector3d(-0.02, 0, 0.6), 640, 480,
                           face == 2 ? M_PI + 0.03 : 0.03, cam);
    shots.push_back(s);
  }
  TempDir dir("point_boards");
  RenderShotsOptions options;
  options.out_dir = dir.str();
  options.progress = false;
  const RenderShotsResult r = RenderShots(scene, shots, options);
  EXPECT_EQ(r.exact_corners, 2 * (24 + 40));
  const std::vector<std::string> exact = Lines(dir / "exact.csv");
  for (size_t i = 1; i < exact.size(); ++i) {
    EXPECT_NE(exact[i].find(",0,"), std::string::npos) << exact[i];
    EXPECT_NE(exact[i].find(",visible"), std::string::npos) << exact[i];
  }
  DetectShotsOptions dopt;
  dopt.progress = false;
  const DetectShotsResult d = DetectShots(scene, shots, dir.str(), dopt);
  EXPECT_EQ(d.total.expected, 2 * (24 + 40));
  EXPECT_EQ(d.total.found, d.total.expected);
  EXPECT_EQ(d.total.corners_kept, d.total.found);
  ASSERT_EQ(d.pixels.size(), static_cast<size_t>(d.total.found));
  for (const PixelObservation& p : d.pixels) EXPECT_EQ(p.corner, 0);
  // Measured 0.075 px RMS (max 0.12 px); a chessboard numbered from the
  // wrong end would be whole squares off and dropped as mismatched.
  EXPECT_EQ(d.total.mismatched, 0);
  EXPECT_LE(d.total.rms_error_px, 0.1);
  std::printf("point boards through DetectShots: %d of %d corners, RMS %.4f px, max %.4f px\n",
              d.total.found, d.total.expected, d.total.rms_error_px, d.total.max_error_px);
}

TEST(ShotsTest, ShardsMergeIntoTheUnshardedOutput) {
  EnsureDisplay();
  const TargetScene scene = SceneOf(FrontBoard(2, 3, 2.0));
  const std::vector<Shot> shots = MakeShots(scene, 5);
  TempDir all("all"), a("shard0"), b("shard1"), merged("merged");
  RenderShotsOptions options;
  options.progress = false;
  options.out_dir = all.str();
  RenderShots(scene, shots, options);
  options.num_shards = 2;
  options.shard = 0;
  options.out_dir = a.str();
  EXPECT_EQ(RenderShots(scene, shots, options).rendered, 3);
  options.shard = 1;
  options.out_dir = b.str();
  EXPECT_EQ(RenderShots(scene, shots, options).rendered, 2);
  EXPECT_TRUE(fs::exists(b / "shots.shard-1-of-2.csv"));

  EXPECT_THROW(MergeShards({a.str()}, merged.str()), std::runtime_error);  // shard 1 missing
  MergeShards({b.str(), a.str()}, merged.str());
  EXPECT_EQ(Lines(merged / "shots.csv"), Lines(all / "shots.csv"));
  EXPECT_EQ(Lines(merged / "exact.csv"), Lines(all / "exact.csv"));
  for (const Shot& s : shots) {
    const cv::Mat x = cv::imread(merged / (s.id + ".png"), cv::IMREAD_GRAYSCALE);
    const cv::Mat y = cv::imread(all / (s.id + ".png"), cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(x.empty()) << s.id;
    EXPECT_EQ(cv::norm(x, y, cv::NORM_INF), 0.0) << s.id;  // rendering is deterministic
  }
}

TEST(ShotsTest, InvalidInputIsRejected) {
  const TargetScene scene = SceneOf(FrontBoard());
  std::vector<Shot> shots = MakeShots(scene, 2);
  shots[1].id = "s0";
  EXPECT_NE(CheckShots(shots), "");
  shots[1].id = "../escape";
  EXPECT_NE(CheckShots(shots), "");
  shots[1].id = "ok-1.b";
  EXPECT_EQ(CheckShots(shots), "");
  RenderShotsOptions options;
  EXPECT_NE(options.Check(), "");  // no out_dir
  options.out_dir = "x";
  options.shard = 2;
  options.num_shards = 2;
  EXPECT_NE(options.Check(), "");
  EXPECT_THROW(RenderShots(scene, shots, options), std::invalid_argument);
  EXPECT_THROW(DetectShots(scene, shots, "/nonexistent-folder", DetectShotsOptions()),
               std::runtime_error);
}

}  // namespace
}  // namespace rtscalib::render

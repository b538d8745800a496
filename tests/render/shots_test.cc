// Shot lists -> images and tables -> pixel observations.
#include "render/shots.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <csignal>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <opencv2/imgcodecs.hpp>

#include "libcalib/io/safe_write.h"
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

// Shots of two placements (SPEC 7.1): each sees its own scene, and
// shots.csv gets a `placement` column; the exact tables follow the scene.
TEST(ShotsTest, PlacementsSeeTheirOwnScene) {
  EnsureDisplay();
  const TargetScene near = SceneOf(FrontBoard(3, 4, 2.0));
  const TargetScene far = SceneOf(FrontBoard(3, 4, 3.0));
  std::vector<Shot> shots = MakeShots(near, 2);
  shots[1].placement = "far";
  shots[0].placement = "near";
  TempDir dir("placements");
  RenderShotsOptions options;
  options.out_dir = dir.str();
  RenderShots(PlacedScenes{{"near", near}, {"far", far}}, shots, options);
  const std::vector<std::string> table = Lines(dir / "shots.csv");
  ASSERT_EQ(table.size(), 3u);
  EXPECT_EQ(table[0], "index,shot,face,zoom,phi,theta,image,placement");
  EXPECT_EQ(table[1].substr(table[1].size() - 5), ",near");
  EXPECT_EQ(table[2].substr(table[2].size() - 4), ",far");
  // The far shot's exact corners are the far board's (1 m further away).
  bool far_rows = false;
  for (const std::string& line : Lines(dir / "exact.csv")) {
    if (line.find(",s1,") == std::string::npos) continue;
    far_rows = true;
    std::stringstream cells(line);
    std::string cell;
    std::vector<std::string> v;
    while (std::getline(cells, cell, ',')) v.push_back(cell);
    const Eigen::Vector3d x(std::stod(v[7]), std::stod(v[8]), std::stod(v[9]));
    bool on_far = false;
    for (const TargetCorner& c : far.AllCorners()) on_far = on_far || (c.X - x).norm() < 1e-9;
    EXPECT_TRUE(on_far) << line;
  }
  EXPECT_TRUE(far_rows);
  shots[1].placement = "elsewhere";
  EXPECT_THROW(RenderShots(PlacedScenes{{"near", near}}, shots, options), std::invalid_argument);
}

// A full disk (a file size limit makes writes fail the same way, even as
// root): a WriteError naming the file that could not be written, from this
// process and from the worker processes alike; never a half-written photo.
TEST(ShotsTest, AFullDiskIsAWriteErrorNamingTheFile) {
  EnsureDisplay();
  const TargetScene scene = SceneOf(FrontBoard(3, 4, 2.0));
  const std::vector<Shot> shots = MakeShots(scene, 3);
  // How large the tables and the photos are, to put the limit between them.
  std::uintmax_t tables = 0, smallest_photo = ~std::uintmax_t{0};
  {
    TempDir dir("sizes");
    RenderShotsOptions options;
    options.out_dir = dir.str();
    RenderShots(scene, shots, options);
    tables = std::max(fs::file_size(dir / "shots.csv"), fs::file_size(dir / "exact.csv"));
    for (const Shot& s : shots) {
      smallest_photo = std::min(smallest_photo, fs::file_size(dir / (s.id + ".png")));
    }
  }
  ASSERT_LT(tables, smallest_photo) << "the test needs photos larger than the tables";
  for (const int jobs : {1, 2}) {
    TempDir dir("full" + std::to_string(jobs));
    RenderShotsOptions options;
    options.out_dir = dir.str();
    options.jobs = jobs;
    rlimit old{};
    getrlimit(RLIMIT_FSIZE, &old);
    const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);
    rlimit lim = old;
    lim.rlim_cur = (tables + smallest_photo) / 2;  // the tables fit, no photo does
    setrlimit(RLIMIT_FSIZE, &lim);
    try {
      RenderShots(scene, shots, options);
      ADD_FAILURE() << "no WriteError with jobs " << jobs;
    } catch (const WriteError& e) {
      EXPECT_NE(e.path.find(dir.str()), std::string::npos) << e.what();
      EXPECT_NE(e.path.find(".png"), std::string::npos) << e.what();
    }
    setrlimit(RLIMIT_FSIZE, &old);
    std::signal(SIGXFSZ, old_handler);
    for (const Shot& s : shots) EXPECT_FALSE(fs::exists(dir / (s.id + ".png"))) << s.id;
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

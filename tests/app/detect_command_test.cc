// `rtscalib detect` in-process: a synthesized photo of one posed tag (the
// photo synthesis and the corner accuracy are tested in tests/detect), the
// command's files and its refusal to overwrite them.
#include <gtest/gtest.h>

#include <unistd.h>
#include <filesystem>
#include <fstream>

#include <opencv2/imgcodecs.hpp>

#include "app/commands.h"
#include "libcalib/io/records.h"
#include "tests/detect/synthetic_photo.h"

namespace rtscalib {
namespace {

namespace fs = std::filesystem;

TEST(DetectCommandTest, WritesPixelsAndSummaryAndRefusesToOverwrite) {
  const fs::path dir =
      fs::path(::testing::TempDir()) / ("rtscalib_detect_command_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir / "photos");
  // One 0.1 m tag at 600 px/m, posed 2 m along +z.
  std::ofstream(dir / "targets.yaml") << "boards:\n"
                                         "  - {family: tag36h11, first_id: 5, rows: 1, cols: 1,\n"
                                         "     tag_size: 0.1, spacing: 0.02,\n"
                                         "     pose: {euler: [0, 0, 0], t: [0, 0, 2]}}\n";
  TagBoard board;
  board.first_id = 5;
  board.rows = board.cols = 1;
  board.tag_size = 0.1;
  const Eigen::Matrix3d h =
      detect::testing::MakeHomography(0.1, Eigen::Vector2d(80.3, 70.6), 600, 0.4);
  const cv::Mat coverage =
      detect::testing::RenderCoverage(detect::testing::PrintBoard(board), h, 160, 140);
  ASSERT_TRUE(
      cv::imwrite((dir / "photos" / "p1.png").string(),
                  detect::testing::ToPixels(coverage, CV_8UC1, cv::Scalar(20), cv::Scalar(220))));
  std::ofstream(dir / "shots.csv") << "face,zoom,phi,theta,image\n1,0,0.1,1.4,photos/p1.png\n";

  app::DetectArgs args;
  args.shots = (dir / "shots.csv").string();
  args.targets = (dir / "targets.yaml").string();
  args.out = (dir / "pixels.csv").string();
  args.quiet = true;
  ASSERT_EQ(app::RunDetect(args), 0);
  ASSERT_TRUE(fs::exists(args.out + ".summary.csv"));
  // A posed board: X, Y, Z filled, so the SPEC 3 reader takes the file; the
  // width/height columns give the image size (SPEC 7).
  const PixelsFile pixels = ReadPixels(args.out);
  ASSERT_EQ(pixels.pixels.size(), 4u);
  EXPECT_TRUE(pixels.notes.empty());
  ASSERT_EQ(pixels.image_sizes.size(), 1u);
  EXPECT_GT(pixels.image_sizes.begin()->second.width, 0);
  for (int k = 0; k < 4; ++k) {
    const PixelObservation& p = pixels.pixels[k];
    EXPECT_EQ(p.shot, "p1");
    EXPECT_EQ(p.target, 5);
    EXPECT_EQ(p.corner, k);
    EXPECT_EQ(p.X, board.CornersInBoard(0)[k] + Eigen::Vector3d(0, 0, 2));
    const Eigen::Vector2d exact = detect::testing::Project(h, board.CornersInBoard(0)[k].head<2>());
    // tests/detect/detector_test.cc: kCornerTolPx.
    EXPECT_LT((p.uv - exact).norm(), 0.05) << "corner " << k;
  }
  EXPECT_THROW(app::RunDetect(args), std::runtime_error);
  args.force = true;
  EXPECT_EQ(app::RunDetect(args), 0);

  // --angle-unit deg: shots.csv in degrees, pixels.csv written in degrees too
  // (the config that reads the shots with data.angle_unit: deg reads them).
  std::ofstream(dir / "shots_deg.csv") << "face,zoom,phi,theta,image\n1,0,45,90,photos/p1.png\n";
  args.shots = (dir / "shots_deg.csv").string();
  args.angle_unit = "deg";
  ASSERT_EQ(app::RunDetect(args), 0);
  const PixelsFile deg = ReadPixels(args.out, AngleUnit::kDeg);
  ASSERT_EQ(deg.pixels.size(), 4u);
  EXPECT_EQ(deg.pixels[0].phi, M_PI / 4);  // 45 deg and 90 deg are exact (angle_unit.h)
  EXPECT_EQ(deg.pixels[0].theta, M_PI / 2);
  std::ifstream written(args.out);
  std::string header, row;
  std::getline(written, header);
  std::getline(written, row);
  EXPECT_EQ(row.rfind("1,0,45,90,p1,", 0), 0u) << row;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rtscalib

// `rtscalib detect` in-process: a synthesized photo of one posed tag (the
// photo synthesis and the corner accuracy are tested in tests/detect), the
// command's files and its refusal to overwrite them.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <unistd.h>
#include <filesystem>
#include <fstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "app/commands.h"
#include "app/photo_session.h"
#include "libcalib/text/errors.h"
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

// Bad photos and boards are InputErrors naming the file and the shots.csv
// line or the targets key, never OpenCV's internal errors: a JPEG cut in
// half (OpenCV decodes it with grey rows and a warning on stderr only), a
// PNG whose header claims 100000 x 100000 pixels (CV_IO_MAX_IMAGE_PIXELS),
// a chessboard of 3 rows (findChessboardCornersSB takes no fewer than 3 x 3
// inner corners).
TEST(DetectCommandTest, BadPhotosAndBoardsNameTheirFileAndLine) {
  const fs::path dir = fs::path(::testing::TempDir()) /
                       ("rtscalib_detect_command_bad_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  cv::Mat img(200, 300, CV_8UC1, cv::Scalar(200));
  cv::rectangle(img, cv::Rect(50, 40, 100, 80), cv::Scalar(20), cv::FILLED);
  std::vector<uint8_t> jpeg;
  cv::imencode(".jpg", img, jpeg);
  std::ofstream(dir / "whole.jpg", std::ios::binary)
      .write(reinterpret_cast<const char*>(jpeg.data()), static_cast<std::streamsize>(jpeg.size()));
  std::ofstream(dir / "half.jpg", std::ios::binary)
      .write(reinterpret_cast<const char*>(jpeg.data()), static_cast<std::streamsize>(jpeg.size() / 2));
  std::vector<uint8_t> png;
  cv::imencode(".png", img, png);
  png = detect::testing::PngClaimingSize(png, 100000, 100000);
  std::ofstream(dir / "huge.png", std::ios::binary)
      .write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  std::ofstream(dir / "targets.yaml") << "boards:\n"
                                         "  - {family: tag36h11, first_id: 0, rows: 1, cols: 1,\n"
                                         "     tag_size: 0.1, spacing: 0.02}\n";

  app::DetectArgs args;
  args.targets = (dir / "targets.yaml").string();
  args.out = (dir / "pixels.csv").string();
  args.quiet = true;
  args.force = true;
  struct Case {
    const char* image;
    const char* says;
  };
  for (const Case& c : {Case{"half.jpg", "is damaged"}, Case{"huge.png", "100000 x 100000"}}) {
    const std::string shots = (dir / (std::string(c.image) + ".csv")).string();
    std::ofstream(shots) << "face,zoom,phi,theta,image\n1,0,,,whole.jpg\n1,0,,," << c.image
                         << "\n";
    args.shots = shots;
    try {
      app::RunDetect(args);
      ADD_FAILURE() << c.image << ": expected an InputError";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file, shots);
      EXPECT_EQ(e.line, 3) << c.image;
      EXPECT_EQ(e.column, "image");
      EXPECT_THAT(e.got, ::testing::HasSubstr(c.image));
      EXPECT_THAT(e.got, ::testing::HasSubstr(c.says));
    }
  }
  std::ofstream(dir / "chess.yaml") << "boards:\n"
                                       "  - {type: chessboard, first_id: 0, rows: 3, cols: 7,\n"
                                       "     square_size: 0.03}\n";
  args.targets = (dir / "chess.yaml").string();
  args.shots = (dir / "half.jpg.csv").string();
  try {
    app::RunDetect(args);
    ADD_FAILURE() << "expected an InputError for rows: 3";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file, args.targets);
    EXPECT_EQ(e.key, "boards[0].rows");
    EXPECT_EQ(e.line, 2);
  }
  fs::remove_all(dir);
}

// The log speaks of what was found (the photo session's line): a session of
// chessboards finds corners, not tags, and has no libapriltag to compare
// with; a session of tags says how many came from their neighbours.
TEST(DetectCommandTest, TheSessionLineNamesWhatWasFound) {
  app::PhotoSessionSummary chess;
  chess.photos.resize(13);
  chess.point_words = "chessboard corners";
  chess.point_corners = 702;
  chess.tags = 702;
  chess.corners = 702;
  chess.images_per_second = 3.2;
  const std::string line = app::PhotoSessionLine(chess);
  EXPECT_THAT(line, ::testing::HasSubstr("13 photos: 702 chessboard corners"));
  EXPECT_THAT(line, ::testing::Not(::testing::HasSubstr("tag")));
  EXPECT_THAT(line, ::testing::Not(::testing::HasSubstr("libapriltag")));

  app::PhotoSessionSummary grid;
  grid.photos.resize(30);
  grid.tag_boards = true;
  grid.apriltags = 1046;
  grid.tags = 1046;
  grid.corners = 4184;
  grid.from_neighbours = 28;
  grid.refined_corners = 4072;
  grid.shift_rms_px = 0.25;
  grid.shift_max_px = 1.7;
  const std::string tags = app::PhotoSessionLine(grid);
  EXPECT_THAT(tags, ::testing::HasSubstr("1046 tags (4184 corners; 28 of the tags grown from their "
                                         "neighbours)"));
  EXPECT_THAT(tags, ::testing::HasSubstr("refined vs libapriltag corners RMS 0.250 px"));
}

}  // namespace
}  // namespace rtscalib

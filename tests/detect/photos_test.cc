// Photos -> pixels.csv as `rtscalib detect` runs it: shots.csv and
// targets.yaml on disk, synthesized photos (synthetic_photo.h), the files it
// writes read back.
#include "detect/photos.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <unistd.h>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "detect/tag_family.h"
#include "libcalib/io/csv.h"
#include "libcalib/text/errors.h"
#include "libcalib/io/records.h"
#include "libcalib/io/targets_io.h"
#include "tests/detect/synthetic_photo.h"

namespace rtscalib::detect {
namespace {

using ::testing::HasSubstr;

class TempDir {
 public:
  TempDir() {
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = std::filesystem::path(::testing::TempDir()) /
            ("rtscalib_detect_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  std::string Path(const std::string& name) const { return (path_ / name).string(); }
  std::string Write(const std::string& name, const std::string& text) const {
    std::ofstream(path_ / name, std::ios::binary) << text;
    return Path(name);
  }

 private:
  std::filesystem::path path_;
};

// Two boards: A (ids 0..11, 3 x 4, no pose) and B (ids 20..25, 2 x 3, with a
// pose). In the photo, A is seen through a homography that puts its right
// column half outside the image (a partial board), B below it.
constexpr const char* kTargets =
    "boards:\n"
    "  - {family: tag36h11, first_id: 0, rows: 3, cols: 4, tag_size: 0.06, spacing: 0.015}\n"
    "  - {family: tag36h11, first_id: 20, rows: 2, cols: 3, tag_size: 0.04, spacing: 0.01,\n"
    "     pose: {euler: [0.1, 0.2, -0.3], t: [1, 2, 3]}}\n";

struct Scene {
  TargetScene targets;
  Eigen::Matrix3d image_from_a, image_from_b;  // board plane [m] -> pixels
};

Scene MakeScene(const TempDir& dir) {
  Scene s;
  const std::map<std::string, int> codes = FamilyCodeCounts();
  s.targets = ReadTargets(dir.Write("targets.yaml", kTargets), &codes);
  // 0.285 m wide board A at 1400 px/m, turned by 180 degrees (an upside-down
  // board: the corner order must follow the tags), its first column cut by
  // the image's right edge.
  s.image_from_a =
      testing::MakeHomography(0.285, Eigen::Vector2d(265.4, 172.7), 1400.0, M_PI, 0.2, -0.1);
  // Recentre: MakeHomography centres a square of side 0.285; board A is 0.285
  // x 0.21, so shift its plane by half the difference in y.
  Eigen::Matrix3d shift = Eigen::Matrix3d::Identity();
  shift(1, 2) = (0.285 - 0.21) / 2;
  s.image_from_a = s.image_from_a * shift;
  s.image_from_b =
      testing::MakeHomography(0.14, Eigen::Vector2d(230.2, 505.9), 2100.0, 0.12, -0.3, 0.2);
  return s;
}

cv::Mat MakePhoto(const Scene& s, int width, int height) {
  const cv::Mat a = testing::RenderCoverage(testing::PrintBoard(s.targets.boards[0]),
                                            s.image_from_a, width, height);
  const cv::Mat b = testing::RenderCoverage(testing::PrintBoard(s.targets.boards[1]),
                                            s.image_from_b, width, height);
  // Both boards on one white background: ink where either prints ink.
  cv::Mat coverage = cv::min(a, b);
  return testing::ToPixels(coverage, CV_16UC1, cv::Scalar(2000), cv::Scalar(50000));
}

TEST(DetectPhotosTest, BoardWithoutPoseGivesItsCornersWithEmptyXyz) {
  TempDir dir;
  const Scene s = MakeScene(dir);
  ASSERT_TRUE(cv::imwrite(dir.Path("p1.png"), MakePhoto(s, 460, 620)));
  dir.Write("shots.csv",
            "# three photos of one scene: 16-bit PNG, 16-bit TIFF, 8-bit colour JPEG\n"
            "image,face,zoom,phi,theta\n"
            "p1.png,1,0,0.5,1.5\n"
            "p2.tif,2,0,3.6,4.7\n"
            "p3.jpg,1,0,0.7,1.4\n");
  const cv::Mat png = cv::imread(dir.Path("p1.png"), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(png.type(), CV_16UC1);
  ASSERT_TRUE(cv::imwrite(dir.Path("p2.tif"), png));
  cv::Mat grey8, colour;
  png.convertTo(grey8, CV_8U, 1.0 / 256);
  cv::cvtColor(grey8, colour, cv::COLOR_GRAY2BGR);
  ASSERT_TRUE(cv::imwrite(dir.Path("p3.jpg"), colour, {cv::IMWRITE_JPEG_QUALITY, 95}));
  const ShotsFile shots = ReadShots(dir.Path("shots.csv"));
  for (int jobs : {1, 2}) {
    PhotoDetectionOptions options;
    options.jobs = jobs;
    options.progress = false;
    const PhotoDetectionResult result = DetectPhotos(shots, s.targets, options);
    ASSERT_EQ(result.photos.size(), 3u);
    EXPECT_TRUE(result.warnings.empty());
    const std::string out = dir.Path("pixels.csv");
    WritePixels(out, PixelObservationsOf(shots, s.targets, result), shots.angle_unit,
                ImageSizesOf(shots, result));
    WriteDetectionSummary(out + ".summary.csv", shots, result);

    // The exact corners of every tag fully inside the image.
    std::map<std::pair<int, int>, Eigen::Vector2d> exact;
    for (int b = 0; b < 2; ++b) {
      const TagBoard& board = s.targets.boards[b];
      const Eigen::Matrix3d& h = b == 0 ? s.image_from_a : s.image_from_b;
      for (int i = 0; i < board.NumTags(); ++i) {
        const auto corners = board.CornersInBoard(i);
        bool inside = true;
        std::array<Eigen::Vector2d, 4> uv;
        for (int k = 0; k < 4; ++k) {
          uv[k] = testing::Project(h, corners[k].head<2>());
          inside = inside && uv[k].x() > 10 && uv[k].x() < 450 && uv[k].y() > 10 && uv[k].y() < 610;
        }
        if (!inside) continue;
        for (int k = 0; k < 4; ++k) exact[{board.first_id + i, k}] = uv[k];
      }
    }
    ASSERT_GE(exact.size(), 4u * 12) << "the scene must show most tags";
    ASSERT_LT(exact.size(), 4u * 18) << "board A must be cut by the image edge";

    const CsvTable t = CsvTable::Read(out, {{"face", "zoom", "phi", "theta", "shot", "target",
                                             "corner", "X", "Y", "Z", "u", "v", "width", "height"},
                                            {}});
    std::map<std::string, std::set<std::pair<int, int>>> seen;
    std::map<std::string, double> max_error;
    for (int row = 0; row < t.NumRows(); ++row) {
      const std::string shot = t.Text(row, "shot");
      const int target = static_cast<int>(t.Integer(row, "target"));
      const int corner = static_cast<int>(t.Integer(row, "corner"));
      seen[shot].insert({target, corner});
      EXPECT_EQ(t.Integer(row, "width"), 460);
      EXPECT_EQ(t.Integer(row, "height"), 620);
      EXPECT_EQ(t.Integer(row, "face"), shot == "p2" ? 2 : 1);
      const auto it = exact.find({target, corner});
      ASSERT_NE(it, exact.end()) << "unexpected tag " << target << " corner " << corner;
      const Eigen::Vector2d uv(t.Number(row, "u"), t.Number(row, "v"));
      // Tolerance: see tests/detect/detector_test.cc (kCornerTolPx); JPEG's
      // 8 x 8 block quantisation at quality 95 moves edges by a little more
      // (measured: max 0.008 px PNG/TIFF, 0.019 px JPEG).
      max_error[shot] = std::max(max_error[shot], (uv - it->second).norm());
      EXPECT_LT((uv - it->second).norm(), shot == "p3" ? 0.1 : 0.05)
          << shot << " tag " << target << " corner " << corner;
      if (target < 20) {
        EXPECT_TRUE(t.Empty(row, "X") && t.Empty(row, "Y") && t.Empty(row, "Z"));
      } else {
        const TagBoard& b = s.targets.boards[1];
        const Eigen::Vector3d X = b.ref_from_board * b.CornersInBoard(target - 20)[corner];
        EXPECT_EQ(t.Number(row, "X"), X.x());
        EXPECT_EQ(t.Number(row, "Y"), X.y());
        EXPECT_EQ(t.Number(row, "Z"), X.z());
      }
    }
    std::set<std::pair<int, int>> all;
    for (const auto& [key, uv] : exact) all.insert(key);
    EXPECT_EQ(seen["p1"], all);
    EXPECT_EQ(seen["p2"], all);
    EXPECT_EQ(seen["p3"], all);
    if (jobs == 1) {
      std::printf("max corner error: PNG %.4f px, TIFF %.4f px, JPEG %.4f px\n", max_error["p1"],
                  max_error["p2"], max_error["p3"]);
    }

    const CsvTable summary = CsvTable::Read(
        out + ".summary.csv",
        {{"shot", "width", "height", "tags_found", "tags_of_boards", "bit_depth", "shift_rms_px"},
         {}});
    ASSERT_EQ(summary.NumRows(), 3);
    EXPECT_EQ(summary.Integer(0, "width"), 460);
    EXPECT_EQ(summary.Integer(0, "height"), 620);
    EXPECT_EQ(summary.Integer(0, "bit_depth"), 16);
    EXPECT_EQ(summary.Integer(2, "bit_depth"), 8);
    EXPECT_EQ(summary.Integer(0, "tags_found"), static_cast<long long>(all.size() / 4));
    EXPECT_EQ(summary.Integer(0, "tags_of_boards"), 18);
    // Refined vs libapriltag corners on a sharp photo: ~0.1-0.3 px, never a
    // whole pixel.
    EXPECT_LT(summary.Number(0, "shift_rms_px"), 0.5);

    // SPEC 3: the pixels.csv reader ignores the extra columns with a note
    // (boards with a pose only: rows with empty X, Y, Z are for the joint fit).
    std::ofstream posed(dir.Path("posed.csv"));
    std::ifstream in(out);
    std::string line;
    while (std::getline(in, line)) {
      if (line.rfind("face", 0) == 0 || line.find(",,,") == std::string::npos)
        posed << line << "\n";
    }
    posed.close();
    const PixelsFile pixels = ReadPixels(dir.Path("posed.csv"));
    EXPECT_EQ(pixels.pixels.size(), 3u * 4 * 6);
    EXPECT_TRUE(pixels.notes.empty());  // width, height are the image size (SPEC 7)
    ASSERT_EQ(pixels.image_sizes.size(), 1u);
    EXPECT_GT(pixels.image_sizes.begin()->second.width, 0);
  }
}

TEST(DetectPhotosTest, PhotoWithoutTagsIsAWarningNamingLineAndImage) {
  TempDir dir;
  const Scene s = MakeScene(dir);
  ASSERT_TRUE(cv::imwrite(dir.Path("blank.png"), cv::Mat(240, 320, CV_8UC3, cv::Scalar::all(200))));
  dir.Write("shots.csv", "face,zoom,phi,theta,image\n# comment\n1,0,0,1.5,blank.png\n");
  PhotoDetectionOptions options;
  options.progress = false;
  const PhotoDetectionResult r = DetectPhotos(ReadShots(dir.Path("shots.csv")), s.targets, options);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_THAT(r.warnings[0], HasSubstr(dir.Path("shots.csv") + ":3: image blank.png"));
  EXPECT_THAT(r.warnings[0], HasSubstr("no target of the boards found"));
  EXPECT_EQ(r.photos[0].width, 320);
  EXPECT_EQ(r.photos[0].channels, 3);
}

TEST(DetectPhotosTest, TagsOfOtherBoardsOrFamiliesAreDropped) {
  TempDir dir;
  const Scene s = MakeScene(dir);
  ASSERT_TRUE(cv::imwrite(dir.Path("p.png"), MakePhoto(s, 460, 620)));
  dir.Write("shots.csv", "face,zoom,phi,theta,image\n1,0,0,1.5,p.png\n");
  // Only board B is declared; board A's tags are in the photo but not kept.
  TargetScene only_b;
  only_b.boards = {s.targets.boards[1]};
  PhotoDetectionOptions options;
  options.progress = false;
  const PhotoDetectionResult r = DetectPhotos(ReadShots(dir.Path("shots.csv")), only_b, options);
  ASSERT_EQ(r.photos[0].tags.size(), 6u);
  for (const DetectedTag& t : r.photos[0].tags) EXPECT_GE(t.id, 20);
  EXPECT_GE(r.photos[0].not_on_boards, 8);
}

TEST(DetectPhotosTest, SizeDifferingWithinAZoomNamesBothPhotos) {
  TempDir dir;
  const Scene s = MakeScene(dir);
  ASSERT_TRUE(cv::imwrite(dir.Path("a.png"), cv::Mat(240, 320, CV_8UC1, cv::Scalar(200))));
  ASSERT_TRUE(cv::imwrite(dir.Path("b.png"), cv::Mat(240, 320, CV_8UC1, cv::Scalar(200))));
  ASSERT_TRUE(cv::imwrite(dir.Path("c.png"), cv::Mat(480, 640, CV_8UC1, cv::Scalar(200))));
  // c has another zoom than a: fine; b and c share zoom 1: an error.
  dir.Write("shots.csv",
            "face,zoom,phi,theta,image\n1,0,0,1.5,a.png\n1,1,0,1.5,c.png\n1,1,0,1.5,b.png\n");
  PhotoDetectionOptions options;
  options.progress = false;
  try {
    DetectPhotos(ReadShots(dir.Path("shots.csv")), s.targets, options);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line, 4);
    EXPECT_EQ(e.column, "image");
    EXPECT_THAT(e.expected,
                HasSubstr("640x480 px like every photo of zoom 1 (line 3, " + dir.Path("c.png")));
    EXPECT_THAT(e.got, HasSubstr(dir.Path("b.png") + ": 320x240 px"));
  }
}

TEST(DetectPhotosTest, UnreadableImageNamesLineAndPath) {
  TempDir dir;
  const Scene s = MakeScene(dir);
  dir.Write("broken.png", "not a png");
  dir.Write("shots.csv", "face,zoom,phi,theta,image\n1,0,0,1.5,broken.png\n");
  PhotoDetectionOptions options;
  options.progress = false;
  try {
    DetectPhotos(ReadShots(dir.Path("shots.csv")), s.targets, options);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line, 2);
    EXPECT_EQ(e.column, "image");
    EXPECT_THAT(e.got, HasSubstr(dir.Path("broken.png")));
    EXPECT_THAT(e.expected, HasSubstr("PNG, JPEG or TIFF"));
  }
}

}  // namespace
}  // namespace rtscalib::detect

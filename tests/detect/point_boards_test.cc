// ChArUco and chessboards through OpenCV's detectors (detect/point_boards.h):
// photos synthesized exactly (synthetic_photo.h, SPEC 2 pixels) from the
// printed board, the detected inner corners against their exact images, the
// target numbering (first_id + k, k = r (cols - 1) + c from the board's top
// left) and the chessboard's orientation rule per face; then a photo folder
// through DetectPhotos, PixelObservationsOf and WritePixels (one corner per target).
#include "detect/point_boards.h"

#include <gtest/gtest.h>

#include <unistd.h>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "detect/photos.h"
#include "libcalib/io/records.h"
#include "libcalib/io/csv.h"
#include "libcalib/text/errors.h"
#include "libcalib/io/targets_io.h"
#include "tests/detect/synthetic_photo.h"

namespace rtscalib::detect {
namespace {

using testing::MakeHomography;
using testing::PrintedTag;

// The printed board as one code image of `cells` per square (0 = ink,
// 255 = paper): square (r, c) black when r + c is even (the top-left square
// is black, as cv::aruco::CharucoBoard draws it); ChArUco markers, 1 bit a
// cell, centred in the white squares in row-major order with ids 0, 1, ...
PrintedTag PrintBoard(const TagBoard& b, int cells) {
  cv::Mat code(b.rows * cells, b.cols * cells, CV_8UC1, cv::Scalar(255));
  cv::Ptr<cv::aruco::Dictionary> dict;
  if (b.kind == BoardKind::kCharuco) {
    dict = cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_50);
  }
  int marker = 0;
  for (int r = 0; r < b.rows; ++r) {
    for (int c = 0; c < b.cols; ++c) {
      const cv::Rect square(c * cells, r * cells, cells, cells);
      if ((r + c) % 2 == 0) {
        code(square).setTo(0);
      } else if (dict) {
        const int bits = dict->markerSize + 2;  // with the black border
        cv::Mat m;
        cv::aruco::drawMarker(dict, marker++, bits, m, 1);
        const int offset = (cells - bits) / 2;
        m.copyTo(code(cv::Rect(c * cells + offset, r * cells + offset, bits, bits)));
      }
    }
  }
  PrintedTag t;
  t.code = code;
  t.width_at_border = code.cols;
  t.border_offset = 0;
  t.size = b.Width();
  return t;
}

TagBoard Charuco() {
  TagBoard b;
  b.kind = BoardKind::kCharuco;
  b.family = "DICT_4X4_50";
  b.first_id = 100;
  b.rows = 5;
  b.cols = 7;
  b.square_size = 0.04;
  b.marker_size = 0.03;  // 6 of 8 cells
  return b;
}

TagBoard Chessboard() {
  TagBoard b;
  b.kind = BoardKind::kChessboard;
  b.family = "chessboard";
  b.first_id = 200;
  b.rows = 6;
  b.cols = 9;
  b.square_size = 0.025;
  return b;
}

struct Photo {
  cv::Mat image;
  Eigen::Matrix3d image_from_board;
};

// The board seen through a homography: centred in a `width` x `height`
// image, `scale` px per metre, turned by `angle` in the image, a slight
// perspective.
Photo Synthesize(const TagBoard& b, int cells, double scale, double angle, int width = 1280,
                 int height = 960) {
  const PrintedTag t = PrintBoard(b, cells);
  Photo p;
  p.image_from_board =
      MakeHomography(b.Width(), {width / 2 + 0.3, height / 2 + 0.6}, scale, angle, 0.3, -0.2);
  const cv::Mat coverage = testing::RenderCoverage({t}, p.image_from_board, width, height);
  p.image = testing::ToPixels(coverage, CV_8UC1, cv::Scalar(30), cv::Scalar(220));
  return p;
}

struct Errors {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  double rms = 0, max = 0;
  int n = 0;
};

Errors Compare(const TagBoard& b, const Photo& p, const PointBoardDetection& d) {
  Errors e;
  double sum = 0;
  for (const auto& [k, uv] : d.corners) {
    const Eigen::Vector3d x = b.CornersInBoard(k)[0];
    const Eigen::Vector2d exact = testing::Project(p.image_from_board, x.head<2>());
    const double err = (uv - exact).norm();
    e.mean += (uv - exact) / static_cast<double>(d.corners.size());
    sum += err * err;
    e.max = std::max(e.max, err);
    ++e.n;
  }
  e.rms = e.n ? std::sqrt(sum / e.n) : 0.0;
  return e;
}

TEST(PointBoards, CharucoCornersAreOpenCvsIdsAtTheirExactImages) {
  const TagBoard b = Charuco();
  for (const double angle : {0.05, M_PI - 0.1}) {  // upright (face 1) and turned (face 2)
    const Photo p = Synthesize(b, 8, 2600.0, angle);
    const PointBoardDetection d = DetectPointBoard(p.image, b, angle > 1 ? 2 : 1);
    const Errors e = Compare(b, p, d);
    std::cout << "charuco, angle " << angle << ": " << e.n << " corners, mean "
              << e.mean.transpose() << " px, RMS " << e.rms
              << " px, max " << e.max << " px\n";
    // All (rows - 1) (cols - 1) inner corners, each where its id says: a
    // wrong id would be a square (104 px) away. OpenCV's corner refinement
    // on exact synthetic photos: measured 0.01-0.03 px RMS; 0.1 px RMS and
    // 0.3 px max (SPEC 2 pixel centres: a half-pixel convention error would
    // be 0.7 px) are the limits.
    EXPECT_EQ(e.n, b.NumTags());
    EXPECT_LT(e.rms, 0.1);
    EXPECT_LT(e.max, 0.3);
  }
}

TEST(PointBoards, ChessboardOrientationFollowsTheFace) {
  const TagBoard b = Chessboard();
  for (const auto& [angle, face] : std::vector<std::pair<double, int>>{{0.08, 1}, {M_PI + 0.05, 2}}) {
    const Photo p = Synthesize(b, 1, 3000.0, angle);
    const PointBoardDetection d = DetectPointBoard(p.image, b, face);
    const Errors e = Compare(b, p, d);
    std::cout << "chessboard, face " << face << ": " << e.n << " corners, RMS " << e.rms
              << " px, max " << e.max << " px\n";
    EXPECT_FALSE(d.misoriented);
    EXPECT_EQ(e.n, b.NumTags());
    EXPECT_LT(e.rms, 0.1);
    EXPECT_LT(e.max, 0.3);
  }
  // Turned by 90 degrees: no face shows a board like that; not used.
  const Photo sideways = Synthesize(b, 1, 3000.0, M_PI / 2);
  const PointBoardDetection d = DetectPointBoard(sideways.image, b, 1);
  EXPECT_TRUE(d.misoriented);
  EXPECT_TRUE(d.corners.empty());
}

// A chessboard whose pose is estimated (SPEC 7.1: one pose per placement)
// may hang or be held in any orientation: every orientation is used, and
// its numbering is the printed one or the one turned by 180 degrees (the
// pose absorbs which), never a mirrored one; upright in face 1 it is the
// printed one, so that every photo of a placement numbers the grid alike.
TEST(PointBoards, EstimatedChessboardIsUsedInAnyOrientation) {
  TagBoard b = Chessboard();
  b.pose_known = false;
  const int nc = b.cols - 1, nr = b.rows - 1;
  for (const auto& [angle, face] : std::vector<std::pair<double, int>>{
           {0.08, 1}, {M_PI / 2 + 0.1, 1}, {M_PI + 0.05, 1}, {-M_PI / 2 + 0.1, 2}, {0.3, 2}}) {
    const Photo p = Synthesize(b, 1, 3000.0, angle);
    const PointBoardDetection d = DetectPointBoard(p.image, b, face);
    EXPECT_FALSE(d.misoriented);
    ASSERT_EQ(static_cast<int>(d.corners.size()), b.NumTags()) << "angle " << angle;
    // RMS against the exact corners under the printed numbering and under
    // the one turned by 180 degrees (k -> n - 1 - k).
    double printed = 0, turned = 0;
    for (const auto& [k, uv] : d.corners) {
      const Eigen::Vector3d x = b.CornersInBoard(k)[0];
      const Eigen::Vector3d y = b.CornersInBoard(nc * nr - 1 - k)[0];
      printed += (uv - testing::Project(p.image_from_board, x.head<2>())).squaredNorm();
      turned += (uv - testing::Project(p.image_from_board, y.head<2>())).squaredNorm();
    }
    printed = std::sqrt(printed / d.corners.size());
    turned = std::sqrt(turned / d.corners.size());
    std::cout << "estimated chessboard, angle " << angle << ", face " << face << ": RMS "
              << std::min(printed, turned) << " px (" << (printed < turned ? "printed" : "turned")
              << " numbering)\n";
    // The limits of the test above; a mirrored numbering matches neither.
    EXPECT_LT(std::min(printed, turned), 0.1) << "angle " << angle;
    if (angle == 0.08) {
      EXPECT_LT(printed, 0.1);
    }
  }
}

// Two printed copies of one chessboard in a photo: neither can be told from
// the other, so neither is used, and the detection says why.
TEST(PointBoards, ChessboardFoundTwiceIsNotUsed) {
  TagBoard b = Chessboard();
  b.pose_known = false;
  const PrintedTag t = PrintBoard(b, 1);
  const Eigen::Matrix3d left = MakeHomography(b.Width(), {330.2, 480.6}, 1300.0, 0.05);
  const Eigen::Matrix3d right = MakeHomography(b.Width(), {950.7, 470.3}, 1300.0, -0.04);
  cv::Mat coverage = cv::min(testing::RenderCoverage({t}, left, 1280, 960),
                             testing::RenderCoverage({t}, right, 1280, 960));
  const cv::Mat two = testing::ToPixels(coverage, CV_8UC1, cv::Scalar(30), cv::Scalar(220));
  const PointBoardDetection d = DetectPointBoard(two, b, 1);
  EXPECT_TRUE(d.duplicated);
  EXPECT_TRUE(d.corners.empty());
  // One copy alone is found.
  const cv::Mat one = testing::ToPixels(testing::RenderCoverage({t}, left, 1280, 960), CV_8UC1,
                                        cv::Scalar(30), cv::Scalar(220));
  const PointBoardDetection single = DetectPointBoard(one, b, 1);
  EXPECT_FALSE(single.duplicated);
  EXPECT_EQ(static_cast<int>(single.corners.size()), b.NumTags());
}

// OpenCV's sample photos of a real camera (Debian's opencv-doc): a hand-held
// 9 x 6 inner-corner chessboard in left01 ... left14 and right01 ... right14
// (no 10s), blurred and steep in some; left.jpg and right.jpg show another
// scene without it. DetectChessboard asks OpenCV's quick check before its
// searches; it must not cost a board: each is found whole, and the photos
// without one give nothing.
TEST(PointBoards, QuickCheckKeepsEveryChessboardOfOpenCvsSamplePhotos) {
  const std::string dir = "/usr/share/doc/opencv-doc/examples/data/";
  TagBoard b = Chessboard();
  b.rows = 7;  // squares: 9 x 6 inner corners
  b.cols = 10;
  b.pose_known = false;
  int photos = 0;
  for (const char* side : {"left", "right"}) {
    for (int i = 1; i <= 14; ++i) {
      if (i == 10) continue;
      const std::string path = dir + side + (i < 10 ? "0" : "") + std::to_string(i) + ".jpg";
      const cv::Mat gray = cv::imread(path, cv::IMREAD_GRAYSCALE);
      ASSERT_FALSE(gray.empty()) << path << " missing (Debian package opencv-doc)";
      EXPECT_EQ(static_cast<int>(DetectPointBoard(gray, b, 1).corners.size()), 54) << path;
      ++photos;
    }
    const std::string without = dir + side + ".jpg";
    const cv::Mat gray = cv::imread(without, cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(gray.empty()) << without;
    EXPECT_TRUE(DetectPointBoard(gray, b, 1).corners.empty()) << without;
  }
  EXPECT_EQ(photos, 26);
}

// A board in a large photo is found in a small copy of it (2560 x 1920:
// the search starts at 320 x 240 or 160 x 120) and its corners are taken
// down to the photo's saddles, as accurate as in the 1280 x 960 photos
// above (the same limits).
TEST(PointBoards, ChessboardInALargePhotoIsFoundInASmallCopyAtThePhotosSaddles) {
  const TagBoard b = Chessboard();
  const Photo p = Synthesize(b, 1, 8000.0, 0.08, 2560, 1920);  // 200 px squares
  const PointBoardDetection d = DetectPointBoard(p.image, b, 1);
  const Errors e = Compare(b, p, d);
  std::cout << "chessboard in 2560 x 1920: " << e.n << " corners, RMS " << e.rms << " px, max "
            << e.max << " px\n";
  EXPECT_FALSE(d.misoriented);
  EXPECT_FALSE(d.duplicated);
  EXPECT_EQ(e.n, b.NumTags());
  EXPECT_LT(e.rms, 0.1);
  EXPECT_LT(e.max, 0.3);
}

const char* const kOpenCvSamples = "/usr/share/doc/opencv-doc/examples/data/";

TagBoard OpenCvSampleBoard() {
  TagBoard b = Chessboard();
  b.rows = 7;  // squares: 9 x 6 inner corners
  b.cols = 10;
  b.pose_known = false;
  return b;
}

cv::Mat OpenCvSample(const std::string& name) {
  const cv::Mat gray = cv::imread(kOpenCvSamples + name, cv::IMREAD_GRAYSCALE);
  EXPECT_FALSE(gray.empty()) << kOpenCvSamples << name << " missing (Debian package opencv-doc)";
  return gray;
}

// The coarse-to-fine search ends at the photo's own saddles: on OpenCV's 26
// sample photos its corners are where cornerSubPix takes OpenCV's classic
// detector's corners (findChessboardCorners on the whole photo) with the
// same window (RefineSaddles': a quarter of the smallest square, from these
// corners). Measured: 0.005 px RMS, 0.057 px at most; what differs is the
// window where the square's estimate before the last refinement falls on
// the other side of a whole pixel (cornerSubPix's saddle moves with its
// window on a real, blurred and distorted corner).
TEST(PointBoards, ChessboardCornersAreTheSaddlesOfThePhotoItself) {
  const TagBoard b = OpenCvSampleBoard();
  const cv::Size size(b.cols - 1, b.rows - 1);
  double sum_sq = 0, worst = 0;
  int n = 0;
  for (const char* side : {"left", "right"}) {
    for (int i = 1; i <= 14; ++i) {
      if (i == 10) continue;
      const std::string name = side + std::string(i < 10 ? "0" : "") + std::to_string(i) + ".jpg";
      const cv::Mat gray = OpenCvSample(name);
      if (gray.empty()) return;
      const PointBoardDetection d = DetectPointBoard(gray, b, 1);
      ASSERT_EQ(static_cast<int>(d.corners.size()), b.NumTags()) << name;
      std::vector<cv::Point2f> classic;
      ASSERT_TRUE(cv::findChessboardCorners(gray, size, classic)) << name;
      double square = 1e9;
      for (const auto& [k, uv] : d.corners) {
        for (const auto& [k2, uv2] : d.corners) {
          if (k2 == k + 1 && k % size.width != size.width - 1) square = std::min(square, (uv2 - uv).norm());
        }
      }
      const int half = std::clamp(static_cast<int>(std::min(square / 4, square - 1)), 2, 10);
      cv::cornerSubPix(gray, classic, cv::Size(half, half), cv::Size(-1, -1),
                       cv::TermCriteria(cv::TermCriteria::MAX_ITER | cv::TermCriteria::EPS, 100, 1e-4));
      // The same grid, numbered from either end: each corner against the
      // nearest of the classic ones.
      for (const auto& [k, uv] : d.corners) {
        double nearest = 1e9;
        for (const cv::Point2f& c : classic) nearest = std::min(nearest, (uv - Eigen::Vector2d(c.x, c.y)).norm());
        sum_sq += nearest * nearest;
        worst = std::max(worst, nearest);
        ++n;
      }
    }
  }
  const double rms = std::sqrt(sum_sq / n);
  std::cout << n << " corners against the classic detector's refined alike: RMS " << rms
            << " px, max " << worst << " px\n";
  EXPECT_EQ(n, 26 * 54);
  EXPECT_LT(rms, 0.02);
  EXPECT_LT(worst, 0.1);
}

// `left` with `right` beside it, on a canvas of `left`'s mean grey.
cv::Mat Beside(const cv::Mat& left, const cv::Mat& right) {
  cv::Mat out(std::max(left.rows, right.rows), left.cols + right.cols, CV_8UC1,
              cv::Scalar(cv::mean(left)[0]));
  left.copyTo(out(cv::Rect(0, 0, left.cols, left.rows)));
  right.copyTo(out(cv::Rect(left.cols, (out.rows - right.rows) / 2, right.cols, right.rows)));
  return out;
}

// Two real chessboards in one photo: OpenCV's left01.jpg beside left02.jpg
// (1280 x 480), and beside left02.jpg at half its size (a copy twice as far
// away): the second copy is found and neither is used. Beside left.jpg (the
// same camera, no board) the board is used.
TEST(PointBoards, RealChessboardFoundTwiceIsNotUsed) {
  const TagBoard b = OpenCvSampleBoard();
  const cv::Mat first = OpenCvSample("left01.jpg"), second = OpenCvSample("left02.jpg"),
                none = OpenCvSample("left.jpg");
  if (first.empty() || second.empty() || none.empty()) return;
  EXPECT_TRUE(DetectPointBoard(Beside(first, second), b, 1).duplicated);
  cv::Mat small;
  cv::resize(second, small, cv::Size(second.cols / 2, second.rows / 2), 0, 0, cv::INTER_AREA);
  EXPECT_TRUE(DetectPointBoard(Beside(first, small), b, 1).duplicated);
  const PointBoardDetection d = DetectPointBoard(Beside(first, none), b, 1);
  EXPECT_FALSE(d.duplicated);
  EXPECT_EQ(static_cast<int>(d.corners.size()), b.NumTags());
}

// The same two copies (left01.jpg beside left02.jpg) as photos of a
// session: where the photo's placement is its own, the board's pose is
// the photo's alone and whichever copy is found is used (no second search,
// CopySearch::kSkip); where two photos share the placement, the copies stay
// unused, with the warning. The lone board is found either way.
TEST(PointBoards, SecondCopyIsSearchedWhereThePlacementIsShared) {
  const cv::Mat first = OpenCvSample("left01.jpg"), second = OpenCvSample("left02.jpg");
  if (first.empty() || second.empty()) return;
  const TagBoard b = OpenCvSampleBoard();
  const PointBoardDetection skipped = DetectPointBoard(Beside(first, second), b, 1,
                                                       CopySearch::kSkip);
  EXPECT_FALSE(skipped.duplicated);
  EXPECT_EQ(static_cast<int>(skipped.corners.size()), b.NumTags());

  const std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) /
                                    ("rtscalib_copies_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  cv::imwrite((dir / "two.png").string(), Beside(first, second));
  cv::imwrite((dir / "one.png").string(), Beside(first, cv::Mat(second.size(), CV_8UC1,
                                                                 cv::Scalar(cv::mean(first)[0]))));
  std::ofstream(dir / "targets.yaml")
      << "boards:\n  - {type: chessboard, first_id: 0, rows: 7, cols: 10, square_size: 0.025}\n";
  const TargetScene targets = ReadTargets((dir / "targets.yaml").string());
  PhotoDetectionOptions options;
  options.progress = false;
  auto detect = [&](const std::string& rows) {
    std::ofstream(dir / "shots.csv") << "face,zoom,phi,theta,image,placement\n" << rows;
    return DetectPhotos(ReadShots((dir / "shots.csv").string()), targets, options);
  };
  const PhotoDetectionResult own = detect("1,0,,,two.png,p1\n1,0,,,one.png,p2\n");
  EXPECT_EQ(own.photos[0].tags.size(), 54u);
  EXPECT_EQ(own.photos[0].duplicate_boards, 0);
  EXPECT_TRUE(own.warnings.empty());
  const PhotoDetectionResult shared = detect("1,0,,,two.png,p1\n1,0,,,one.png,p1\n");
  EXPECT_TRUE(shared.photos[0].tags.empty());
  EXPECT_EQ(shared.photos[0].duplicate_boards, 1);
  EXPECT_EQ(shared.photos[1].tags.size(), 54u);
  ASSERT_FALSE(shared.warnings.empty());
  EXPECT_NE(shared.warnings[0].find("found twice"), std::string::npos) << shared.warnings[0];
  std::filesystem::remove_all(dir);
}

TEST(PointBoards, PhotoFolderGivesOneCornerPerTarget) {
  const std::filesystem::path dir =
      std::filesystem::path(::testing::TempDir()) / ("rtscalib_point_boards_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  cv::imwrite((dir / "c.png").string(), Synthesize(Charuco(), 8, 2600.0, 0.05).image);
  cv::imwrite((dir / "s.png").string(), Synthesize(Chessboard(), 1, 3000.0, M_PI + 0.05).image);
  std::ofstream(dir / "shots.csv") << "face,zoom,phi,theta,image\n1,0,0.1,1.5,c.png\n2,0,3.3,4.8,s.png\n";
  std::ofstream(dir / "targets.yaml")
      << "boards:\n"
         "  - {type: charuco, dictionary: DICT_4X4_50, first_id: 100, rows: 5, cols: 7, "
         "square_size: 0.04, marker_size: 0.03}\n"
         "  - {type: chessboard, first_id: 200, rows: 6, cols: 9, square_size: 0.025}\n";
  const ShotsFile shots = ReadShots((dir / "shots.csv").string());
  const TargetScene targets = ReadTargets((dir / "targets.yaml").string());
  ASSERT_EQ(targets.boards.size(), 2u);
  EXPECT_EQ(targets.boards[0].NumTags(), 24);
  EXPECT_EQ(targets.boards[1].NumTags(), 40);
  PhotoDetectionOptions options;
  options.progress = false;
  const PhotoDetectionResult r = DetectPhotos(shots, targets, options);
  ASSERT_EQ(r.photos.size(), 2u);
  EXPECT_EQ(r.photos[0].tags.size(), 24u);
  EXPECT_EQ(r.photos[1].tags.size(), 40u);
  EXPECT_TRUE(r.warnings.empty());
  WritePixels((dir / "pixels.csv").string(), PixelObservationsOf(shots, targets, r),
              shots.angle_unit, ImageSizesOf(shots, r));
  const CsvTable t = CsvTable::Read((dir / "pixels.csv").string(),
                                    {{"shot", "target", "corner", "u", "v"}, {}});
  EXPECT_EQ(t.NumRows(), 64);
  for (int i = 0; i < t.NumRows(); ++i) EXPECT_EQ(t.Integer(i, "corner"), 0);
  EXPECT_EQ(t.Integer(0, "target"), 100);
  EXPECT_EQ(t.Integer(24, "target"), 200);
  std::filesystem::remove_all(dir);
}

// targets.yaml is read against what the detector can find: ArUco
// dictionaries OpenCV knows, and enough markers for the board.
TEST(PointBoards, DictionaryAndMarkerCountAreCheckedWhenReadingTargets) {
  const std::map<std::string, int> codes = DetectableCodeCounts();
  EXPECT_EQ(codes.at("aruco:DICT_4X4_50"), 50);
  EXPECT_EQ(codes.at("tag36h11"), 587);
  auto error = [&](const std::string& board) {
    try {
      ParseTargets("boards:\n  - {" + board + "}\n", "targets.yaml", &codes);
    } catch (const InputError& e) {
      return std::make_pair(e.key, std::string(e.what()));
    }
    return std::make_pair(std::string(), std::string());
  };
  const auto unknown = error(
      "type: charuco, dictionary: DICT_9X9_50, first_id: 0, rows: 3, cols: 4, square_size: 0.02, "
      "marker_size: 0.01");
  EXPECT_EQ(unknown.first, "boards[0].dictionary");
  EXPECT_NE(unknown.second.find("DICT_4X4_50"), std::string::npos) << unknown.second;
  const auto too_big = error(
      "type: charuco, dictionary: DICT_4X4_50, first_id: 0, rows: 12, cols: 12, square_size: 0.02, "
      "marker_size: 0.01");
  EXPECT_EQ(too_big.first, "boards[0].rows");
  EXPECT_NE(too_big.second.find("72 markers"), std::string::npos) << too_big.second;
  // An AprilTag board cannot name an ArUco dictionary as its family.
  EXPECT_EQ(error("family: DICT_4X4_50, first_id: 0, rows: 1, cols: 1, tag_size: 0.1, spacing: 0")
                .first,
            "boards[0].family");
}

}  // namespace
}  // namespace rtscalib::detect

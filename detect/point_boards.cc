#include "detect/point_boards.h"

#include <opencv2/aruco/charuco.hpp>
#include <opencv2/calib3d.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <opencv2/imgproc.hpp>

namespace rtscalib::detect {
namespace {

const std::vector<std::pair<std::string, cv::aruco::PREDEFINED_DICTIONARY_NAME>>& Dictionaries() {
  using namespace cv::aruco;
  static const std::vector<std::pair<std::string, PREDEFINED_DICTIONARY_NAME>> names = {
      {"DICT_4X4_50", DICT_4X4_50},       {"DICT_4X4_100", DICT_4X4_100},
      {"DICT_4X4_250", DICT_4X4_250},     {"DICT_4X4_1000", DICT_4X4_1000},
      {"DICT_5X5_50", DICT_5X5_50},       {"DICT_5X5_100", DICT_5X5_100},
      {"DICT_5X5_250", DICT_5X5_250},     {"DICT_5X5_1000", DICT_5X5_1000},
      {"DICT_6X6_50", DICT_6X6_50},       {"DICT_6X6_100", DICT_6X6_100},
      {"DICT_6X6_250", DICT_6X6_250},     {"DICT_6X6_1000", DICT_6X6_1000},
      {"DICT_7X7_50", DICT_7X7_50},       {"DICT_7X7_100", DICT_7X7_100},
      {"DICT_7X7_250", DICT_7X7_250},     {"DICT_7X7_1000", DICT_7X7_1000},
      {"DICT_ARUCO_ORIGINAL", DICT_ARUCO_ORIGINAL}};
  return names;
}

cv::Ptr<cv::aruco::CharucoBoard> MakeCharuco(const TagBoard& board) {
  for (const auto& [name, id] : Dictionaries()) {
    if (name != board.family) continue;
    const cv::Ptr<cv::aruco::Dictionary> dict = cv::aruco::getPredefinedDictionary(id);
    const int markers = board.rows * board.cols / 2;
    if (dict->bytesList.rows < markers) {
      throw std::invalid_argument("ChArUco board of " + std::to_string(board.rows) + " x " +
                                  std::to_string(board.cols) + " squares needs " +
                                  std::to_string(markers) + " markers, " + name + " has " +
                                  std::to_string(dict->bytesList.rows));
    }
    return cv::aruco::CharucoBoard::create(board.cols, board.rows,
                                           static_cast<float>(board.square_size),
                                           static_cast<float>(board.marker_size), dict);
  }
  throw std::invalid_argument("unknown ArUco dictionary '" + board.family + "'");
}

// cv::cornerSubPix to the saddle points of the squares' corners, in SPEC 2
// pixels whatever the start. `square_px` is the smallest distance between
// neighbouring corners of a row (one square; 1e9 when unknown), `clear` the
// fraction of a square around a corner that holds nothing but the four
// squares' edges (a ChArUco marker starts (square - marker) / 2 from its
// square's edge). Window half size: a quarter of the square, and one pixel
// less than the clear part, 2..10 px: the gradients of anything else in the
// window (the next corners, a marker's edges) pull the saddle (a 7.5 cm /
// 5.6 cm ChArUco board rendered at 64 px squares: 0.11 px RMS with a 10 px
// window reaching into the markers, 0.077 px with 7 px; docs/photos.md).
void RefineSaddles(const cv::Mat& gray, double square_px, double clear,
                   std::vector<cv::Point2f>* corners) {
  int half = 5;
  if (square_px < 1e9) {
    half = std::clamp(static_cast<int>(std::min(square_px / 4, clear * square_px - 1)), 2, 10);
  }
  cv::cornerSubPix(gray, *corners, cv::Size(half, half), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::MAX_ITER | cv::TermCriteria::EPS, 100, 1e-4));
}

PointBoardDetection DetectCharuco(const cv::Mat& gray, const TagBoard& board) {
  const cv::Ptr<cv::aruco::CharucoBoard> charuco = MakeCharuco(board);
  std::vector<std::vector<cv::Point2f>> marker_corners;
  std::vector<int> marker_ids;
  cv::aruco::detectMarkers(gray, charuco->dictionary, marker_corners, marker_ids);
  PointBoardDetection out;
  if (marker_ids.empty()) return out;
  std::vector<cv::Point2f> corners;
  std::vector<int> ids;
  cv::aruco::interpolateCornersCharuco(marker_corners, marker_ids, gray, charuco, corners, ids);
  if (ids.empty()) return out;
  // OpenCV 4.5.4 to 4.12 return the corners 0.5 px right of and below the
  // saddle point (they shift around cornerSubPix and shift back: opencv
  // issue 25539, fixed by pull request 28380; tests/detect/point_boards_test.cc
  // measures the shift). cornerSubPix converges to the
  // saddle in absolute SPEC 2 coordinates whatever its start, so the corners
  // are refined once more here, which is right for every version.
  double square_px = 1e9;
  const int per_row = board.cols - 1;
  for (size_t i = 0; i < ids.size(); ++i) {
    for (size_t j = 0; j < ids.size(); ++j) {
      if (ids[j] == ids[i] + 1 && ids[i] % per_row != per_row - 1) {
        square_px = std::min(square_px, static_cast<double>(cv::norm(corners[j] - corners[i])));
      }
    }
  }
  RefineSaddles(gray, square_px, (board.square_size - board.marker_size) / (2 * board.square_size),
                &corners);
  for (size_t i = 0; i < ids.size(); ++i) {
    out.corners.emplace_back(ids[i], Eigen::Vector2d(corners[i].x, corners[i].y));
  }
  return out;
}

// The smallest distance between neighbouring corners of a row of a grid of
// `nc` corners per row: one square in pixels (1e9 for a grid of one column).
double SmallestRowStep(const std::vector<cv::Point2f>& grid, int nc) {
  double step = 1e9;
  for (size_t k = 0; k + 1 < grid.size(); ++k) {
    if (static_cast<int>(k) % nc != nc - 1) {
      step = std::min(step, static_cast<double>(cv::norm(grid[k + 1] - grid[k])));
    }
  }
  return step;
}

// The chessboard search's levels of a photo: level 0 the photo itself, each
// next one half its width and height (means of 2 x 2 pixels, so that pixel
// (i, j) of level l + 1 is centred at (2 i + 0.5, 2 j + 0.5) of level l),
// down to the last whose shorter side is at least kCoarsestSide pixels.
// OpenCV's saddle-point search (findChessboardCornersSB) costs time in
// proportion to the pixels it is given (BM_LargePhotoDetect and
// BM_LargePhotoOpenCv in opencv_bench_side_by_side_benchmark report it per
// pixel, up to 6000 x 4000 photos) and finds boards whose squares are 5 px
// or more, so a board that fills a good part of the photo is found in a
// small copy of it: a quarter of the time at half the size. The 61 real photos of OpenCV's,
// BoofCV's and ValidationBoof's chessboard sets (640 x 480, squares of 28
// to 62 px) are all found in their copies of 160 x 120, and give the same
// corners as a search of the photo itself (below).
constexpr int kCoarsestSide = 120;

// OpenCV's quick check (checkChessboard: the classic detector's
// CALIB_CB_FAST_CHECK, quads of the right count at a few thresholds) sees
// boards whose squares are about kCheckSquarePx or more (its quads are at
// least 5 px across after an erosion; measured on boards turned by 7
// degrees, blurred by 0.7 px: found at 14 px, not at 12 px).
constexpr double kCheckSquarePx = 14;

std::vector<cv::Mat> SearchLevels(const cv::Mat& gray) {
  std::vector<cv::Mat> levels = {gray};
  while (std::min(levels.back().cols, levels.back().rows) / 2 >= kCoarsestSide) {
    cv::Mat half;
    cv::resize(levels.back(), half, cv::Size(levels.back().cols / 2, levels.back().rows / 2), 0, 0,
               cv::INTER_AREA);
    levels.push_back(half);
  }
  return levels;
}

// The coarsest level from the coarsest down to `finest` at which the quick
// check sees a board, or -1. Most photos of a session show no chessboard
// (another board, or this one out of view), and there it answers in
// milliseconds where the search would run through every level, so that a
// session of several boards (tests/app/rendered_point_boards_test.cc: three
// ChArUco boards and a chessboard) is detected several times faster, every
// visible corner still found. It keeps every board of OpenCV's 26
// sample photos of a real camera
// (PointBoards.QuickCheckKeepsEveryChessboardOfOpenCvsSamplePhotos). A
// board whose squares are too small for it at a coarse level is seen at a
// finer one; level 0, the photo itself, is the check of the whole photo.
// At coarse levels it costs a small fraction of the photo's check: on a
// noisy photo fewer specks of noise cross its thresholds at half the size.
int QuickCheck(const std::vector<cv::Mat>& levels, cv::Size size, int finest) {
  for (int l = static_cast<int>(levels.size()) - 1; l >= finest; --l) {
    if (cv::checkChessboard(levels[l], size)) return l;
  }
  return -1;
}

// One level: the exhaustive search first; on real photos it misses a few
// boards that the plain search finds (OpenCV's left11.jpg at full size:
// blur and a steep view), so that one is tried next. Not the classic quad
// detector: on a photo of noise without a board it can search for minutes,
// and for seconds even with its fast check. Without CALIB_CB_ACCURACY: with
// it the corners are farther off on rendered photos than cornerSubPix's and
// cost more time per image; cornerSubPix from either start converges to the same
// saddles, 0.06 px RMS (tests/render/point_boards_test.cc, docs/photos.md).
bool FindGridAt(const cv::Mat& level, cv::Size size, std::vector<cv::Point2f>* grid) {
  grid->clear();
  if (cv::findChessboardCornersSB(level, size, *grid,
                                  cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_EXHAUSTIVE)) {
    return true;
  }
  grid->clear();
  return cv::findChessboardCornersSB(level, size, *grid, cv::CALIB_CB_NORMALIZE_IMAGE);
}

// The grid of a whole chessboard of `size` inner corners when the quick
// check saw one down to level `finest`: searched from level `checked` + 1
// (the search sees squares of a third of the size the check needs; coarser
// levels hold none it could find) down to the photo (the first level that
// holds it wins), then taken down level by level, refined to the saddles at
// each (RefineSaddles, its window a quarter of that level's square): the
// search's corners are up to 1.5 px of their level off the saddles, so a
// start from level l is within the window of level l - 1 once refined at
// level l. At the photo they are the saddles a search of the photo itself
// and cornerSubPix give, cornerSubPix converging to the same point from
// either start. False when no level holds the board.
bool FindChessboardGrid(const std::vector<cv::Mat>& levels, cv::Size size, int finest,
                        std::vector<cv::Point2f>* grid) {
  grid->clear();
  const int checked = QuickCheck(levels, size, finest);
  if (checked < 0) return false;
  for (int l = std::min(checked + 1, static_cast<int>(levels.size()) - 1); l >= 0; --l) {
    if (!FindGridAt(levels[l], size, grid) ||
        static_cast<int>(grid->size()) != size.width * size.height) {
      continue;
    }
    for (int k = l; k >= 0; --k) {
      if (k < l) {
        for (cv::Point2f& p : *grid) p = p * 2.0f + cv::Point2f(0.5f, 0.5f);
      }
      RefineSaddles(levels[k], SmallestRowStep(*grid, size.width), 1.0, grid);
    }
    return true;
  }
  grid->clear();
  return false;
}

PointBoardDetection DetectChessboard(const cv::Mat& gray, const TagBoard& board, int face,
                                     CopySearch copies) {
  const int nc = board.cols - 1, nr = board.rows - 1;
  PointBoardDetection out;
  const cv::Size size(nc, nr);
  std::vector<cv::Point2f> grid;
  if (!FindChessboardGrid(SearchLevels(gray), size, 0, &grid)) return out;
  // A second copy: the found board masked out (its hull, grown by one and a
  // half squares, filled with the photo's mean grey) and the photo searched
  // again, as for the first board, for copies whose squares are at least a
  // quarter of the found one's (printed alike and up to 4 times as far
  // away, or a reflection): the quick check runs down to the level where
  // such squares are kCheckSquarePx. A photo with one board passes no check
  // once it is masked (none of the 61 real photos above), so the second
  // search costs only the checks, a fraction of the photo's own where the
  // board is large in a large photo.
  const double step = SmallestRowStep(grid, nc);
  if (copies == CopySearch::kSearch) {
    std::vector<cv::Point2f> hull_f;
    cv::convexHull(grid, hull_f);
    const cv::Point2f centre = std::accumulate(hull_f.begin(), hull_f.end(), cv::Point2f(0, 0)) *
                               (1.0f / static_cast<float>(hull_f.size()));
    std::vector<cv::Point> hull;
    for (const cv::Point2f& p : hull_f) {
      const cv::Point2f out_dir = p - centre;
      const float len = std::max(1e-3f, static_cast<float>(cv::norm(out_dir)));
      hull.emplace_back(p + out_dir * static_cast<float>(1.5 * step / len));
    }
    cv::Mat masked = gray.clone();
    cv::fillConvexPoly(masked, hull, cv::Scalar(cv::mean(gray)[0]));
    const int finest = std::max(0, static_cast<int>(std::floor(std::log2(step / 4 / kCheckSquarePx))));
    std::vector<cv::Point2f> second;
    if (FindChessboardGrid(SearchLevels(masked), size, finest, &second)) {
      out.duplicated = true;
      return out;
    }
  }
  // Directions of the grid's rows (along k) and columns in the image.
  auto at = [&](int r, int c) { return Eigen::Vector2d(grid[r * nc + c].x, grid[r * nc + c].y); };
  const Eigen::Vector2d along_row = at(0, nc - 1) - at(0, 0);
  const Eigen::Vector2d down_cols = at(nr - 1, 0) - at(0, 0);
  // A grid numbered as a print seen from its back (rows turning the other
  // way round, image v pointing down) is mirrored.
  const bool mirrored = along_row.x() * down_cols.y() - along_row.y() * down_cols.x() <= 0;
  const double sign = face == 2 ? -1.0 : 1.0;  // face 2: the image turned by 180 degrees
  bool reverse_rows = false, reverse_all = false;
  if (board.pose_known) {
    // A surveyed board's numbering is its print's: the camera does not roll,
    // so in face 1 its rows run to the right (+u) and its columns down, in
    // face 2 turned by 180 degrees. A grid returned the other way round is
    // reversed (OpenCV may start at either end); anything else is a board
    // seen sideways or mirrored, not used.
    const bool mostly_horizontal = std::abs(along_row.x()) > std::abs(along_row.y());
    if (!mostly_horizontal || mirrored) {
      out.misoriented = true;
      return out;
    }
    reverse_all = sign * along_row.x() < 0;
  } else {
    // A board whose pose is estimated (per placement, SPEC 7.1) may hang or
    // be held in any orientation: its pose absorbs the numbering of its grid,
    // as in OpenCV's calibrateCamera. The numbering is made proper (seen from
    // the front: a mirrored grid has its rows reversed) and, of the two
    // proper ones turned by 180 degrees, the one whose rows run at an image
    // angle in [-45, 135) degrees in face 1 (turned by 180 in face 2) is
    // kept, so that every photo of one placement from one instrument (which
    // does not roll) numbers the grid alike; upright and sideways boards lie
    // far from the boundaries.
    reverse_rows = mirrored;
    Eigen::Vector2d row = reverse_rows ? Eigen::Vector2d(-along_row) : along_row;
    row *= sign;
    const double angle = std::atan2(row.y(), row.x()) * 180.0 / M_PI;
    reverse_all = !(angle >= -45.0 && angle < 135.0);
  }
  for (int k = 0; k < nc * nr; ++k) {
    int r = k / nc, c = k % nc;
    if (reverse_rows) c = nc - 1 - c;
    if (reverse_all) {
      r = nr - 1 - r;
      c = nc - 1 - c;
    }
    const cv::Point2f& p = grid[r * nc + c];
    out.corners.emplace_back(k, Eigen::Vector2d(p.x, p.y));
  }
  return out;
}

}  // namespace

std::map<std::string, int> ArucoDictionaryMarkerCounts() {
  std::map<std::string, int> out;
  for (const auto& [name, id] : Dictionaries()) {
    out[name] = cv::aruco::getPredefinedDictionary(id)->bytesList.rows;
  }
  return out;
}

std::vector<cv::Mat> CharucoMarkerImages(const TagBoard& board) {
  const cv::Ptr<cv::aruco::CharucoBoard> charuco = MakeCharuco(board);
  const int bits = charuco->dictionary->markerSize + 2;
  std::vector<cv::Mat> out;
  for (const int id : charuco->ids) {
    cv::Mat code;
    cv::aruco::drawMarker(charuco->dictionary, id, bits, code, /*borderBits=*/1);
    out.push_back(code);
  }
  return out;
}

PointBoardDetection DetectPointBoard(const cv::Mat& gray, const TagBoard& board, int face,
                                     CopySearch copies) {
  switch (board.kind) {
    case BoardKind::kCharuco:
      return DetectCharuco(gray, board);
    case BoardKind::kChessboard:
      return DetectChessboard(gray, board, face, copies);
    case BoardKind::kAprilTag:
      break;
  }
  throw std::invalid_argument("DetectPointBoard: an AprilTag board");
}

}  // namespace rtscalib::detect

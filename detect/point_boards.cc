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
  // issue 25539, fixed by pull request 28380); measured +0.50, +0.49 px here
  // (tests/detect/point_boards_test.cc). cornerSubPix converges to the
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

PointBoardDetection DetectChessboard(const cv::Mat& gray, const TagBoard& board, int face) {
  const int nc = board.cols - 1, nr = board.rows - 1;
  std::vector<cv::Point2f> grid;
  PointBoardDetection out;
  // Without CALIB_CB_ACCURACY: its corners were 0.13 px RMS off on rendered
  // photos and it cost 0.3 s more per 1280 x 960 image; cornerSubPix from
  // either start converges to the same saddles, 0.06 px RMS
  // (tests/render/point_boards_test.cc, docs/photos.md).
  // The exhaustive search first; on real photos it misses a few boards that
  // the plain search finds (OpenCV's left11.jpg: blur and a steep view), so
  // that one is tried next (~0.5 s more on a 1280 x 960 photo without a
  // board). Not the classic quad detector: on a photo without a board it
  // can search for minutes (540 s on 1280 x 960 noise, 9.5 s with its fast
  // check). Either grid is refined below.
  const cv::Size size(nc, nr);
  // Most photos of a session show no chessboard (another board, or this one
  // out of view), and there both searches below run to the end. OpenCV's
  // quick check (the classic detector's CALIB_CB_FAST_CHECK: quads of the
  // right count at a few thresholds) answers in milliseconds. With it the
  // 50 rendered photos of three ChArUco boards and a chessboard are
  // detected in 2.7 s instead of 20.2 s (Release, RenderedPointBoards'
  // own output), every visible corner still found. It keeps every board of
  // OpenCV's 26 sample photos of a real camera
  // (PointBoards.QuickCheckKeepsEveryChessboardOfOpenCvsSamplePhotos).
  if (!cv::checkChessboard(gray, size)) return out;
  bool found = cv::findChessboardCornersSB(gray, size, grid,
                                           cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_EXHAUSTIVE);
  if (!found) {
    grid.clear();
    found = cv::findChessboardCornersSB(gray, size, grid, cv::CALIB_CB_NORMALIZE_IMAGE);
  }
  if (!found || static_cast<int>(grid.size()) != nc * nr) return out;
  // A second copy: the found board masked out (its hull, grown by one
  // square, filled with the photo's mean grey) and the photo searched again
  // (the fast non-exhaustive search: a second whole board would be as clear).
  {
    std::vector<cv::Point2f> hull_f;
    cv::convexHull(grid, hull_f);
    const cv::Point2f centre = std::accumulate(hull_f.begin(), hull_f.end(), cv::Point2f(0, 0)) *
                               (1.0f / static_cast<float>(hull_f.size()));
    double step = 1e9;
    for (int k = 0; k + 1 < nc * nr; ++k) {
      if (k % nc != nc - 1) step = std::min(step, static_cast<double>(cv::norm(grid[k + 1] - grid[k])));
    }
    std::vector<cv::Point> hull;
    for (const cv::Point2f& p : hull_f) {
      const cv::Point2f out_dir = p - centre;
      const float len = std::max(1e-3f, static_cast<float>(cv::norm(out_dir)));
      hull.emplace_back(p + out_dir * static_cast<float>(1.5 * step / len));
    }
    cv::Mat masked = gray.clone();
    cv::fillConvexPoly(masked, hull, cv::Scalar(cv::mean(gray)[0]));
    std::vector<cv::Point2f> second;
    if (cv::findChessboardCornersSB(masked, size, second, cv::CALIB_CB_NORMALIZE_IMAGE)) {
      out.duplicated = true;
      return out;
    }
  }
  double square_px = 1e9;
  for (int k = 0; k + 1 < nc * nr; ++k) {
    if (k % nc != nc - 1) {
      square_px = std::min(square_px, static_cast<double>(cv::norm(grid[k + 1] - grid[k])));
    }
  }
  RefineSaddles(gray, square_px, 1.0, &grid);
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

PointBoardDetection DetectPointBoard(const cv::Mat& gray, const TagBoard& board, int face) {
  switch (board.kind) {
    case BoardKind::kCharuco:
      return DetectCharuco(gray, board);
    case BoardKind::kChessboard:
      return DetectChessboard(gray, board, face);
    case BoardKind::kAprilTag:
      break;
  }
  throw std::invalid_argument("DetectPointBoard: an AprilTag board");
}

}  // namespace rtscalib::detect

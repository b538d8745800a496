#include "detect/point_boards.h"

#include <opencv2/aruco/charuco.hpp>
#include <opencv2/calib3d.hpp>

#include <algorithm>
#include <cmath>
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
  if (!cv::findChessboardCornersSB(gray, cv::Size(nc, nr), grid,
                                   cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_EXHAUSTIVE) ||
      static_cast<int>(grid.size()) != nc * nr) {
    return out;
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
  // Face 1: rows to the right (+u), columns down (+v); face 2: turned by 180
  // degrees. A grid returned the other way round is reversed (OpenCV may
  // start at either end); anything else is a board seen sideways.
  const double sign = face == 2 ? -1.0 : 1.0;
  const bool mostly_horizontal = std::abs(along_row.x()) > std::abs(along_row.y());
  if (!mostly_horizontal || along_row.x() * down_cols.y() - along_row.y() * down_cols.x() <= 0) {
    out.misoriented = true;  // sideways, or mirrored (a print seen from its back)
    return out;
  }
  const bool reverse = sign * along_row.x() < 0;
  for (int k = 0; k < nc * nr; ++k) {
    const cv::Point2f& p = grid[reverse ? nc * nr - 1 - k : k];
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

// ChArUco and chessboards (TagBoard::IsPointBoard, libcalib/model/targets.h)
// found in a photo by OpenCV's own detectors: cv::aruco::detectMarkers +
// cv::aruco::interpolateCornersCharuco for ChArUco,
// cv::findChessboardCornersSB for chessboards, both followed by
// cv::cornerSubPix to the saddle points. Pixel positions in OpenCV's
// convention, which is SPEC 2's (pixel (i, j) centred at (i, j)).
//
// Targets: inner corner k = r (cols - 1) + c of the board (targets.h), as
// pixels.csv target first_id + k, corner 0. ChArUco's corner ids are k
// (OpenCV's CharucoBoard: id 0 at the top-left inner corner of the upright
// printed board, row by row). A chessboard has no identity, only a grid.
// A surveyed chessboard (pose given) is numbered as printed, its
// orientation fixed from the instrument's geometry, never from a model: the
// camera does not roll, so in face 1 the board's rows run to the image's
// right and its columns down, and in face 2 (the telescope transited) the
// board appears turned by 180 degrees; a grid whose orientation is neither
// (a board hung sideways) is not used and counted. A chessboard whose pose
// is estimated (SPEC 7.1) may be seen in any orientation: its pose absorbs
// the numbering (point_boards.cc says which of the grid's numberings is
// kept). A chessboard is only found whole (all inner corners in the photo),
// and only once: after it is found, the photo is searched again with the
// board masked out, and a second board makes the detection void.
#pragma once

#include <Eigen/Core>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "libcalib/model/targets.h"

namespace rtscalib::detect {

struct PointBoardDetection {
  std::vector<std::pair<int, Eigen::Vector2d>> corners;  // inner corner k, pixel
  bool misoriented = false;  // chessboard found, but in no orientation the faces allow
  // A chessboard found twice in the photo (two printed copies, or a board
  // and its reflection): neither can be told from the other, none is used.
  bool duplicated = false;
};

// Whether a chessboard's second copy is looked for. It matters where the
// board's corners are tied to more than the photo: a surveyed board
// (pose_known), whose corners have world coordinates, and a placement that
// other photos share, whose one pose the photos hold together; a copy found
// instead of the board would give them wrong corners. A photo whose
// placement is its own (a board held by hand, OpenCV's calibration
// tutorial) gets a pose of its own for whichever copy is found, as in
// calibrateCamera, and the search, which costs more than finding the board
// where the board's squares are small (the copy's quick check runs on the
// photo itself), is skipped.
enum class CopySearch { kSearch, kSkip };

// `gray` is CV_8UC1; `face` 1 or 2 (chessboard orientation). Throws
// std::invalid_argument for a ChArUco dictionary OpenCV does not know or
// one with too few markers for the board.
PointBoardDetection DetectPointBoard(const cv::Mat& gray, const TagBoard& board, int face,
                                     CopySearch copies = CopySearch::kSearch);

// OpenCV's predefined ArUco dictionaries by name (DICT_4X4_50, ...) with
// their numbers of markers.
std::map<std::string, int> ArucoDictionaryMarkerCounts();

// The markers of a ChArUco board as cv::aruco::CharucoBoard::create makes
// them (what DetectPointBoard looks for): marker i sits in the i-th white
// square counted row by row from the top-left (square (r, c) is white when
// r + c is odd), centred, `marker_size` wide; entry i is its printed image,
// the dictionary code of the board's i-th marker id with a black border of
// one bit, one pixel per bit (CV_8UC1, 0 = ink, 255 = paper, side
// markerSize + 2). Throws like DetectPointBoard.
std::vector<cv::Mat> CharucoMarkerImages(const TagBoard& board);

}  // namespace rtscalib::detect

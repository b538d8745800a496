// Known calibration targets: boards of AprilTags placed in the reference frame.
//
// A board is a grid of `rows` x `cols` tags of one family with consecutive ids
// starting at `first_id`, row by row. In the board frame the tags lie in the
// z = 0 plane, x to the right along a row, y down along a column, z out of the
// back of the board (so a camera looking at the printed side looks along +z);
// row 0 is the board's top row. Tag (r, c)'s black square has edge `tag_size`
// and its top-left corner at ((tag_size + spacing) * c, (tag_size + spacing) * r).
// Corner order of one tag follows libapriltag's detection order (see
// detect/detector.h): corner 0 = bottom-left, 1 = bottom-right, 2 = top-right,
// 3 = top-left, as seen in an upright image of the printed tag.
//
// Which tag an id names (`ids_from`, read in GridOf alone): SPEC 7 counts ids
// from the top-left tag, left to right, then down (tag first_id + i is row
// i / cols from the top). Kalibr's AprilGrid counts from the bottom-left tag,
// left to right, then UP (its target frame has y up the printed page): tag
// first_id + i is row i / cols from the bottom, i.e. row rows - 1 - i / cols
// of the board frame. Ids stay the print's, coordinates are this frame's.
//
// `border_bits`: the width of a tag's black border in code bits (SPEC 7.2).
// libapriltag's own prints have 1; Kalibr's AprilGrid has 2 (the code bits
// sit one bit further in, the quad of a tag36h11 tag is 10 bits wide instead
// of 8) and small black squares of side `spacing` where four tags' corners
// meet, touching each corner. `tag_size` is always the outer edge of the
// black border.
//
// A board need not be flat (the catalogue effect `board_warp`, mrcal's
// calobject_warp): its points leave the z = 0 plane by
//   z = wx (1 - xr^2) + wy (1 - yr^2)   [m],  `warp` = {wx, wy},
// with xr, yr the point's x and y mapped onto [-1, 1] across the extent of
// the board's points (AprilTag boards: the tags' outer corners, 0 .. Width()
// and 0 .. Height(); boards of points: their first to last inner corner):
// two parabolas, zero along the board's edges and wx + wy at its centre,
// positive out of its back (away from a camera that faces the printed
// side). A flat board has warp {0, 0}; a bent one bends alike wherever it
// is put, so the warp belongs to the board, not to a pose of it.
//
// `ref_from_board` is the board's pose when `pose_known` (surveyed, or the
// simulation's truth). A board of a real instrument's targets.yaml without a
// `pose` has `pose_known = false` (SPEC 7): its pose is to be estimated and
// `ref_from_board` is only a placeholder (identity) until then.
#pragma once

#include <Eigen/Core>
#include <array>
#include <map>
#include <string>
#include <vector>

#include "libcalib/geometry/rotation.h"

namespace rtscalib {

// The kinds of board (targets.yaml `type`). An AprilTag board's targets are
// its tags, four corners each. ChArUco and chessboards (OpenCV's detectors)
// are boards of points: `rows` x `cols` squares of `square_size`, whose
// (rows - 1) x (cols - 1) inner corners are the targets, one corner (0)
// each: target first_id + k for inner corner k = r (cols - 1) + c at
// ((c + 1) square_size, (r + 1) square_size, 0), r from the board's top row,
// c from its left column (ChArUco: k is OpenCV's charuco corner id; the
// top-left square is black, as cv::aruco::CharucoBoard draws it).
enum class BoardKind { kAprilTag, kCharuco, kChessboard };

// Where a board's tag ids start (see above).
enum class IdOrigin { kTopLeft, kBottomLeft };

// A tag's place in its board's grid: row r from the board's top, column c
// from its left.
struct GridCell {
  int row = 0, col = 0;
};

struct TagBoard {
  BoardKind kind = BoardKind::kAprilTag;
  std::string family = "tag36h11";  // ChArUco: the ArUco dictionary (DICT_4X4_50, ...)
  int first_id = 0;
  int rows = 3;
  int cols = 4;
  double tag_size = 0.08;  // edge of the black square [m] (AprilTag)
  double spacing = 0.02;   // white gap between neighbouring tags [m] (AprilTag)
  int border_bits = 1;     // black border of a tag [code bits] (AprilTag)
  IdOrigin ids_from = IdOrigin::kTopLeft;  // (AprilTag)
  double square_size = 0;  // [m] (ChArUco, chessboard)
  double marker_size = 0;  // [m] (ChArUco)
  Rigid3 ref_from_board;
  bool pose_known = true;
  std::array<double, 2> warp{0, 0};  // {wx, wy} [m], above

  bool IsPointBoard() const { return kind != BoardKind::kAprilTag; }
  // A board of 2-bit tags is Kalibr's AprilGrid (SPEC 7.2): printed with a
  // black square at every crossing of the gaps between its tags.
  bool HasCornerSquares() const { return kind == BoardKind::kAprilTag && border_bits == 2; }
  // Corners per target: 4 for a tag, 1 for a point board's inner corner.
  int CornersPerTarget() const { return IsPointBoard() ? 1 : 4; }
  int NumTags() const { return IsPointBoard() ? (rows - 1) * (cols - 1) : rows * cols; }
  int LastId() const { return first_id + NumTags() - 1; }
  bool HasId(int id) const { return id >= first_id && id <= LastId(); }
  // The grid cell of tag `index` (0 .. NumTags-1, id first_id + index) of an
  // AprilTag board, by `ids_from`; and the index of a cell.
  GridCell GridOf(int index) const {
    const int r = index / cols, c = index % cols;
    return {ids_from == IdOrigin::kBottomLeft ? rows - 1 - r : r, c};
  }
  int IndexOf(const GridCell& cell) const {
    const int r = ids_from == IdOrigin::kBottomLeft ? rows - 1 - cell.row : cell.row;
    return r * cols + cell.col;
  }
  // The four corners of tag `index` (0 .. NumTags-1) in the board frame, on
  // the flat board (z = 0); for a point board all four are its inner corner
  // `index`.
  std::array<Eigen::Vector3d, 4> FlatCornersInBoard(int index) const {
    if (IsPointBoard()) {
      const int r = index / (cols - 1), c = index % (cols - 1);
      const Eigen::Vector3d p(square_size * (c + 1), square_size * (r + 1), 0);
      return {p, p, p, p};
    }
    const GridCell cell = GridOf(index);
    const double x0 = (tag_size + spacing) * cell.col, y0 = (tag_size + spacing) * cell.row;
    return {Eigen::Vector3d(x0, y0 + tag_size, 0), Eigen::Vector3d(x0 + tag_size, y0 + tag_size, 0),
            Eigen::Vector3d(x0 + tag_size, y0, 0), Eigen::Vector3d(x0, y0, 0)};
  }
  // The extent of the board's points in x and y [m]: {x_min, x_max, y_min, y_max}.
  std::array<double, 4> PointsExtent() const {
    if (IsPointBoard()) {
      return {square_size, square_size * (cols - 1), square_size, square_size * (rows - 1)};
    }
    return {0.0, Width(), 0.0, Height()};
  }
  // The warp's shape at a flat board point: {1 - xr^2, 1 - yr^2} (above); 0
  // along an axis on which the points do not extend (one column of inner
  // corners).
  Eigen::Vector2d WarpShape(const Eigen::Vector3d& flat) const {
    const std::array<double, 4> e = PointsExtent();
    auto shape = [](double v, double lo, double hi) {
      if (!(hi > lo)) return 0.0;
      const double t = 2.0 * (v - lo) / (hi - lo) - 1.0;
      return 1.0 - t * t;
    };
    return {shape(flat.x(), e[0], e[1]), shape(flat.y(), e[2], e[3])};
  }
  // The four corners of tag `index` in the board frame, warped (above).
  std::array<Eigen::Vector3d, 4> CornersInBoard(int index) const {
    std::array<Eigen::Vector3d, 4> out = FlatCornersInBoard(index);
    if (warp[0] != 0 || warp[1] != 0) {
      for (Eigen::Vector3d& p : out) p.z() = WarpShape(p).dot(Eigen::Vector2d(warp[0], warp[1]));
    }
    return out;
  }
  // Width and height of the printed pattern [m].
  double Width() const {
    return IsPointBoard() ? cols * square_size : cols * tag_size + (cols - 1) * spacing;
  }
  double Height() const {
    return IsPointBoard() ? rows * square_size : rows * tag_size + (rows - 1) * spacing;
  }
  Eigen::Vector3d CentreInRef() const {
    return ref_from_board * Eigen::Vector3d(Width() / 2, Height() / 2, 0);
  }
};

struct TargetCorner {
  int target = 0;     // tag id
  int corner = 0;     // 0..3
  Eigen::Vector3d X;  // reference frame [m]
};

struct TargetScene {
  std::vector<TagBoard> boards;

  std::vector<TargetCorner> AllCorners() const {
    std::vector<TargetCorner> out;
    for (const TagBoard& b : boards) {
      for (int i = 0; i < b.NumTags(); ++i) {
        const auto corners = b.CornersInBoard(i);
        for (int k = 0; k < b.CornersPerTarget(); ++k)
          out.push_back({b.first_id + i, k, b.ref_from_board * corners[k]});
      }
    }
    return out;
  }
};

// SPEC 7.1: the scene of each placement of a session whose boards were moved
// between sets of shots (the same boards, other poses), by placement name;
// "" is the one placement of a session without placements.
using PlacedScenes = std::map<std::string, TargetScene>;

}  // namespace rtscalib

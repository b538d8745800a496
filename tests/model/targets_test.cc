#include "libcalib/model/targets.h"

#include <gtest/gtest.h>

#include <map>
#include <set>

namespace rtscalib {
namespace {

// Sums and products of a few decimetre-scale numbers: round-off only.
constexpr double kTargetsRoundOff = 1e-14;

TagBoard Board(int first_id, int rows, int cols, double tag, double spacing) {
  TagBoard b;
  b.first_id = first_id;
  b.rows = rows;
  b.cols = cols;
  b.tag_size = tag;
  b.spacing = spacing;
  return b;
}

TEST(Targets, TagTopLeftCornerFollowsTheSpecLayout) {
  // SPEC 7: tag (r, c)'s black square has its top-left corner at
  // ((tag + spacing) c, (tag + spacing) r) in the board frame, z = 0; tags
  // are row-major (index = r * cols + c), row 0 at the board's top.
  const TagBoard b = Board(0, 3, 4, 0.06, 0.015);
  ASSERT_EQ(b.NumTags(), 12);
  for (int r = 0; r < b.rows; ++r) {
    for (int c = 0; c < b.cols; ++c) {
      const auto k = b.CornersInBoard(r * b.cols + c);
      const Eigen::Vector3d top_left(0.075 * c, 0.075 * r, 0.0);
      // Corner 3 is the top-left one (libapriltag's order, SPEC 7).
      EXPECT_LT((k[3] - top_left).norm(), kTargetsRoundOff) << r << "," << c;
      for (const auto& p : k) EXPECT_EQ(p.z(), 0.0);
    }
  }
}

TEST(Targets, CornerOrderIsBottomLeftBottomRightTopRightTopLeft) {
  // Board frame: x to the right along a row, y DOWN a column. "Bottom" of the
  // upright printed tag is therefore the larger y, "right" the larger x.
  const TagBoard b = Board(0, 2, 2, 0.1, 0.02);
  const auto k = b.CornersInBoard(3);  // tag (1, 1): top-left at (0.12, 0.12)
  const double x0 = 0.12, y0 = 0.12, s = 0.1;
  EXPECT_LT((k[0] - Eigen::Vector3d(x0, y0 + s, 0)).norm(), kTargetsRoundOff);      // bottom-left
  EXPECT_LT((k[1] - Eigen::Vector3d(x0 + s, y0 + s, 0)).norm(), kTargetsRoundOff);  // bottom-right
  EXPECT_LT((k[2] - Eigen::Vector3d(x0 + s, y0, 0)).norm(), kTargetsRoundOff);      // top-right
  EXPECT_LT((k[3] - Eigen::Vector3d(x0, y0, 0)).norm(), kTargetsRoundOff);          // top-left
  // The edges are tag_size long and the square is closed.
  for (int i = 0; i < 4; ++i) EXPECT_NEAR((k[(i + 1) % 4] - k[i]).norm(), s, kTargetsRoundOff);
}

TEST(Targets, CornerOrderAsSeenByACameraFacingThePrintedSide) {
  // SPEC 7: a camera facing the printed side looks along the board's +z.
  // With the camera frame of SPEC 2 (x = image right, y = image down, z out of
  // the lens) and camera axes parallel to the board's, a pinhole image of the
  // tag shows corner 0 bottom-left (smallest u, largest v), 1 bottom-right,
  // 2 top-right, 3 top-left; and the order 0 -> 1 -> 2 -> 3 runs
  // counter-clockwise on screen (clockwise in image coordinates, v down).
  const TagBoard b = Board(0, 1, 1, 0.2, 0.05);
  const auto k = b.CornersInBoard(0);
  const Eigen::Vector3d camera_in_board(0.1, 0.1, -2.0);  // 2 m in front of the printed side
  const double f = 1000.0, cx = 640.0, cy = 480.0;
  Eigen::Vector2d uv[4];
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector3d x_cam = k[i] - camera_in_board;  // cam_from_board = translation only
    ASSERT_GT(x_cam.z(), 0.0) << "the printed side must be in front of the camera";
    uv[i] = Eigen::Vector2d(f * x_cam.x() / x_cam.z() + cx, f * x_cam.y() / x_cam.z() + cy);
  }
  EXPECT_LT(uv[0].x(), uv[1].x());  // 0 left of 1
  EXPECT_GT(uv[0].y(), uv[3].y());  // 0 below 3
  EXPECT_GT(uv[1].y(), uv[2].y());  // 1 below 2
  EXPECT_LT(uv[3].x(), uv[2].x());  // 3 left of 2
  EXPECT_NEAR(uv[0].x(), uv[3].x(), 1e-9);
  EXPECT_NEAR(uv[0].y(), uv[1].y(), 1e-9);
  // Signed area in image coordinates (v down): negative for a polygon that
  // is counter-clockwise on screen.
  double area2 = 0;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector2d& p = uv[i];
    const Eigen::Vector2d& q = uv[(i + 1) % 4];
    area2 += p.x() * q.y() - q.x() * p.y();
  }
  EXPECT_LT(area2, 0.0);
  // The board frame is right-handed: z = x cross y, out of the back.
  const Eigen::Vector3d ex = (k[1] - k[0]).normalized(), ey = (k[0] - k[3]).normalized();
  EXPECT_LT((ex.cross(ey) - Eigen::Vector3d::UnitZ()).norm(), kTargetsRoundOff);
}

TEST(Targets, CentreInRefIsTheBoardMiddleMovedByThePose) {
  TagBoard b = Board(0, 3, 4, 0.08, 0.02);
  // Width 4 * 0.08 + 3 * 0.02 = 0.38, height 3 * 0.08 + 2 * 0.02 = 0.28.
  EXPECT_LT((b.CentreInRef() - Eigen::Vector3d(0.19, 0.14, 0)).norm(), kTargetsRoundOff);
  b.ref_from_board = Rigid3::FromEuler({0.3, -0.2, 1.0}, {1.0, 2.0, 3.0});
  const Eigen::Vector3d expected = b.ref_from_board * Eigen::Vector3d(0.19, 0.14, 0);
  EXPECT_LT((b.CentreInRef() - expected).norm(), kTargetsRoundOff);
  // The centre is the mean of all the board's corners (the layout is symmetric).
  TargetScene scene;
  scene.boards.push_back(b);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  const auto corners = scene.AllCorners();
  for (const auto& c : corners) mean += c.X;
  mean /= static_cast<double>(corners.size());
  EXPECT_LT((mean - expected).norm(), 1e-12);
}

TEST(Targets, AllCornersCarryIdsCornersAndReferencePositions) {
  TargetScene scene;
  scene.boards.push_back(Board(0, 2, 3, 0.05, 0.01));
  TagBoard second = Board(48, 1, 2, 0.1, 0.025);
  second.ref_from_board = Rigid3::FromEuler({M_PI / 2, 0.0, 0.4}, {-1.0, 5.0, 0.2});
  scene.boards.push_back(second);

  const auto all = scene.AllCorners();
  ASSERT_EQ(all.size(), 4u * (6 + 2));
  std::map<int, int> per_tag;
  std::set<std::pair<int, int>> unique;
  for (const TargetCorner& c : all) {
    ++per_tag[c.target];
    unique.insert({c.target, c.corner});
    EXPECT_GE(c.corner, 0);
    EXPECT_LE(c.corner, 3);
  }
  EXPECT_EQ(unique.size(), all.size());
  // Consecutive ids from first_id, row-major.
  const std::set<int> ids{0, 1, 2, 3, 4, 5, 48, 49};
  ASSERT_EQ(per_tag.size(), ids.size());
  for (const auto& [id, n] : per_tag) {
    EXPECT_TRUE(ids.count(id)) << id;
    EXPECT_EQ(n, 4) << id;
  }
  // Each entry is its board's corner moved by ref_from_board.
  for (const TargetCorner& c : all) {
    const TagBoard& b = c.target >= 48 ? scene.boards[1] : scene.boards[0];
    const Eigen::Vector3d expected =
        b.ref_from_board * b.CornersInBoard(c.target - b.first_id)[c.corner];
    EXPECT_LT((c.X - expected).norm(), kTargetsRoundOff) << c.target << "/" << c.corner;
  }
  // Tag 4 = row 1, column 1 of the first board (3 columns): top-left corner
  // at (0.06, 0.06, 0) in the identity-posed board.
  bool found = false;
  for (const TargetCorner& c : all) {
    if (c.target == 4 && c.corner == 3) {
      EXPECT_LT((c.X - Eigen::Vector3d(0.06, 0.06, 0)).norm(), kTargetsRoundOff);
      found = true;
    }
  }
  EXPECT_TRUE(found);
}

// board_warp (TagBoard::warp) is mrcal's calobject_warp: for corner (i, j)
// of a W x H corner grid, mrcal adds warp.x 4 xr (1 - xr) + warp.y 4 yr (1 -
// yr) to the board-frame z, xr = i / (W - 1), yr = j / (H - 1) (mrcal.c).
// On the mrcal tour's board (10 x 10 inner corners of 0.077 m, mrcal's
// corner (i, j) = our inner corner row j, column i, mrcal's x along a row as
// ours) the two agree corner by corner, and both put +z out of the board's
// back.
TEST(Targets, WarpIsMrcalsCalobjectWarpOnItsBoard) {
  TagBoard b;
  b.kind = BoardKind::kChessboard;
  b.rows = b.cols = 11;  // squares: 10 x 10 inner corners
  b.square_size = 0.077;
  b.warp = {-0.00104, 0.00052};  // mrcal's OPENCV8 solution of the tour (PROVENANCE.md)
  for (int j = 0; j < 10; ++j) {
    for (int i = 0; i < 10; ++i) {
      const double xr = i / 9.0, yr = j / 9.0;
      const double mrcal = b.warp[0] * 4 * xr * (1 - xr) + b.warp[1] * 4 * yr * (1 - yr);
      const Eigen::Vector3d p = b.CornersInBoard(j * 10 + i)[0];
      EXPECT_NEAR(p.z(), mrcal, kTargetsRoundOff) << i << "," << j;
      // The warp moves corners along z only.
      EXPECT_EQ(p.head<2>(), b.FlatCornersInBoard(j * 10 + i)[0].head<2>());
    }
  }
}

TEST(Targets, WarpIsZeroAlongTheEdgesAndWxPlusWyAtTheCentre) {
  // A tag board: its points span 0 .. Width() x 0 .. Height(); the middle
  // tag's centre is the board's centre when rows and cols are odd.
  TagBoard b = Board(0, 3, 3, 0.1, 0.02);
  b.warp = {0.002, -0.0005};
  const Eigen::Vector3d centre(0.5 * b.Width(), 0.5 * b.Height(), 0);
  EXPECT_NEAR(b.WarpShape(centre)[0], 1.0, kTargetsRoundOff);
  EXPECT_NEAR(b.WarpShape(centre)[1], 1.0, kTargetsRoundOff);
  // Tag 0's top-left corner is the board's corner: no deflection there.
  EXPECT_NEAR(b.CornersInBoard(0)[3].z(), 0.0, kTargetsRoundOff);
  // Tag 8's bottom-right corner likewise; tag 1's top-right corner lies on
  // the top edge, so only the x term is left.
  EXPECT_NEAR(b.CornersInBoard(8)[1].z(), 0.0, kTargetsRoundOff);
  const Eigen::Vector3d top = b.FlatCornersInBoard(1)[2];
  const double xr = 2 * top.x() / b.Width() - 1;
  EXPECT_NEAR(b.CornersInBoard(1)[2].z(), b.warp[0] * (1 - xr * xr), kTargetsRoundOff);
  // One column of inner corners has no extent across: no term there.
  TagBoard narrow;
  narrow.kind = BoardKind::kChessboard;
  narrow.rows = 5;
  narrow.cols = 2;
  narrow.square_size = 0.03;
  narrow.warp = {0.001, 0.0};
  EXPECT_EQ(narrow.CornersInBoard(0)[0].z(), 0.0);
}

TEST(Targets, DefaultsAndEmptyScene) {
  const TagBoard b;
  EXPECT_EQ(b.family, "tag36h11");
  EXPECT_EQ(b.NumTags(), b.rows * b.cols);
  EXPECT_TRUE(TargetScene().AllCorners().empty());
}

}  // namespace
}  // namespace rtscalib

namespace rtscalib {
namespace {

// Kalibr's id layout (targets.h `ids_from`): tag first_id + i in row
// rows - 1 - i / cols; GridOf and IndexOf invert each other either way.
TEST(Targets, IdsFromTheBottomLeftCountRowsUpwards) {
  TagBoard b;
  b.rows = 3;
  b.cols = 4;
  for (const IdOrigin origin : {IdOrigin::kTopLeft, IdOrigin::kBottomLeft}) {
    b.ids_from = origin;
    for (int i = 0; i < b.NumTags(); ++i) EXPECT_EQ(b.IndexOf(b.GridOf(i)), i);
  }
  b.ids_from = IdOrigin::kBottomLeft;
  EXPECT_EQ(b.GridOf(0).row, 2);
  EXPECT_EQ(b.GridOf(0).col, 0);
  EXPECT_EQ(b.GridOf(5).row, 1);
  EXPECT_EQ(b.GridOf(5).col, 1);
  EXPECT_EQ(b.GridOf(11).row, 0);
  // Tag 4 sits above tag 0: smaller y in the board frame (y down).
  EXPECT_LT(b.CornersInBoard(4)[3].y(), b.CornersInBoard(0)[3].y());
}

}  // namespace
}  // namespace rtscalib

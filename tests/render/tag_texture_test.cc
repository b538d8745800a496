// Texture geometry: exact, no rendering.
#include "render/tag_texture.h"

#include <gtest/gtest.h>

#include <cmath>

#include <opencv2/aruco/charuco.hpp>

#include "detect/point_boards.h"
#include "detect/tag_family.h"

namespace rtscalib::render {
namespace {

using detect::GetTagFamilyInfo;
using detect::TagCodeImage;
using detect::TagFamilyInfo;

// The texel at continuous texel coordinates just inside/outside a point.
uint8_t TexelAt(const TagTexture& tex, const Eigen::Vector2d& t, double dx, double dy) {
  return tex.image.at<uint8_t>(static_cast<int>(std::floor(t.y() + dy)),
                               static_cast<int>(std::floor(t.x() + dx)));
}

TagBoard Board(const std::string& family, double spacing) {
  TagBoard b;
  b.family = family;
  b.rows = 2;
  b.cols = 3;
  b.tag_size = 0.08;
  b.spacing = spacing;
  return b;
}

// Every tag corner of the board must land exactly on a texel boundary, with
// the quad exactly width_at_border bits of pixels_per_bit texels wide; inside
// the corner is the black border, outside the white quiet zone (tag36h11).
void ExpectExactCorners(const TagBoard& board, const TagTexture& tex) {
  const TagFamilyInfo info = GetTagFamilyInfo(board.family);
  const double quad_texels = info.width_at_border * tex.pixels_per_bit;
  for (int i = 0; i < board.NumTags(); ++i) {
    const auto corners = board.CornersInBoard(i);
    std::array<Eigen::Vector2d, 4> t;
    for (int k = 0; k < 4; ++k) {
      t[k] = tex.TexelFromBoard(corners[k].x(), corners[k].y());
      // Exact up to floating point: the breakpoints are the code images' edges.
      EXPECT_NEAR(t[k].x(), std::round(t[k].x()), 1e-9) << "tag " << i << " corner " << k;
      EXPECT_NEAR(t[k].y(), std::round(t[k].y()), 1e-9) << "tag " << i << " corner " << k;
      EXPECT_EQ(static_cast<long>(std::lround(t[k].x())) % tex.pixels_per_bit, 0);
      EXPECT_EQ(static_cast<long>(std::lround(t[k].y())) % tex.pixels_per_bit, 0);
    }
    // TargetCorner order: 0 bottom-left, 1 bottom-right, 2 top-right, 3 top-left.
    EXPECT_NEAR(t[1].x() - t[0].x(), quad_texels, 1e-9);
    EXPECT_NEAR(t[0].y() - t[3].y(), quad_texels, 1e-9);
    EXPECT_NEAR(t[2].x() - t[3].x(), quad_texels, 1e-9);
    EXPECT_NEAR(t[1].y() - t[2].y(), quad_texels, 1e-9);
    // Inside each corner (towards the tag centre) the ink, outside the paper.
    const uint8_t ink = info.reversed_border ? 255 : 0, paper = info.reversed_border ? 0 : 255;
    const double dx[4] = {+0.5, -0.5, -0.5, +0.5}, dy[4] = {-0.5, -0.5, +0.5, +0.5};
    for (int k = 0; k < 4; ++k) {
      EXPECT_EQ(TexelAt(tex, t[k], dx[k], dy[k]), ink) << "tag " << i << " corner " << k;
      EXPECT_EQ(TexelAt(tex, t[k], -dx[k], -dy[k]), paper) << "tag " << i << " corner " << k;
    }
  }
}

TEST(TagTextureTest, CornersLandOnTexelBoundaries) {
  const TagBoard board = Board("tag36h11", 0.02);
  const TagTexture tex = MakeTagTexture(board);
  EXPECT_EQ(tex.pixels_per_bit, 16);
  EXPECT_DOUBLE_EQ(tex.bit_size, 0.01);
  ExpectExactCorners(board, tex);
  // White margin of one bit around 3 x 2 code images of 10 bits, no gaps.
  EXPECT_EQ(tex.image.cols, (2 + 3 * 10) * 16);
  EXPECT_EQ(tex.image.rows, (2 + 2 * 10) * 16);
  EXPECT_NEAR(tex.x_min(), -0.02, 1e-12);
  EXPECT_NEAR(tex.x_max(), 2 * 0.1 + 0.09 + 0.01, 1e-12);
}

TEST(TagTextureTest, SpacingThatIsNoWholeNumberOfBitsStaysExact) {
  const TagBoard board = Board("tag36h11", 0.0337);
  ExpectExactCorners(board, MakeTagTexture(board));
}

TEST(TagTextureTest, CodeImageMatchesLibapriltagBitForBit) {
  const TagBoard board = Board("tag25h9", 0.05);
  TagTextureOptions options;
  options.pixels_per_bit = 4;
  const TagTexture tex = MakeTagTexture(board, options);
  const TagFamilyInfo info = GetTagFamilyInfo(board.family);
  const double bit = tex.bit_size;
  for (int i = 0; i < board.NumTags(); ++i) {
    const cv::Mat code = TagCodeImage(board.family, board.first_id + i);
    const auto corners = board.CornersInBoard(i);
    const Eigen::Vector3d& top_left = corners[3];
    for (int r = 0; r < info.total_width; ++r) {
      for (int c = 0; c < info.total_width; ++c) {
        // Centre of bit (r, c) on the board, then in the texture.
        const double x = top_left.x() + (c - info.border_offset() + 0.5) * bit;
        const double y = top_left.y() + (r - info.border_offset() + 0.5) * bit;
        const Eigen::Vector2d t = tex.TexelFromBoard(x, y);
        ASSERT_EQ(TexelAt(tex, t, 0, 0), code.at<uint8_t>(r, c))
            << "tag " << i << " bit " << r << "," << c;
      }
    }
  }
}

TEST(TagTextureTest, ReversedBorderFamily) {
  const TagBoard board = Board("tagStandard41h12", 0.07);
  ExpectExactCorners(board, MakeTagTexture(board));
}

TEST(TagTextureTest, InkAndPaperLevels) {
  TagTextureOptions options;
  options.black = 30;
  options.white = 200;
  const TagTexture tex = MakeTagTexture(Board("tag16h5", 0.03), options);
  double lo, hi;
  cv::minMaxLoc(tex.image, &lo, &hi);
  EXPECT_EQ(lo, 30);
  EXPECT_EQ(hi, 200);
}

TEST(TagTextureTest, LargeBoardsLowerTheResolution) {
  TagBoard board = Board("tag36h11", 0.02);
  board.rows = 20;
  board.cols = 29;  // 580 of tag36h11's 587 codes
  TagTextureOptions options;
  options.max_texture_size = 4096;
  const TagTexture tex = MakeTagTexture(board, options);
  EXPECT_LE(std::max(tex.image.cols, tex.image.rows), 4096);
  EXPECT_EQ(tex.pixels_per_bit, 8);  // 292 bits across: 16 texels would need 4672
  ExpectExactCorners(board, tex);
}

TEST(TagTextureTest, RejectsUnprintableBoards) {
  // tagStandard41h12's code image reaches two bits beyond the quad on each
  // side: 4 bits = 6.4 cm of spacing at least.
  EXPECT_THROW(MakeTagTexture(Board("tagStandard41h12", 0.02)), std::invalid_argument);
  EXPECT_THROW(MakeTagTexture(Board("tag99h99", 0.02)), std::invalid_argument);
  TagBoard too_many = Board("tag16h5", 0.02);
  too_many.first_id = 29;  // tag16h5 has 30 codes
  EXPECT_THROW(MakeTagTexture(too_many), std::invalid_argument);
  TagTextureOptions bad;
  bad.pixels_per_bit = 3;
  EXPECT_FALSE(bad.Check().empty());
  EXPECT_THROW(MakeTagTexture(Board("tag36h11", 0.02), bad), std::invalid_argument);
}

TEST(TagTextureTest, PrintedAreaMatchesTheTexture) {
  const TagBoard board = Board("tag36h11", 0.0337);
  const TagTexture tex = MakeTagTexture(board);
  const BoardRect r = PrintedArea(board);
  EXPECT_NEAR(r.x_min, tex.x_min(), 1e-12);
  EXPECT_NEAR(r.x_max, tex.x_max(), 1e-12);
  EXPECT_NEAR(r.y_min, tex.y_min(), 1e-12);
  EXPECT_NEAR(r.y_max, tex.y_max(), 1e-12);
}

// Kalibr's AprilGrid (2-bit tags, SPEC 7.2): a black square of side
// `spacing` at every crossing of the gaps, the outer ones included. At each
// tag corner the ink is inside the tag and diagonally outside it (the
// square), the paper along the tag's two edges outside it (the white ring
// of the code image and the gap); the squares end at the tags' black edges
// and, outside, `spacing` beyond them, with paper beyond that.
TEST(TagTextureTest, AprilGridHasKalibrsSquaresAtEveryCrossing) {
  TagBoard board = Board("tag36h11", 0.024);  // Kalibr's tagSpacing 0.3 of 8 cm tags
  board.border_bits = 2;
  ASSERT_TRUE(board.HasCornerSquares());
  const TagTexture tex = MakeTagTexture(board);
  const double bit = tex.bit_size;
  EXPECT_DOUBLE_EQ(bit, 0.008);
  const double half = 0.25 * bit;  // a quarter bit: well inside a texel run of 16 per bit
  auto at = [&](double x, double y) {
    const Eigen::Vector2d t = tex.TexelFromBoard(x, y);
    return TexelAt(tex, t, 0, 0);
  };
  for (int i = 0; i < board.NumTags(); ++i) {
    const auto corners = board.CornersInBoard(i);
    // TargetCorner order: 0 bottom-left, 1 bottom-right, 2 top-right, 3 top-left;
    // (sx, sy) points out of the tag at corner k.
    const double sx[4] = {-1, +1, +1, -1}, sy[4] = {+1, +1, -1, -1};
    for (int k = 0; k < 4; ++k) {
      const double x = corners[k].x(), y = corners[k].y();
      EXPECT_EQ(at(x - sx[k] * half, y - sy[k] * half), 0) << "inside tag " << i << " corner " << k;
      EXPECT_EQ(at(x + sx[k] * half, y + sy[k] * half), 0) << "square at tag " << i << " corner " << k;
      EXPECT_EQ(at(x + sx[k] * half, y - sy[k] * half), 255) << "beside tag " << i << " corner " << k;
      EXPECT_EQ(at(x - sx[k] * half, y + sy[k] * half), 255) << "beside tag " << i << " corner " << k;
      // The square's far side: `spacing` out along the diagonal, then paper
      // (or the next tag's black, inside the board).
      EXPECT_EQ(at(x + sx[k] * (board.spacing - half), y + sy[k] * (board.spacing - half)), 0)
          << "square at tag " << i << " corner " << k;
    }
  }
  // Beyond an outer square: paper. (The board's top-left square spans
  // [-spacing, 0] in x and y.)
  EXPECT_EQ(at(-board.spacing + half, -board.spacing + half), 0);
  EXPECT_EQ(at(-board.spacing - half, -board.spacing + half), 255);
  EXPECT_EQ(at(-board.spacing + half, -board.spacing - half), 255);
  const BoardRect r = PrintedArea(board);
  EXPECT_NEAR(r.x_min, tex.x_min(), 1e-12);
  EXPECT_NEAR(r.y_max, tex.y_max(), 1e-12);
  EXPECT_LT(r.x_min, -board.spacing);
  // The tags' own bits (black border and code) are the 2-bit family's.
  const TagFamilyInfo info = GetTagFamilyInfo(board.family, 2);
  for (int i = 0; i < board.NumTags(); ++i) {
    const cv::Mat code = TagCodeImage(board.family, board.first_id + i, 2);
    const auto corners = board.CornersInBoard(i);
    for (int row = 0; row < info.width_at_border; ++row) {
      for (int col = 0; col < info.width_at_border; ++col) {
        const double x = corners[3].x() + (col + 0.5) * bit, y = corners[3].y() + (row + 0.5) * bit;
        ASSERT_EQ(at(x, y), code.at<uint8_t>(row + info.border_offset(), col + info.border_offset()))
            << "tag " << i << " bit " << row << "," << col;
      }
    }
  }
}

// ChArUco and chessboards (docs/photos.md): square (r, c) is
// [c s, (c + 1) s] x [r s, (r + 1) s], black when r + c is even.
TagBoard PointBoard(BoardKind kind, int rows, int cols, double square, double marker = 0) {
  TagBoard b;
  b.kind = kind;
  b.family = kind == BoardKind::kCharuco ? "DICT_4X4_50" : "chessboard";
  b.rows = rows;
  b.cols = cols;
  b.square_size = square;
  b.marker_size = marker;
  return b;
}

// Every square's corners land exactly on texel boundaries at multiples of
// pixels_per_bit (so the inner corners, the targets, stay put through the
// first mipmap levels); each square is uniformly black or white next to the
// corner, the top-left one black.
void ExpectExactSquares(const TagBoard& board, const TagTexture& tex) {
  const double s = board.square_size;
  for (int r = 0; r <= board.rows; ++r) {
    for (int c = 0; c <= board.cols; ++c) {
      const Eigen::Vector2d t = tex.TexelFromBoard(c * s, r * s);
      EXPECT_NEAR(t.x(), std::round(t.x()), 1e-9) << r << "," << c;
      EXPECT_NEAR(t.y(), std::round(t.y()), 1e-9) << r << "," << c;
      EXPECT_EQ(std::lround(t.x()) % tex.pixels_per_bit, 0);
      EXPECT_EQ(std::lround(t.y()) % tex.pixels_per_bit, 0);
      // The texels just inside the four squares around the point.
      for (int dr : {-1, 0}) {
        for (int dc : {-1, 0}) {
          const int sr = r + dr, sc = c + dc;
          const bool on_board = sr >= 0 && sc >= 0 && sr < board.rows && sc < board.cols;
          const uint8_t expected = on_board && (sr + sc) % 2 == 0 ? 0 : 255;
          EXPECT_EQ(TexelAt(tex, t, dc + 0.5, dr + 0.5), expected)
              << "square " << sr << "," << sc << " at its corner " << r << "," << c;
        }
      }
    }
  }
}

TEST(TagTextureTest, ChessboardSquaresLandOnTexelBoundaries) {
  const TagBoard board = PointBoard(BoardKind::kChessboard, 6, 9, 0.025);
  const TagTexture tex = MakeTagTexture(board);
  EXPECT_EQ(tex.pixels_per_bit, 16);
  EXPECT_DOUBLE_EQ(tex.bit_size, 0.025 / kChessboardBitsPerSquare);
  ExpectExactSquares(board, tex);
  // A white margin of one square around 9 x 6 squares.
  EXPECT_EQ(tex.image.cols, (2 + 9) * kChessboardBitsPerSquare * 16);
  EXPECT_EQ(tex.image.rows, (2 + 6) * kChessboardBitsPerSquare * 16);
  EXPECT_NEAR(tex.x_min(), -0.025, 1e-12);
  EXPECT_NEAR(tex.x_max(), 10 * 0.025, 1e-12);
  EXPECT_NEAR(tex.y_max(), 7 * 0.025, 1e-12);
  // Only the squares' outline and the margin are breakpoints.
  EXPECT_EQ(tex.x_board.size(), 4u);
  const BoardRect r = PrintedArea(board);
  EXPECT_NEAR(r.x_min, tex.x_min(), 1e-12);
  EXPECT_NEAR(r.x_max, tex.x_max(), 1e-12);
  EXPECT_NEAR(r.y_min, tex.y_min(), 1e-12);
  EXPECT_NEAR(r.y_max, tex.y_max(), 1e-12);
}

// The ChArUco texture against OpenCV's own board: the squares exact, and
// every marker, bit for bit at its bit centres, where CharucoBoard::create
// puts it (objPoints, ids) and as CharucoBoard::draw prints it.
TEST(TagTextureTest, CharucoIsOpenCvsBoard) {
  // 5 x 7 squares of 4 cm, 3 cm markers (6 bits of 5 mm, margins of 1 bit).
  // An even number of rows too: OpenCV's legacy boards of even rows differ.
  for (int rows : {5, 4}) {
    const TagBoard board = PointBoard(BoardKind::kCharuco, rows, 7, 0.04, 0.03);
    const TagTexture tex = MakeTagTexture(board);
    EXPECT_DOUBLE_EQ(tex.bit_size, 0.005);
    ExpectExactSquares(board, tex);
    const BoardRect area = PrintedArea(board);
    EXPECT_NEAR(area.x_min, tex.x_min(), 1e-12);
    EXPECT_NEAR(area.y_max, tex.y_max(), 1e-12);

    const cv::Ptr<cv::aruco::CharucoBoard> cv_board = cv::aruco::CharucoBoard::create(
        board.cols, board.rows, 0.04f, 0.03f,
        cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_50));
    const std::vector<cv::Mat> codes = detect::CharucoMarkerImages(board);
    ASSERT_EQ(codes.size(), cv_board->ids.size());
    ASSERT_EQ(static_cast<int>(codes.size()), board.rows * board.cols / 2);
    for (size_t i = 0; i < codes.size(); ++i) {
      // objPoints: top-left, top-right, bottom-right, bottom-left (y down).
      const cv::Point3f top_left = cv_board->objPoints[i][0];
      const double bit = tex.bit_size;
      for (int r = 0; r < codes[i].rows; ++r) {
        for (int c = 0; c < codes[i].cols; ++c) {
          const Eigen::Vector2d t =
              tex.TexelFromBoard(top_left.x + (c + 0.5) * bit, top_left.y + (r + 0.5) * bit);
          ASSERT_EQ(TexelAt(tex, t, 0, 0), codes[i].at<uint8_t>(r, c))
              << "marker " << i << " (id " << cv_board->ids[i] << ") bit " << r << "," << c;
        }
      }
      // The marker's corners on texel boundaries (objPoints are floats:
      // 1e-3 texel is 3e-7 m here).
      const Eigen::Vector2d t0 = tex.TexelFromBoard(top_left.x, top_left.y);
      EXPECT_NEAR(t0.x(), std::round(t0.x()), 1e-3);
      EXPECT_NEAR(t0.y(), std::round(t0.y()), 1e-3);
    }

    // CharucoBoard::draw at 48 px per square (6 px per marker bit, so that
    // OpenCV's integer layout is exact): every pixel, sampled at its centre
    // in the texture.
    const int px = 48;
    cv::Mat drawn;
    cv_board->draw(cv::Size(board.cols * px, board.rows * px), drawn, 0, 1);
    int differ = 0;
    for (int v = 0; v < drawn.rows; ++v) {
      for (int u = 0; u < drawn.cols; ++u) {
        const double s = board.square_size / px;
        const Eigen::Vector2d t = tex.TexelFromBoard((u + 0.5) * s, (v + 0.5) * s);
        differ += TexelAt(tex, t, 0, 0) != drawn.at<uint8_t>(v, u);
      }
    }
    EXPECT_EQ(differ, 0) << "rows " << rows;
  }
}

// A marker gap that is no whole number of bits stays exact: the gap is
// stretched, the squares and the marker bits are not.
TEST(TagTextureTest, CharucoMarkerOfAnyProportion) {
  const TagBoard board = PointBoard(BoardKind::kCharuco, 3, 4, 0.05, 0.0371);
  const TagTexture tex = MakeTagTexture(board);
  ExpectExactSquares(board, tex);
  EXPECT_NEAR(tex.bit_size, 0.0371 / 6, 1e-15);
  const std::vector<cv::Mat> codes = detect::CharucoMarkerImages(board);
  // Marker 0 sits in square (0, 1), centred.
  const double x0 = 0.05 + (0.05 - 0.0371) / 2, y0 = (0.05 - 0.0371) / 2;
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) {
      const Eigen::Vector2d t =
          tex.TexelFromBoard(x0 + (c + 0.5) * tex.bit_size, y0 + (r + 0.5) * tex.bit_size);
      EXPECT_EQ(TexelAt(tex, t, 0, 0), codes[0].at<uint8_t>(r, c)) << r << "," << c;
    }
  }
}

TEST(TagTextureTest, RejectsUnprintablePointBoards) {
  EXPECT_THROW(MakeTagTexture(PointBoard(BoardKind::kChessboard, 1, 9, 0.025)),
               std::invalid_argument);
  EXPECT_THROW(MakeTagTexture(PointBoard(BoardKind::kCharuco, 5, 7, 0.04, 0.04)),
               std::invalid_argument);
  TagBoard unknown = PointBoard(BoardKind::kCharuco, 5, 7, 0.04, 0.03);
  unknown.family = "DICT_9X9_50";
  EXPECT_THROW(MakeTagTexture(unknown), std::invalid_argument);
  // DICT_4X4_50 has 50 markers; 11 x 11 squares need 60.
  EXPECT_THROW(MakeTagTexture(PointBoard(BoardKind::kCharuco, 11, 11, 0.04, 0.03)),
               std::invalid_argument);
}

}  // namespace
}  // namespace rtscalib::render

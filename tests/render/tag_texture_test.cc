// Texture geometry: exact, no rendering.
#include "render/tag_texture.h"

#include <gtest/gtest.h>

#include <cmath>

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

}  // namespace
}  // namespace rtscalib::render

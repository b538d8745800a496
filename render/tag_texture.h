// The printed image of a whole TagBoard, and where its texels lie on the board.
//
// Layout (targets.h): tag (r, c)'s detection quad is the square
// [x0, x0 + tag_size] x [y0, y0 + tag_size] of the board frame with
// x0 = (tag_size + spacing) c, y0 = (tag_size + spacing) r; x right, y down.
// One code bit is b = tag_size / width_at_border, so the tag's whole code image
// (tag_family.h) covers [x0 - o b, x0 + tag_size + o b] with o = border_offset.
//
// The texture is built from whole bits (nearest-neighbour, `pixels_per_bit`
// texels per bit) on a white background, with `margin` of white around the
// outermost code images. Texel (i, j) covers the continuous texel square
// [i, i+1) x [j, j+1), row 0 at the board's top (smallest y).
//
// Board -> texel is piecewise linear, exact inside every code image: the
// breakpoints are the code images' edges and the margin's outer edge, so each
// quad edge lands exactly on a texel boundary whatever `spacing` is (the white
// gaps between code images are stretched or squeezed by less than one bit to a
// whole number of bits). The renderer draws one rectangle per breakpoint cell
// with these texture coordinates.
//
// Every code image starts at a multiple of `pixels_per_bit` (a power of two)
// texels and the texture's size is a multiple of it, so the first
// log2(pixels_per_bit) mipmap levels (2x2 box averages) still have every bit
// edge on a texel boundary: linear/mipmap filtering blurs an edge
// symmetrically and never moves it.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "libcalib/model/targets.h"

namespace rtscalib::render {

struct TagTextureOptions {
  // Texels per code bit, a power of two; 0 = the largest power of two
  // <= max_pixels_per_bit that keeps both sides <= max_texture_size.
  int pixels_per_bit = 0;
  int max_pixels_per_bit = 16;
  int max_texture_size = 8192;
  // White paper around the outermost code images [m]; < 0 = one code bit.
  double margin = -1;
  unsigned char black = 0;    // ink
  unsigned char white = 255;  // paper

  std::string Check() const;  // empty when valid
};

struct TagTexture {
  cv::Mat image;           // CV_8UC1, rows = board y, columns = board x
  int pixels_per_bit = 0;  // texels per code bit
  double bit_size = 0;     // one code bit on the board [m]
  // Breakpoints of board -> texel along x and y (strictly increasing; texel
  // coordinates continuous, texel i spans [i, i+1)).
  std::vector<double> x_board, x_texel;
  std::vector<double> y_board, y_texel;

  // Board rectangle the texture covers [m].
  double x_min() const { return x_board.front(); }
  double x_max() const { return x_board.back(); }
  double y_min() const { return y_board.front(); }
  double y_max() const { return y_board.back(); }
  // Continuous texel coordinates of a board point (piecewise linear).
  Eigen::Vector2d TexelFromBoard(double x, double y) const;
};

// The board rectangle MakeTagTexture prints (code images plus margin), in the
// board frame [m]; `margin` < 0 means one code bit, as in TagTextureOptions.
struct BoardRect {
  double x_min = 0, x_max = 0, y_min = 0, y_max = 0;
};
BoardRect PrintedArea(const TagBoard& board, double margin = -1);

// Builds the texture of `board`. Throws std::invalid_argument when the board
// cannot be printed: unknown family, id beyond the family, spacing too small
// for the code images' extra bits (spacing >= 2 border_offset bits), or no
// power-of-two resolution fits max_texture_size.
TagTexture MakeTagTexture(const TagBoard& board, const TagTextureOptions& options = {});

}  // namespace rtscalib::render

// The printed image of a whole board (targets.h: AprilTags, ChArUco or a
// chessboard), and where its texels lie on the board.
//
// AprilTag boards. Layout (targets.h): tag (r, c)'s detection quad is the square
// [x0, x0 + tag_size] x [y0, y0 + tag_size] of the board frame with
// x0 = (tag_size + spacing) c, y0 = (tag_size + spacing) r; x right, y down;
// tag first_id + i sits in cell TagBoard::GridOf(i). One code bit is
// b = tag_size / width_at_border (of the board's border_bits), so the tag's
// whole code image (tag_family.h) covers [x0 - o b, x0 + tag_size + o b] with
// o = border_offset. A board of 2-bit tags, Kalibr's AprilGrid, also has
// its black squares of side `spacing` at every crossing of the gaps, the
// outer crossings included (TagBoard::HasCornerSquares), each touching the
// corners of the tags around it; its margin (by default) is as wide as a
// square.
//
// ChArUco and chessboards (docs/photos.md). `rows` x `cols` squares of
// square_size, square (r, c) = [c s, (c + 1) s] x [r s, (r + 1) s], black when
// r + c is even (the top-left square is black). ChArUco: the white squares
// hold the markers exactly as cv::aruco::CharucoBoard::create(cols, rows,
// square_size, marker_size, dictionary) defines them
// (detect::CharucoMarkerImages): centred, marker_size wide, one code bit
// b = marker_size / (markerSize + 2) (its black border of one bit included).
// A chessboard square is printed as kChessboardBitsPerSquare x
// kChessboardBitsPerSquare bits (it has no code; the number only sets the
// texel density, like a ChArUco square of 4 x 4 markers).
//
// The texture is built from whole bits (nearest-neighbour, `pixels_per_bit`
// texels per bit) on a white background, with `margin` of white around the
// outermost code images (AprilTag) or around the squares (point boards).
// Texel (i, j) covers the continuous texel square [i, i+1) x [j, j+1), row 0
// at the board's top (smallest y).
//
// Board -> texel is piecewise linear, exact between breakpoints; one code path
// for every kind of board (the renderer draws one rectangle per breakpoint
// cell with these texture coordinates), the kind decides only the breakpoints
// and the texture's content:
//   AprilTag: the breakpoints are the code images' edges and the margin's
//     outer edge, so each quad edge lands exactly on a texel boundary whatever
//     `spacing` is (the white gaps between code images are stretched or
//     squeezed by less than one bit to a whole number of bits);
//   ChArUco: the square edges, the markers' edges and the margin's outer
//     edge: every square edge (the inner corners) and every marker bit edge
//     lands exactly on a texel boundary; the white gap between a marker and
//     its square's edge, (square_size - marker_size) / 2, is printed as a
//     whole number (>= 1) of bits;
//   chessboard: the squares' outline and the margin's outer edge (the
//     squares are uniform in between).
//
// Every code image and every square starts at a multiple of `pixels_per_bit`
// (a power of two) texels and the texture's size is a multiple of it, so the
// first log2(pixels_per_bit) mipmap levels (2x2 box averages) still have every
// bit and square edge on a texel boundary: linear/mipmap filtering blurs an
// edge symmetrically and never moves it.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "libcalib/model/targets.h"

namespace rtscalib::render {

// A chessboard square in texture bits (see above).
constexpr int kChessboardBitsPerSquare = 8;

struct TagTextureOptions {
  // Texels per code bit, a power of two; 0 = the largest power of two
  // <= max_pixels_per_bit that keeps both sides <= max_texture_size.
  int pixels_per_bit = 0;
  int max_pixels_per_bit = 16;
  int max_texture_size = 8192;
  // White paper around the outermost code images (AprilTag) or the squares
  // (ChArUco, chessboard) [m]; < 0 = one code bit for AprilTag boards (an
  // AprilGrid's square side, when larger), one square for point boards (the
  // quiet zone OpenCV's chessboard detector needs around the outer squares).
  double margin = -1;
  unsigned char black = 0;    // ink
  unsigned char white = 255;  // paper

  std::string Check() const;  // empty when valid
};

struct TagTexture {
  cv::Mat image;           // CV_8UC1, rows = board y, columns = board x
  int pixels_per_bit = 0;  // texels per code bit
  double bit_size = 0;     // one code bit on the board [m] (PrintedBitSize)
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

// The board rectangle MakeTagTexture prints (code images or squares, plus the
// margin), in the board frame [m]; `margin` < 0 as in TagTextureOptions.
struct BoardRect {
  double x_min = 0, x_max = 0, y_min = 0, y_max = 0;
};
BoardRect PrintedArea(const TagBoard& board, double margin = -1);

// One code bit of `board`'s print [m]: tag_size / width_at_border (AprilTag),
// marker_size / (markerSize + 2) (ChArUco), square_size /
// kChessboardBitsPerSquare (chessboard). Throws std::invalid_argument for an
// unknown family or dictionary.
double PrintedBitSize(const TagBoard& board);

// Builds the texture of `board`. Throws std::invalid_argument when the board
// cannot be printed: unknown family or dictionary, id beyond the family,
// spacing too small for the code images' extra bits (spacing >= 2
// border_offset bits), a ChArUco dictionary with fewer markers than white
// squares or marker_size outside (0, square_size), fewer than 2 x 2 squares,
// or no power-of-two resolution fits max_texture_size.
TagTexture MakeTagTexture(const TagBoard& board, const TagTextureOptions& options = {});

}  // namespace rtscalib::render

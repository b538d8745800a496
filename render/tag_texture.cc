#include "render/tag_texture.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "detect/point_boards.h"
#include "detect/tag_family.h"

namespace rtscalib::render {
namespace {

bool IsPowerOfTwo(int n) { return n > 0 && (n & (n - 1)) == 0; }

double Interpolate(const std::vector<double>& from, const std::vector<double>& to, double v) {
  // Extrapolates linearly beyond the ends (the margins are uniform anyway).
  size_t i = std::upper_bound(from.begin(), from.end(), v) - from.begin();
  i = std::clamp<size_t>(i, 1, from.size() - 1);
  const double t = (v - from[i - 1]) / (from[i] - from[i - 1]);
  return to[i - 1] + t * (to[i] - to[i - 1]);
}

// Breakpoints along one axis with `count` code images of `code_bits` bits,
// code image k starting at board coordinate start0 + k * pitch.
// Texels: margin_bits, then code, gap, code, ..., margin_bits (in bits, times ppb).
void AxisBreakpoints(int count, double start0, double pitch, double bit, int code_bits,
                     int gap_bits, int margin_bits, double margin, int ppb,
                     std::vector<double>* board, std::vector<double>* texel) {
  board->clear();
  texel->clear();
  const double code = code_bits * bit;
  double t = 0;
  board->push_back(start0 - margin);
  texel->push_back(t);
  t += margin_bits * ppb;
  for (int k = 0; k < count; ++k) {
    const double s = start0 + k * pitch;
    if (k > 0 && gap_bits > 0) t += gap_bits * ppb;
    if (k == 0 || gap_bits > 0) {  // a zero gap shares the previous code's end
      board->push_back(s);
      texel->push_back(t);
    }
    t += code_bits * ppb;
    board->push_back(s + code);
    texel->push_back(t);
  }
  t += margin_bits * ppb;
  board->push_back(start0 + (count - 1) * pitch + code + margin);
  texel->push_back(t);
}

// Texels per bit for a texture of bits_x x bits_y bits (TagTextureOptions).
int ChoosePixelsPerBit(int bits_x, int bits_y, const TagTextureOptions& options,
                       const std::string& what) {
  int ppb = options.pixels_per_bit;
  if (ppb == 0) {
    ppb = options.max_pixels_per_bit;
    while (ppb > 1 && std::max(bits_x, bits_y) * ppb > options.max_texture_size) ppb /= 2;
  }
  if (std::max(bits_x, bits_y) * ppb > options.max_texture_size) {
    throw std::invalid_argument(what + ": " + std::to_string(bits_x) + " x " +
                                std::to_string(bits_y) + " bits at " + std::to_string(ppb) +
                                " texel(s) per bit exceed max_texture_size " +
                                std::to_string(options.max_texture_size));
  }
  return ppb;
}

// Paper everywhere, `code` (0 = ink, anything else = paper, one pixel per bit)
// at texel (x, y), scaled by ppb (nearest neighbour), in the options' levels.
void PaintCode(const cv::Mat& code, int x, int y, int ppb, const TagTextureOptions& options,
               cv::Mat* image) {
  cv::Mat lut(1, 256, CV_8UC1, cv::Scalar(options.white));
  lut.at<uint8_t>(0) = options.black;
  cv::Mat levels, scaled;
  cv::LUT(code, lut, levels);
  cv::resize(levels, scaled, cv::Size(), ppb, ppb, cv::INTER_NEAREST);
  scaled.copyTo((*image)(cv::Rect(x, y, scaled.cols, scaled.rows)));
}

// White paper around the outermost code images when the options leave it
// to the board: one code bit; an AprilGrid's outer squares lie beyond its
// code images, so there it is the squares' side (at least a bit).
double DefaultTagMargin(const TagBoard& board, double bit) {
  return board.HasCornerSquares() ? std::max(bit, board.spacing) : bit;
}

// Kalibr's squares (targets.h): one at every crossing of the gaps between
// the tags, the outer crossings included, from the black edge of the tags
// on one side to that of the tags on the other. Their inner edges are the
// tags' black edges, on texel boundaries like them; an outer square's
// outer edge lies in the margin, `spacing` beyond the tags' edge, to the
// nearest texel.
void PaintCornerSquares(const TagBoard& board, const detect::TagFamilyInfo& info,
                        int margin_bits, int gap_bits, TagTexture* tex,
                        const TagTextureOptions& options) {
  const int ppb = tex->pixels_per_bit;
  const int off = info.border_offset();
  const int step = (info.total_width + gap_bits) * ppb;
  // The texel span [lo, hi) of the squares before tag `k` along one axis
  // (k = 0 .. count, the last after the last tag).
  auto span = [&](int k, int count, const std::vector<double>& board_at,
                  const std::vector<double>& texel_at) {
    const double pitch = board.tag_size + board.spacing;
    const int black_start = margin_bits * ppb + off * ppb;  // tag 0's black edge
    const int black = info.width_at_border * ppb;
    int lo = k > 0 ? black_start + (k - 1) * step + black : 0;
    int hi = k < count ? black_start + k * step : 0;
    if (k == 0) {
      lo = static_cast<int>(std::lround(Interpolate(board_at, texel_at, -board.spacing)));
    }
    if (k == count) {
      hi = static_cast<int>(
          std::lround(Interpolate(board_at, texel_at, (count - 1) * pitch + board.tag_size +
                                                          board.spacing)));
    }
    return std::make_pair(lo, hi);
  };
  for (int r = 0; r <= board.rows; ++r) {
    const auto [y0, y1] = span(r, board.rows, tex->y_board, tex->y_texel);
    for (int c = 0; c <= board.cols; ++c) {
      const auto [x0, x1] = span(c, board.cols, tex->x_board, tex->x_texel);
      const cv::Rect square = cv::Rect(x0, y0, x1 - x0, y1 - y0) &
                              cv::Rect(0, 0, tex->image.cols, tex->image.rows);
      tex->image(square).setTo(options.black);
    }
  }
}

void CheckPointBoard(const TagBoard& board) {
  if (board.rows < 2 || board.cols < 2 || !(board.square_size > 0)) {
    throw std::invalid_argument(
        "TagBoard: a ChArUco or chessboard needs rows, cols >= 2 and square_size > 0");
  }
  if (board.kind == BoardKind::kCharuco &&
      !(board.marker_size > 0 && board.marker_size < board.square_size)) {
    throw std::invalid_argument("TagBoard: a ChArUco board needs 0 < marker_size < square_size");
  }
}

// ChArUco and chessboards (see the header): squares of square_bits bits, a
// ChArUco marker gap_bits from its square's top-left corner.
TagTexture MakePointBoardTexture(const TagBoard& board, const TagTextureOptions& options) {
  CheckPointBoard(board);
  const bool charuco = board.kind == BoardKind::kCharuco;
  const double s = board.square_size;
  std::vector<cv::Mat> markers;
  int marker_bits = 0, gap_bits = 0, square_bits = kChessboardBitsPerSquare;
  double gap = 0;
  if (charuco) {
    markers = detect::CharucoMarkerImages(board);
    marker_bits = markers.front().cols;
    gap = (s - board.marker_size) / 2;
    gap_bits = std::max(1, static_cast<int>(std::lround(gap * marker_bits / board.marker_size)));
    square_bits = marker_bits + 2 * gap_bits;
  }
  TagTexture tex;
  tex.bit_size = charuco ? board.marker_size / marker_bits : s / kChessboardBitsPerSquare;
  const double margin = options.margin < 0 ? s : options.margin;
  const int margin_bits =
      margin > 0 ? std::max(1, static_cast<int>(std::ceil(margin / tex.bit_size - 1e-9))) : 0;
  const int bits_x = 2 * margin_bits + board.cols * square_bits;
  const int bits_y = 2 * margin_bits + board.rows * square_bits;
  const int ppb = ChoosePixelsPerBit(bits_x, bits_y, options, "TagBoard");
  tex.pixels_per_bit = ppb;

  const int t0 = margin_bits * ppb, sq = square_bits * ppb;
  auto axis = [&](int squares, std::vector<double>* b, std::vector<double>* t) {
    if (margin_bits > 0) {
      b->push_back(-margin);
      t->push_back(0);
    }
    for (int k = 0; k < squares; ++k) {
      if (k == 0 || charuco) {
        b->push_back(k * s);
        t->push_back(t0 + k * sq);
      }
      if (charuco) {
        b->push_back(k * s + gap);
        t->push_back(t0 + k * sq + gap_bits * ppb);
        b->push_back(k * s + gap + board.marker_size);
        t->push_back(t0 + k * sq + (gap_bits + marker_bits) * ppb);
      }
    }
    b->push_back(squares * s);
    t->push_back(t0 + squares * sq);
    if (margin_bits > 0) {
      b->push_back(squares * s + margin);
      t->push_back(2 * t0 + squares * sq);
    }
  };
  axis(board.cols, &tex.x_board, &tex.x_texel);
  axis(board.rows, &tex.y_board, &tex.y_texel);

  tex.image = cv::Mat(bits_y * ppb, bits_x * ppb, CV_8UC1, cv::Scalar(options.white));
  size_t marker = 0;
  for (int r = 0; r < board.rows; ++r) {
    for (int c = 0; c < board.cols; ++c) {
      const int x = t0 + c * sq, y = t0 + r * sq;
      if ((r + c) % 2 == 0) {
        tex.image(cv::Rect(x, y, sq, sq)).setTo(options.black);
      } else if (charuco) {
        PaintCode(markers.at(marker++), x + gap_bits * ppb, y + gap_bits * ppb, ppb, options,
                  &tex.image);
      }
    }
  }
  return tex;
}

}  // namespace

double PrintedBitSize(const TagBoard& board) {
  switch (board.kind) {
    case BoardKind::kAprilTag:
      return board.tag_size /
             detect::GetTagFamilyInfo(board.family, board.border_bits).width_at_border;
    case BoardKind::kCharuco:
      return board.marker_size / detect::CharucoMarkerImages(board).front().cols;
    case BoardKind::kChessboard:
      break;
  }
  return board.square_size / kChessboardBitsPerSquare;
}

std::string TagTextureOptions::Check() const {
  if (pixels_per_bit != 0 && !IsPowerOfTwo(pixels_per_bit)) {
    return "pixels_per_bit: expected 0 (auto) or a power of two, got " +
           std::to_string(pixels_per_bit);
  }
  if (!IsPowerOfTwo(max_pixels_per_bit)) {
    return "max_pixels_per_bit: expected a power of two, got " + std::to_string(max_pixels_per_bit);
  }
  if (max_texture_size < 16) {
    return "max_texture_size: expected >= 16, got " + std::to_string(max_texture_size);
  }
  if (black >= white) return "black/white: expected black < white";
  return "";
}

Eigen::Vector2d TagTexture::TexelFromBoard(double x, double y) const {
  return {Interpolate(x_board, x_texel, x), Interpolate(y_board, y_texel, y)};
}

BoardRect PrintedArea(const TagBoard& board, double margin) {
  if (board.IsPointBoard()) {
    const double m = margin < 0 ? board.square_size : margin;
    return {-m, board.Width() + m, -m, board.Height() + m};
  }
  const detect::TagFamilyInfo info = detect::GetTagFamilyInfo(board.family, board.border_bits);
  const double bit = board.tag_size / info.width_at_border;
  const double m = margin < 0 ? DefaultTagMargin(board, bit) : margin;
  const double off = info.border_offset() * bit;
  const double pitch = board.tag_size + board.spacing;
  const double code = info.total_width * bit;
  return {-off - m, (board.cols - 1) * pitch + code - off + m, -off - m,
          (board.rows - 1) * pitch + code - off + m};
}

TagTexture MakeTagTexture(const TagBoard& board, const TagTextureOptions& options) {
  if (const std::string msg = options.Check(); !msg.empty()) {
    throw std::invalid_argument("TagTextureOptions: " + msg);
  }
  if (board.IsPointBoard()) return MakePointBoardTexture(board, options);
  if (board.rows < 1 || board.cols < 1 || !(board.tag_size > 0) || board.spacing < 0) {
    throw std::invalid_argument("TagBoard: expected rows, cols >= 1, tag_size > 0, spacing >= 0");
  }
  const detect::TagFamilyPtr family = detect::CreateTagFamily(board.family, board.border_bits);
  const detect::TagFamilyInfo info = detect::GetTagFamilyInfo(board.family, board.border_bits);
  if (board.first_id < 0 || board.first_id + board.NumTags() > info.num_codes) {
    throw std::invalid_argument("TagBoard: ids " + std::to_string(board.first_id) + ".." +
                                std::to_string(board.first_id + board.NumTags() - 1) +
                                " do not fit family " + board.family + " (ids 0.." +
                                std::to_string(info.num_codes - 1) + ")");
  }

  TagTexture tex;
  const double bit = board.tag_size / info.width_at_border;
  tex.bit_size = bit;
  const int off = info.border_offset();
  const int code_bits = info.total_width;
  const double pitch = board.tag_size + board.spacing;
  // White between neighbouring code images, in bits. A code image may not
  // overlap its neighbour; floating-point slack of 1e-9 bit is tolerated.
  const double gap = (pitch - code_bits * bit) / bit;
  if (gap < -1e-9) {
    throw std::invalid_argument(
        "TagBoard: spacing " + std::to_string(board.spacing) + " m is too small for " +
        board.family + ": its code images extend " + std::to_string(off) +
        " bit(s) beyond the tag square, so spacing must be >= " + std::to_string(2 * off * bit) +
        " m");
  }
  // A gap is printed as a whole number of white bits; a gap of (almost) zero
  // width lets neighbouring code images touch.
  const int gap_bits = gap < 1e-9 ? 0 : std::max(1, static_cast<int>(std::lround(gap)));
  const double margin = options.margin < 0 ? DefaultTagMargin(board, bit) : options.margin;
  const int margin_bits = static_cast<int>(std::ceil(margin / bit - 1e-9));

  const int bits_x = 2 * margin_bits + board.cols * code_bits + (board.cols - 1) * gap_bits;
  const int bits_y = 2 * margin_bits + board.rows * code_bits + (board.rows - 1) * gap_bits;
  const int ppb = ChoosePixelsPerBit(bits_x, bits_y, options, "TagBoard");
  tex.pixels_per_bit = ppb;

  AxisBreakpoints(board.cols, -off * bit, pitch, bit, code_bits, gap_bits, margin_bits, margin, ppb,
                  &tex.x_board, &tex.x_texel);
  AxisBreakpoints(board.rows, -off * bit, pitch, bit, code_bits, gap_bits, margin_bits, margin, ppb,
                  &tex.y_board, &tex.y_texel);

  tex.image = cv::Mat(bits_y * ppb, bits_x * ppb, CV_8UC1, cv::Scalar(options.white));
  const int step = (code_bits + gap_bits) * ppb;
  for (int i = 0; i < board.NumTags(); ++i) {
    const GridCell cell = board.GridOf(i);
    PaintCode(detect::TagCodeImage(family.get(), board.first_id + i),
              margin_bits * ppb + cell.col * step, margin_bits * ppb + cell.row * step, ppb,
              options, &tex.image);
  }
  if (board.HasCornerSquares()) PaintCornerSquares(board, info, margin_bits, gap_bits, &tex, options);
  return tex;
}

}  // namespace rtscalib::render

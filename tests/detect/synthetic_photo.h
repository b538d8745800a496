// Photos of AprilTags synthesized with OpenCV alone (no renderer), exact to
// the SPEC 2 pixel convention: pixel (i, j) is the area [i - 1/2, i + 1/2] x
// [j - 1/2, j + 1/2] of the continuous image plane, its centre (i, j). A
// pixel's value is the mean of the printed pattern over that area, computed
// exactly by clipping (see RenderCoverage).
//
// The printed plane is mapped to the image by a homography `image_from_plane`
// (continuous coordinates on both sides); the plane holds code images of tags
// (tag_family.h: code bit (x, y) covers [x, x+1) x [y, y+1) of the code
// image, row 0 = top of the upright tag) on white paper.
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "detect/tag_family.h"
#include "libcalib/model/targets.h"

namespace rtscalib::detect::testing {

// One tag printed on the plane: its detection quad is the square
// [x0, x0 + size] x [y0, y0 + size] (plane units, y down the upright tag).
struct PrintedTag {
  cv::Mat code;  // TagCodeImage
  int width_at_border = 0, border_offset = 0;
  double x0 = 0, y0 = 0, size = 1;
};

inline PrintedTag PrintTag(const std::string& family, int id, double x0, double y0, double size,
                           int border_bits = 1) {
  const TagFamilyInfo info = GetTagFamilyInfo(family, border_bits);
  return {TagCodeImage(family, id, border_bits), info.width_at_border, info.border_offset(), x0,
          y0, size};
}

// A black square [x0, x0 + size]^2 on the plane (one ink bit).
inline PrintedTag PrintSquare(double x0, double y0, double size) {
  return {cv::Mat(1, 1, CV_8UC1, cv::Scalar(0)), 1, 0, x0, y0, size};
}

// Every tag of `board` with its quad in board coordinates [m] (targets.h),
// with the board's border_bits.
inline std::vector<PrintedTag> PrintBoard(const TagBoard& board) {
  std::vector<PrintedTag> tags;
  for (int i = 0; i < board.NumTags(); ++i) {
    const Eigen::Vector3d top_left = board.CornersInBoard(i)[3];
    tags.push_back(PrintTag(board.family, board.first_id + i, top_left.x(), top_left.y(),
                            board.tag_size, board.border_bits));
  }
  return tags;
}

// Kalibr's AprilGrid (SPEC 7.2): `board`'s tags and a black square of side
// `spacing` at every crossing of the gaps, the outer ones included, each
// touching the corners of the tags around it. With `overlap` > 0 [plane
// units] the squares grow by that much on every side and cover the tags'
// corners, as some prints do (TUM VI's). `skip` squares (by crossing index
// r (cols + 1) + c, r, c = 0 .. rows, cols from the top-left) are left out.
// The squares come first: CellAt finds a square before the white quiet
// zone of the tag whose corner bit it covers. With overlap, the ink that a
// square and a tag's border share is counted twice by RenderCoverage (pixel
// values clipped at ink), at the junctions only.
inline std::vector<PrintedTag> PrintAprilGrid(const TagBoard& board, double overlap = 0,
                                              const std::vector<int>& skip = {}) {
  std::vector<PrintedTag> out;
  const double pitch = board.tag_size + board.spacing;
  for (int r = 0; r <= board.rows; ++r) {
    for (int c = 0; c <= board.cols; ++c) {
      if (std::find(skip.begin(), skip.end(), r * (board.cols + 1) + c) != skip.end()) continue;
      out.push_back(PrintSquare(c * pitch - board.spacing - overlap,
                                r * pitch - board.spacing - overlap,
                                board.spacing + 2 * overlap));
    }
  }
  for (const PrintedTag& t : PrintBoard(board)) out.push_back(t);
  return out;
}

// The code bit under plane point p: which tag (-1 = plain paper) and which
// bit of its code image, and the printed value there (0 = ink, 1 = paper).
struct Cell {
  int tag = -1, bx = 0, by = 0;
  double value = 1.0;
  bool operator==(const Cell& o) const { return tag == o.tag && bx == o.bx && by == o.by; }
};

// Only the tags listed in `candidates` (all when empty) are looked at.
inline Cell CellAt(const std::vector<PrintedTag>& tags, const Eigen::Vector2d& p,
                   const std::vector<int>& candidates = {}) {
  const int n = static_cast<int>(candidates.empty() ? tags.size() : candidates.size());
  for (int k = 0; k < n; ++k) {
    const int i = candidates.empty() ? k : candidates[k];
    const PrintedTag& t = tags[i];
    const double bit = t.size / t.width_at_border;
    const double bx = (p.x() - t.x0) / bit + t.border_offset;
    const double by = (p.y() - t.y0) / bit + t.border_offset;
    if (bx < 0 || by < 0 || bx >= t.code.cols || by >= t.code.rows) continue;
    const int x = static_cast<int>(bx), y = static_cast<int>(by);
    return {i, x, y, t.code.at<uint8_t>(y, x) / 255.0};
  }
  return {};
}

// The exact image position of a plane point (SPEC 2 pixels).
inline Eigen::Vector2d Project(const Eigen::Matrix3d& image_from_plane, const Eigen::Vector2d& p) {
  return (image_from_plane * p.homogeneous()).hnormalized();
}

// The quad corners of `t` in TargetCorner order: 0 bottom-left, 1
// bottom-right, 2 top-right, 3 top-left of the upright tag (SPEC 7).
inline std::array<Eigen::Vector2d, 4> QuadCorners(const PrintedTag& t) {
  return {Eigen::Vector2d(t.x0, t.y0 + t.size), Eigen::Vector2d(t.x0 + t.size, t.y0 + t.size),
          Eigen::Vector2d(t.x0 + t.size, t.y0), Eigen::Vector2d(t.x0, t.y0)};
}

// Area of the part of convex polygon `poly` (image points, either
// orientation) inside the pixel square [i - 1/2, i + 1/2] x [j - 1/2, j + 1/2]
// (SPEC 2): Sutherland-Hodgman clipping by the square's four sides, then the
// shoelace formula. Exact up to rounding.
inline double AreaInPixel(std::vector<Eigen::Vector2d> poly, int i, int j) {
  const double lo[2] = {i - 0.5, j - 0.5}, hi[2] = {i + 0.5, j + 0.5};
  for (int side = 0; side < 4 && !poly.empty(); ++side) {
    const int axis = side / 2;
    const bool upper = side % 2 == 1;
    const double bound = upper ? hi[axis] : lo[axis];
    auto inside = [&](const Eigen::Vector2d& p) {
      return upper ? p[axis] <= bound : p[axis] >= bound;
    };
    std::vector<Eigen::Vector2d> out;
    for (size_t k = 0; k < poly.size(); ++k) {
      const Eigen::Vector2d& a = poly[k];
      const Eigen::Vector2d& b = poly[(k + 1) % poly.size()];
      if (inside(a)) out.push_back(a);
      if (inside(a) != inside(b)) {
        const double t = (bound - a[axis]) / (b[axis] - a[axis]);
        out.push_back(a + t * (b - a));
      }
    }
    poly.swap(out);
  }
  double twice = 0;
  for (size_t k = 0; k < poly.size(); ++k) {
    const Eigen::Vector2d& a = poly[k];
    const Eigen::Vector2d& b = poly[(k + 1) % poly.size()];
    twice += a.x() * b.y() - a.y() * b.x();
  }
  return std::abs(twice) / 2;
}

// A CV_64FC1 image of coverage values (0 = ink, 1 = paper), exact: a pixel's
// value is 1 minus the area of the pixel square covered by the images of the
// tags' ink bits. A homography maps a bit's square onto a convex
// quadrilateral (the scenes here keep the line at infinity off the boards),
// which is clipped against the pixel square. A pixel whose four corners map
// into one code bit (or all onto plain paper) lies wholly in it: a pixel's
// preimage is a convex quadrilateral and a bit a convex square. Otherwise
// the bits looked at are those of the tags at the pixel's corners within the
// bounding box of the pixel's preimage.
inline cv::Mat RenderCoverage(const std::vector<PrintedTag>& tags,
                              const Eigen::Matrix3d& image_from_plane, int width, int height) {
  const Eigen::Matrix3d plane_from_image = image_from_plane.inverse();
  // Pixel corner (i, j) is the image point (i - 1/2, j - 1/2).
  std::vector<Eigen::Vector2d> plane((width + 1) * (height + 1));
  std::vector<Cell> corners(plane.size());
  for (int j = 0; j <= height; ++j) {
    for (int i = 0; i <= width; ++i) {
      const int k = j * (width + 1) + i;
      plane[k] = Project(plane_from_image, Eigen::Vector2d(i - 0.5, j - 0.5));
      corners[k] = CellAt(tags, plane[k]);
    }
  }
  cv::Mat out(height, width, CV_64FC1);
  for (int j = 0; j < height; ++j) {
    for (int i = 0; i < width; ++i) {
      const std::array<int, 4> at = {j * (width + 1) + i, j * (width + 1) + i + 1,
                                     (j + 1) * (width + 1) + i, (j + 1) * (width + 1) + i + 1};
      const Cell& c = corners[at[0]];
      if (c == corners[at[1]] && c == corners[at[2]] && c == corners[at[3]]) {
        out.at<double>(j, i) = c.value;
        continue;
      }
      // The tags at the pixel's corners: code images are at least one white
      // bit apart and their outer ring is white for the families used here,
      // so no other tag can change the pixel's value (an AprilGrid's squares
      // touch the tags only where the tags' code images are white).
      std::vector<int> candidates;
      for (const int k : at) {
        const int tag = corners[k].tag;
        if (tag >= 0 && std::find(candidates.begin(), candidates.end(), tag) == candidates.end()) {
          candidates.push_back(tag);
        }
      }
      Eigen::Vector2d lo = plane[at[0]], hi = plane[at[0]];
      for (const int k : at) {
        lo = lo.cwiseMin(plane[k]);
        hi = hi.cwiseMax(plane[k]);
      }
      double ink = 0;
      for (const int tag : candidates) {
        const PrintedTag& t = tags[tag];
        const double bit = t.size / t.width_at_border;
        auto bit_index = [&](double v, double origin) {
          return static_cast<int>(std::floor((v - origin) / bit + t.border_offset));
        };
        const int x0 = std::max(0, bit_index(lo.x(), t.x0));
        const int x1 = std::min(t.code.cols - 1, bit_index(hi.x(), t.x0));
        const int y0 = std::max(0, bit_index(lo.y(), t.y0));
        const int y1 = std::min(t.code.rows - 1, bit_index(hi.y(), t.y0));
        for (int by = y0; by <= y1; ++by) {
          for (int bx = x0; bx <= x1; ++bx) {
            if (t.code.at<uint8_t>(by, bx) != 0) continue;  // paper
            const double px = t.x0 + (bx - t.border_offset) * bit;
            const double py = t.y0 + (by - t.border_offset) * bit;
            ink += AreaInPixel(
                {Project(image_from_plane, {px, py}), Project(image_from_plane, {px + bit, py}),
                 Project(image_from_plane, {px + bit, py + bit}),
                 Project(image_from_plane, {px, py + bit})},
                i, j);
          }
        }
      }
      out.at<double>(j, i) = std::max(0.0, 1.0 - ink);
    }
  }
  return out;
}

// Coverage -> pixel values: ink + (paper - ink) coverage, rounded, in `type`
// (CV_8UC1, CV_16UC1, CV_8UC3 with per-channel levels...). `ink` and `paper`
// give one level per channel.
inline cv::Mat ToPixels(const cv::Mat& coverage, int type, const cv::Scalar& ink,
                        const cv::Scalar& paper) {
  const int channels = CV_MAT_CN(type);
  std::vector<cv::Mat> planes;
  for (int c = 0; c < channels; ++c) {
    cv::Mat plane;
    coverage.convertTo(plane, CV_MAKETYPE(CV_MAT_DEPTH(type), 1), paper[c] - ink[c], ink[c]);
    planes.push_back(plane);
  }
  cv::Mat out;
  cv::merge(planes, out);
  return out;
}

// A homography: the plane square [0, size]^2 centred on `centre`, `scale`
// pixels per plane unit, turned by `angle` (image rotation, radians) with a
// perspective tilt (px_per, py_per: the bottom row of the matrix).
inline Eigen::Matrix3d MakeHomography(double size, const Eigen::Vector2d& centre, double scale,
                                      double angle, double px_per = 0, double py_per = 0) {
  Eigen::Matrix3d to_origin = Eigen::Matrix3d::Identity();
  to_origin(0, 2) = to_origin(1, 2) = -size / 2;
  Eigen::Matrix3d perspective = Eigen::Matrix3d::Identity();
  perspective(2, 0) = px_per;
  perspective(2, 1) = py_per;
  Eigen::Matrix3d rotate = Eigen::Matrix3d::Identity();
  rotate.topLeftCorner<2, 2>() << std::cos(angle), -std::sin(angle), std::sin(angle),
      std::cos(angle);
  rotate.topLeftCorner<2, 2>() *= scale;
  Eigen::Matrix3d to_centre = Eigen::Matrix3d::Identity();
  to_centre(0, 2) = centre.x();
  to_centre(1, 2) = centre.y();
  return to_centre * rotate * perspective * to_origin;
}

// A PNG file's bytes (as cv::imencode writes them) whose header claims
// `width` x `height` pixels: IHDR's width and height, big-endian, at bytes
// 16..23 (after the signature and the chunk's length and type), and its
// CRC over type and data (bytes 12..28) at 29..32, made right so that
// libpng reads the header (PNG spec 5.3, CRC-32 of ISO 3309).
inline std::vector<uint8_t> PngClaimingSize(std::vector<uint8_t> png, uint32_t width,
                                            uint32_t height) {
  for (int i = 0; i < 4; ++i) {
    png[16 + i] = static_cast<uint8_t>(width >> (24 - 8 * i));
    png[20 + i] = static_cast<uint8_t>(height >> (24 - 8 * i));
  }
  uint32_t crc = 0xFFFFFFFFu;
  for (int i = 12; i < 29; ++i) {
    crc ^= png[i];
    for (int b = 0; b < 8; ++b) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  crc ^= 0xFFFFFFFFu;
  for (int i = 0; i < 4; ++i) png[29 + i] = static_cast<uint8_t>(crc >> (24 - 8 * i));
  return png;
}

}  // namespace rtscalib::detect::testing

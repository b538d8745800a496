#include "detect/board_growth.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <map>
#include <optional>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "detect/tag_family.h"

namespace rtscalib::detect {
namespace {

using Corners = std::array<Eigen::Vector2d, 4>;

// The quad's corners in code-image coordinates (bits; bit (x, y) covers
// [x, x+1) x [y, y+1), y down the upright tag), TargetCorner order.
Corners QuadInCode(const TagFamilyInfo& info) {
  const double b0 = info.border_offset(), b1 = b0 + info.width_at_border;
  return {Eigen::Vector2d(b0, b1), Eigen::Vector2d(b1, b1), Eigen::Vector2d(b1, b0),
          Eigen::Vector2d(b0, b0)};
}

// The least-squares homography that maps src to dst (>= 4 points), or
// nothing when they do not determine one.
std::optional<Eigen::Matrix3d> FitHomography(const std::vector<Eigen::Vector2d>& src,
                                             const std::vector<Eigen::Vector2d>& dst) {
  std::vector<cv::Point2d> s, d;
  for (size_t i = 0; i < src.size(); ++i) {
    s.emplace_back(src[i].x(), src[i].y());
    d.emplace_back(dst[i].x(), dst[i].y());
  }
  const cv::Mat h = cv::findHomography(s, d, 0);
  if (h.empty()) return std::nullopt;
  Eigen::Matrix3d out;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out(r, c) = h.at<double>(r, c);
  }
  if (!out.allFinite()) return std::nullopt;
  return out;
}

Eigen::Vector2d Apply(const Eigen::Matrix3d& h, const Eigen::Vector2d& p) {
  return (h * p.homogeneous()).hnormalized();
}

// Bilinear interpolation at p (SPEC 2 pixels, inside the image).
double Sample(const cv::Mat& gray, const Eigen::Vector2d& p) {
  const int x = static_cast<int>(std::floor(p.x())), y = static_cast<int>(std::floor(p.y()));
  const int x1 = std::min(x + 1, gray.cols - 1), y1 = std::min(y + 1, gray.rows - 1);
  const double fx = p.x() - x, fy = p.y() - y;
  const double top = (1 - fx) * gray.at<uint8_t>(y, x) + fx * gray.at<uint8_t>(y, x1);
  const double bottom = (1 - fx) * gray.at<uint8_t>(y1, x) + fx * gray.at<uint8_t>(y1, x1);
  return (1 - fy) * top + fy * bottom;
}

double MedianOfCopy(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// What the bits of a tag read, sampled at each bit's centre through the
// homography of its quad corners (step 4 of board_growth.h).
struct CodeRead {
  bool inside = false;  // every bit centre inside the image
  double contrast = 0;  // paper - ink [grey levels]
  int frame_bits = 0, frame_misses = 0;
  int hamming = 0;  // data bits that differ from the expected code
};

CodeRead ReadCode(const cv::Mat& gray, const cv::Mat& code, const TagFamilyInfo& info,
                  const Corners& corners) {
  CodeRead out;
  const Corners quad = QuadInCode(info);
  const std::optional<Eigen::Matrix3d> h = FitHomography(
      std::vector<Eigen::Vector2d>(quad.begin(), quad.end()),
      std::vector<Eigen::Vector2d>(corners.begin(), corners.end()));
  if (!h) return out;
  const int n = code.cols, border = info.border_bits;
  std::vector<double> ink, paper;  // border and quiet-zone samples
  cv::Mat values(n, n, CV_64FC1);
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const int ring = std::min({x, y, n - 1 - x, n - 1 - y});
      // The quiet zone's corner bits: an AprilGrid's squares cover them.
      const bool corner = ring == 0 && (x == 0 || x == n - 1) && (y == 0 || y == n - 1);
      if (corner) continue;
      const Eigen::Vector2d p = Apply(*h, Eigen::Vector2d(x + 0.5, y + 0.5));
      if (!(p.x() >= 0 && p.y() >= 0 && p.x() <= gray.cols - 1 && p.y() <= gray.rows - 1)) {
        return out;
      }
      const double v = Sample(gray, p);
      values.at<double>(y, x) = v;
      if (ring == 0) paper.push_back(v);
      if (ring >= 1 && ring <= border) ink.push_back(v);
    }
  }
  out.inside = true;
  const double black = MedianOfCopy(ink), white = MedianOfCopy(paper);
  out.contrast = white - black;
  const double threshold = 0.5 * (black + white);
  for (const double v : ink) out.frame_misses += v >= threshold;
  for (const double v : paper) out.frame_misses += v < threshold;
  out.frame_bits = static_cast<int>(ink.size() + paper.size());
  for (int y = border + 1; y < n - border - 1; ++y) {
    for (int x = border + 1; x < n - border - 1; ++x) {
      const bool read_ink = values.at<double>(y, x) < threshold;
      const bool code_ink = code.at<uint8_t>(y, x) < 128;
      out.hamming += read_ink != code_ink;
    }
  }
  return out;
}

bool Verified(const CodeRead& read, const GrowthOptions& options) {
  return read.inside && read.contrast >= options.min_contrast &&
         read.frame_misses <= options.max_frame_miss_fraction * read.frame_bits &&
         read.hamming <= options.max_hamming;
}

// Code bit size [px] along the shortest edge of a quad.
double QuadBitPixels(const Corners& c, int width_at_border) {
  double shortest = 1e300;
  for (int k = 0; k < 4; ++k) shortest = std::min(shortest, (c[(k + 1) % 4] - c[k]).norm());
  return shortest / width_at_border;
}

// The second prediction (step 2): each corner of the tag from the found
// tags that share its junction (the AprilGrid square at that corner, or the
// gap's crossing), through the homography of that tag's own four corners: an
// extrapolation over one gap instead of across the block of neighbours, which
// a strongly curved view (a bent board at a fisheye's edge) favours. Nothing
// when a corner has no such tag.
std::optional<Corners> PredictFromJunctions(const TagBoard& board, const std::vector<int>& near,
                                            const std::map<int, Corners>& found,
                                            const Corners& target) {
  // A corner across a gap is `spacing` away, across its diagonal sqrt(2) times.
  const double reach = 1.5 * board.spacing + 1e-9 * board.tag_size;
  Corners out;
  for (int k = 0; k < 4; ++k) {
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    int count = 0;
    for (const int j : near) {
      const std::array<Eigen::Vector3d, 4> b3 = board.CornersInBoard(j);
      std::vector<Eigen::Vector2d> src, dst;
      bool touches = false;
      for (int m = 0; m < 4; ++m) {
        src.push_back(b3[m].head<2>());
        dst.push_back(found.at(j)[m]);
        touches |= (b3[m].head<2>() - target[k]).norm() <= reach;
      }
      if (!touches) continue;
      if (const std::optional<Eigen::Matrix3d> h = FitHomography(src, dst)) {
        sum += Apply(*h, target[k]);
        ++count;
      }
    }
    if (count == 0) return std::nullopt;
    out[k] = sum / count;
  }
  return out;
}

// Steps 3 to 5 for one prediction (board coordinates `target` predicted at
// image corners `start`): snap, read, refine, read again. Fills *d and
// returns true when the tag holds.
bool TryTag(const cv::Mat& gray, const TagBoard& board, const TagFamilyInfo& info,
            const cv::Mat& code, Corners start, TagDetector* detector,
            const GrowthOptions& options, TagDetection* d) {
  for (const Eigen::Vector2d& c : start) {
    if (!(c.allFinite() && c.x() >= 0 && c.y() >= 0 && c.x() <= gray.cols - 1 &&
          c.y() <= gray.rows - 1)) {
      return false;
    }
  }
  const double bit = QuadBitPixels(start, info.width_at_border);
  if (!(bit >= 1.0)) return false;

  // Step 3: snap to the saddle points (a border of 2 bits or more keeps
  // the window clear of the data bits; a 1-bit border would not). First
  // in a window of 1.5 bits either way, which reaches a corner predicted
  // up to 2 bits off (the fisheye views of TUM VI: 1 bit typical, 2 at
  // the image's edge) and still ends before the square's far corners (3
  // bits away on Kalibr's grids), then in one of 0.8 bits, clear of
  // the border's inner edge.
  if (board.border_bits >= 2) {
    for (const auto& [window_bits, max_move_bits] : {std::pair{1.5, 2.0}, {0.8, 1.0}}) {
      const int half = std::clamp(static_cast<int>(std::lround(window_bits * bit)), 2, 12);
      std::vector<cv::Point2f> pts;
      for (const Eigen::Vector2d& c : start) {
        pts.emplace_back(static_cast<float>(c.x()), static_cast<float>(c.y()));
      }
      cv::cornerSubPix(gray, pts, cv::Size(half, half), cv::Size(-1, -1),
                       cv::TermCriteria(cv::TermCriteria::MAX_ITER | cv::TermCriteria::EPS, 30,
                                        1e-3));
      for (int k = 0; k < 4; ++k) {
        const Eigen::Vector2d snapped(pts[k].x, pts[k].y);
        if (snapped.allFinite() && (snapped - start[k]).norm() < max_move_bits * bit) {
          start[k] = snapped;
        }
      }
    }
  }

  // Step 4: the tag's own bits, a first look: worth refining when they are
  // near the code (the snapped corners can still be a fraction of a bit
  // off); the verdict is the read at the refined corners.
  const CodeRead read = ReadCode(gray, code, info, start);
  if (!(read.inside && read.contrast >= options.min_contrast &&
        read.frame_misses <= 2 * options.max_frame_miss_fraction * read.frame_bits &&
        read.hamming <= 2 * options.max_hamming)) {
    return false;
  }

  // Step 5: its own edges or pattern; read again where they put it.
  d->apriltag_corners = start;
  d->from_neighbours = true;
  detector->Refine(gray, d);
  if (!d->refined()) return false;
  const CodeRead again = ReadCode(gray, code, info, d->corners);
  if (!Verified(again, options)) return false;
  d->hamming = again.hamming;
  d->decision_margin = again.contrast;
  return true;
}

}  // namespace

std::string GrowthOptions::Check() const {
  if (max_hamming < 0) return "max_hamming: expected >= 0";
  if (!(max_frame_miss_fraction >= 0 && max_frame_miss_fraction < 0.5)) {
    return "max_frame_miss_fraction: expected in [0, 0.5)";
  }
  if (!(min_contrast > 0)) return "min_contrast: expected > 0";
  return "";
}

void GrowBoardTags(const cv::Mat& gray, const TagBoard& board, TagDetector* detector,
                   std::vector<TagDetection>* detections, const GrowthOptions& options) {
  if (board.IsPointBoard() || !TakesWideBorder(board.family)) return;
  const TagFamilyInfo info = GetTagFamilyInfo(board.family, board.border_bits);
  const TagFamilyPtr family = CreateTagFamily(board.family, board.border_bits);
  auto ours = [&](const TagDetection& d) {
    return d.family == board.family && d.border_bits == board.border_bits && board.HasId(d.id);
  };
  // Seeds: refined and found once.
  std::map<int, int> count;
  for (const TagDetection& d : *detections) {
    if (ours(d)) ++count[d.id];
  }
  std::map<int, Corners> found;  // by tag index
  for (const TagDetection& d : *detections) {
    if (ours(d) && d.refined() && count[d.id] == 1) found[d.id - board.first_id] = d.corners;
  }
  if (found.empty()) return;

  const int n = board.NumTags();
  // Board coordinates of a tag's corners (x, y of the board frame).
  auto board_corners = [&](int index) {
    const std::array<Eigen::Vector3d, 4> c = board.CornersInBoard(index);
    return Corners{c[0].head<2>(), c[1].head<2>(), c[2].head<2>(), c[3].head<2>()};
  };
  // The found tags within `reach` cells of tag `index`.
  auto neighbours = [&](int index, int reach) {
    const GridCell cell = board.GridOf(index);
    std::vector<int> out;
    for (int dr = -reach; dr <= reach; ++dr) {
      for (int dc = -reach; dc <= reach; ++dc) {
        const GridCell other{cell.row + dr, cell.col + dc};
        if ((dr == 0 && dc == 0) || other.row < 0 || other.col < 0 || other.row >= board.rows ||
            other.col >= board.cols) {
          continue;
        }
        const int j = board.IndexOf(other);
        if (found.count(j) > 0) out.push_back(j);
      }
    }
    return out;
  };

  std::vector<TagDetection> grown;
  std::map<int, std::vector<int>> tried_with;  // index -> the neighbours of its last try
  // The cells to try: those within two cells of a found tag, queued again
  // when a tag is found near them. A cell is tried again only when its
  // neighbours have changed, and they only grow: at most 24 times.
  std::deque<int> queue;
  std::vector<char> queued(n, 0);
  auto enqueue_around = [&](int index) {
    const GridCell cell = board.GridOf(index);
    for (int dr = -2; dr <= 2; ++dr) {
      for (int dc = -2; dc <= 2; ++dc) {
        const GridCell other{cell.row + dr, cell.col + dc};
        if (other.row < 0 || other.col < 0 || other.row >= board.rows || other.col >= board.cols) {
          continue;
        }
        const int j = board.IndexOf(other);
        if (found.count(j) == 0 && !queued[j]) {
          queued[j] = 1;
          queue.push_back(j);
        }
      }
    }
  };
  for (const auto& [index, corners] : found) enqueue_around(index);
  while (!queue.empty()) {
    const int index = queue.front();
    queue.pop_front();
    queued[index] = 0;
    // A tag libapriltag found twice (two printed copies) stays out.
    if (found.count(index) > 0 || count[board.first_id + index] >= 2) continue;
    std::vector<int> near = neighbours(index, 1);
    if (near.empty()) continue;
    if (near.size() < 2) near = neighbours(index, 2);
    auto& last = tried_with[index];
    if (last == near) continue;  // nothing new to predict from
    last = near;

    // Step 2: the predictions, each tried in turn until one holds.
    const Corners target = board_corners(index);
    std::vector<Corners> predictions;
    {
      std::vector<Eigen::Vector2d> src, dst;
      for (const int j : near) {
        const Corners b = board_corners(j);
        for (int k = 0; k < 4; ++k) {
          src.push_back(b[k]);
          dst.push_back(found[j][k]);
        }
      }
      if (const std::optional<Eigen::Matrix3d> h = FitHomography(src, dst)) {
        Corners p;
        for (int k = 0; k < 4; ++k) p[k] = Apply(*h, target[k]);
        predictions.push_back(p);
      }
    }
    if (const std::optional<Corners> p = PredictFromJunctions(board, near, found, target)) {
      predictions.push_back(*p);
    }
    const cv::Mat code = TagCodeImage(family.get(), board.first_id + index);
    for (const Corners& prediction : predictions) {
      TagDetection d;
      d.family = board.family;
      d.border_bits = board.border_bits;
      d.id = board.first_id + index;
      if (!TryTag(gray, board, info, code, prediction, detector, options, &d)) continue;
      found[index] = d.corners;
      grown.push_back(d);
      enqueue_around(index);
      break;
    }
  }
  if (grown.empty()) return;
  // A tag libapriltag found but could not refine is replaced by the grown one.
  detections->erase(std::remove_if(detections->begin(), detections->end(),
                                   [&](const TagDetection& d) {
                                     return ours(d) && !d.refined() &&
                                            found.count(d.id - board.first_id) > 0;
                                   }),
                    detections->end());
  detections->insert(detections->end(), grown.begin(), grown.end());
}

}  // namespace rtscalib::detect

#include "detect/detector.h"

#include <apriltag.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <vector>

#include "detect/tag_family.h"

namespace rtscalib::detect {
namespace {

// One edge in its own frame: p(t) = origin + t dir + s(t) normal with
// s(t) = c0 + c1 t + c2 t^2, t in [0, length].
struct EdgeCurve {
  Eigen::Vector2d origin, dir, normal;
  double length = 0;
  Eigen::Vector3d coef = Eigen::Vector3d::Zero();

  double S(double t) const { return coef[0] + t * (coef[1] + t * coef[2]); }
  double DS(double t) const { return coef[1] + 2 * t * coef[2]; }
  Eigen::Vector2d At(double t) const { return origin + t * dir + S(t) * normal; }
  Eigen::Vector2d Tangent(double t) const { return dir + DS(t) * normal; }
};

EdgeCurve StraightEdge(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  EdgeCurve e;
  e.origin = a;
  e.length = (b - a).norm();
  e.dir = (b - a) / e.length;
  e.normal = Eigen::Vector2d(-e.dir.y(), e.dir.x());
  return e;
}

// Reorders v.
double Median(std::vector<double>& v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// A slowly changing level along `values` (one per strip, in strip order):
// the median of each block of `block` consecutive values (the last block
// takes the remainder), and out[i] linear between the blocks' centres,
// constant beyond the first and the last. Each block's median ignores a
// strip or two that graze another feature; the whole costs one pass of
// nth_element, as one median of all the values would. Reorders `work`.
void BlockLevels(const std::vector<double>& values, int block, std::vector<double>* work,
                 std::vector<double>* centres, std::vector<double>* levels,
                 std::vector<double>* out) {
  const int n = static_cast<int>(values.size());
  const int blocks = std::max(1, n / block);
  *work = values;
  centres->clear();
  levels->clear();
  for (int k = 0; k < blocks; ++k) {
    const int i0 = k * block, i1 = k + 1 == blocks ? n : i0 + block;
    const auto mid = work->begin() + (i0 + i1) / 2;
    std::nth_element(work->begin() + i0, mid, work->begin() + i1);
    centres->push_back(0.5 * (i0 + i1 - 1));
    levels->push_back(*mid);
  }
  out->resize(n);
  int k = 0;
  for (int i = 0; i < n; ++i) {
    while (k + 1 < blocks && (*centres)[k + 1] <= i) ++k;
    if (k + 1 == blocks || i <= (*centres)[0]) {
      (*out)[i] = (*levels)[i <= (*centres)[0] ? 0 : k];
    } else {
      const double f = (i - (*centres)[k]) / ((*centres)[k + 1] - (*centres)[k]);
      (*out)[i] = (*levels)[k] + f * ((*levels)[k + 1] - (*levels)[k]);
    }
  }
}

// The buffers of one tag's refinement, reused from edge to edge and
// iteration to iteration: some 4,400 tags of a photo session take twelve
// edge samplings each, and the allocations were a good part of the time
// (most of it under the sanitizers' allocator).
struct EdgeScratch {
  struct Strip {
    int q, i0, i1;
    double first, last, sum;
  };
  std::vector<Strip> strips;
  std::vector<double> firsts, lasts, ts, ss, work, centres, medians, levels_a, levels_b;
  std::vector<Eigen::Vector2d> points;
};

// Sub-pixel points of one edge by strip areas. The edge is crossed by strips
// of whole pixels along the image axis closest to its normal (rows for steep
// edges, columns for flat ones), one strip per pixel row/column, centred on
// the current curve and reaching `half_width` either side along the normal.
// With plateau levels a (strip start) and b (strip end), a strip of pixels
// i0..i1 puts the edge at
//   e = i1 + 1/2 - sum_i (f_i - a) / (b - a),
// the length of the a-side of the strip. A pixel's value is the area average of
// the scene over the pixel, so the sum is the exact area of the b side; any
// blur that is point-symmetric moves as much area across the edge as back
// (unlike the mid-level crossing of an interpolated profile, which is biased
// by up to ~0.05 px depending on where the edge falls within a pixel).
// Strips within `end_gap` of the curve's ends (the corners) are skipped.
bool EdgePoints(const cv::Mat& img, const EdgeCurve& e, double half_width, double end_gap,
                EdgeScratch* scratch) {
  std::vector<Eigen::Vector2d>* points = &scratch->points;
  points->clear();
  // a: axis the strips run along; o: the axis that indexes the strips.
  const int a = std::abs(e.dir.x()) < std::abs(e.dir.y()) ? 0 : 1;
  const int o = 1 - a;
  const int size_a = a == 0 ? img.cols : img.rows, size_o = a == 0 ? img.rows : img.cols;
  const Eigen::Vector2d p0 = e.At(end_gap), p1 = e.At(e.length - end_gap);
  if (!(p1[o] != p0[o])) return false;
  const int q0 = static_cast<int>(std::ceil(std::min(p0[o], p1[o])));
  const int q1 = static_cast<int>(std::floor(std::max(p0[o], p1[o])));
  using Strip = EdgeScratch::Strip;
  std::vector<Strip>& strips = scratch->strips;
  std::vector<double>& firsts = scratch->firsts;
  std::vector<double>& lasts = scratch->lasts;
  strips.clear();
  firsts.clear();
  lasts.clear();
  for (int q = q0; q <= q1; ++q) {
    if (q < 0 || q >= size_o) continue;
    // The curve's crossing of line o = q (Newton on At(t)[o] = q).
    double t = end_gap + (q - p0[o]) / (p1[o] - p0[o]) * (e.length - 2 * end_gap);
    for (int it = 0; it < 5; ++it) t -= (e.At(t)[o] - q) / e.Tangent(t)[o];
    const Eigen::Vector2d tangent = e.Tangent(t).normalized();
    const double cos_axis = std::abs(tangent[o]);  // = |unit normal component along a|
    const double c = e.At(t)[a];
    const double reach = half_width / cos_axis;
    const int i0 = static_cast<int>(std::lround(c - reach));
    const int i1 = static_cast<int>(std::lround(c + reach));
    if (i0 < 0 || i1 >= size_a || i1 - i0 < 3) continue;
    const int m = i1 - i0 >= 9 ? 2 : 1;  // plateau pixels at each end
    Strip s{q, i0, i1, 0, 0, 0};
    for (int i = i0; i <= i1; ++i) {
      const double f = a == 0 ? img.at<uint8_t>(q, i) : img.at<uint8_t>(i, q);
      s.sum += f;
      if (i < i0 + m) s.first += f / m;
      if (i > i1 - m) s.last += f / m;
    }
    strips.push_back(s);
    firsts.push_back(s.first);
    lasts.push_back(s.last);
  }
  if (strips.size() < 4) return false;
  // The two levels along the edge: ink and paper are uniform, but the light
  // on them need not be (a lamp to one side, vignetting): a level that
  // changes by d along the edge, taken as constant, moves the strips' edge
  // points by up to d / (lb - la) strip lengths and tilts the fitted edge
  // (on swat_tags_hallway, a tag of 8.6 px bits lit from one side: its
  // corners 2.5 px off). So each level is a line along the edge through the
  // medians of the edge's two halves (BlockLevels with two blocks): it
  // follows a gradient of the light, a strip that grazes another feature
  // does not move it, and each median still pools half of the edge's
  // strips. Smaller blocks follow the light more closely but pass their
  // medians' noise into the edge points: with blocks of 8 strips the
  // rendered zoom3 session's corners were a third further from the exact
  // projections (detected vs exact corners in the run's log).
  const int level_block = std::max(8, static_cast<int>(strips.size() + 1) / 2);
  const double la0 = Median(firsts), lb0 = Median(lasts);
  if (std::abs(lb0 - la0) < 10.0) return false;
  // firsts and lasts are in strip order again (Median reorders them).
  for (size_t i = 0; i < strips.size(); ++i) {
    firsts[i] = strips[i].first;
    lasts[i] = strips[i].last;
  }
  BlockLevels(firsts, level_block, &scratch->work, &scratch->centres, &scratch->medians,
              &scratch->levels_a);
  BlockLevels(lasts, level_block, &scratch->work, &scratch->centres, &scratch->medians,
              &scratch->levels_b);
  const int count = static_cast<int>(strips.size());
  for (int i = 0; i < count; ++i) {
    const Strip& s = strips[i];
    const double la = scratch->levels_a[i], lb = scratch->levels_b[i];
    if (std::abs(lb - la) < 10.0) continue;
    const int n = s.i1 - s.i0 + 1;
    const double edge = s.i1 + 0.5 - (s.sum - n * la) / (lb - la);
    if (edge < s.i0 - 0.5 || edge > s.i1 + 0.5) continue;  // not a step here
    Eigen::Vector2d p;
    p[a] = edge;
    p[o] = s.q;
    points->push_back(p);
  }
  return points->size() >= 4;
}

// Fits s(t) to the points, in the frame of `edge` (replaces its coefficients,
// keeping the frame). Least squares by the normal equations of the columns
// 1, u, u^2 with u = t / length in [0, 1] (condition number of the normal
// matrix ~1e3 for points spread along the edge): no allocation per edge.
bool FitEdge(const std::vector<double>& ts, const std::vector<double>& ss, bool quadratic,
             EdgeCurve* edge) {
  const int n = static_cast<int>(ts.size());
  const int m = quadratic ? 3 : 2;
  if (n < m + 3) return false;
  const double scale = edge->length;  // conditions the columns
  Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
  Eigen::Vector3d atb = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    const double u = ts[i] / scale;
    const Eigen::Vector3d row(1.0, u, quadratic ? u * u : 0.0);
    ata.selfadjointView<Eigen::Lower>().rankUpdate(row);
    atb += ss[i] * row;
  }
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  if (quadratic) {
    x = ata.selfadjointView<Eigen::Lower>().ldlt().solve(atb);
  } else {
    const Eigen::Matrix2d a2 = ata.topLeftCorner<2, 2>().selfadjointView<Eigen::Lower>();
    x.head<2>() = a2.ldlt().solve(atb.head<2>());
  }
  if (!x.allFinite()) return false;
  edge->coef = Eigen::Vector3d(x(0), x(1) / scale, x(2) / (scale * scale));
  return true;
}

// The intersection of `a` near its end (t = length) and `b` near its start
// (t = 0), by Newton's method on a(ta) - b(tb) = 0.
bool Intersect(const EdgeCurve& a, const EdgeCurve& b, Eigen::Vector2d* corner) {
  double ta = a.length, tb = 0;
  for (int it = 0; it < 20; ++it) {
    const Eigen::Vector2d f = a.At(ta) - b.At(tb);
    Eigen::Matrix2d j;
    j.col(0) = a.Tangent(ta);
    j.col(1) = -b.Tangent(tb);
    const double det = j.determinant();
    if (std::abs(det) < 1e-9) return false;
    const Eigen::Vector2d step = j.inverse() * f;
    ta -= step(0);
    tb -= step(1);
    if (step.norm() < 1e-10) break;
  }
  *corner = 0.5 * (a.At(ta) + b.At(tb));
  return corner->allFinite();
}

// Code bit size [px] along the shortest edge of a quad of `width_at_border` bits.
double BitPixels(const std::array<Eigen::Vector2d, 4>& corners, int width_at_border) {
  double min_len = 1e300;
  for (int k = 0; k < 4; ++k) {
    min_len = std::min(min_len, (corners[(k + 1) % 4] - corners[k]).norm());
  }
  return min_len / width_at_border;
}

}  // namespace

double EstimateNoiseSigma(const cv::Mat& gray) {
  if (gray.type() != CV_8UC1) throw std::invalid_argument("EstimateNoiseSigma: expected CV_8UC1");
  // |L| <= 16 * 255; a histogram gives the median in one pass.
  std::vector<int> histogram(16 * 255 + 1, 0);
  int n = 0;
  for (int y = 1; y + 1 < gray.rows; y += 2) {
    const uint8_t* a = gray.ptr<uint8_t>(y - 1);
    const uint8_t* b = gray.ptr<uint8_t>(y);
    const uint8_t* c = gray.ptr<uint8_t>(y + 1);
    for (int x = 1; x + 1 < gray.cols; x += 2) {
      const int l = a[x - 1] - 2 * a[x] + a[x + 1] - 2 * b[x - 1] + 4 * b[x] - 2 * b[x + 1] +
                    c[x - 1] - 2 * c[x] + c[x + 1];
      ++histogram[std::abs(l)];
      ++n;
    }
  }
  if (n == 0) return 0.0;
  // The median, interpolated within its bin (|L| = k stands for [k - 1/2,
  // k + 1/2)): integer grey levels would otherwise quantise the estimate in
  // steps of 1/4 sigma.
  const double half = 0.5 * n;
  double below = 0;
  int k = 0;
  while (below + histogram[k] < half) below += histogram[k++];
  const double median = std::max(0.0, k - 0.5 + (half - below) / histogram[k]);
  return median / (6.0 * 0.6745);
}

std::string DetectorOptions::Check() const {
  if (families.empty()) return "families: expected at least one tag family";
  for (const PrintedFamily& f : families) {
    if (std::find(KnownTagFamilies().begin(), KnownTagFamilies().end(), f.name) ==
        KnownTagFamilies().end()) {
      return "families: unknown tag family '" + f.name + "'";
    }
    if (f.border_bits != 1 && (f.border_bits < 1 || !TakesWideBorder(f.name))) {
      return "families: " + f.name + " cannot have a black border of " +
             std::to_string(f.border_bits) + " bits";
    }
  }
  if (threads < 1) return "threads: expected >= 1, got " + std::to_string(threads);
  if (!(quad_sigma >= 0)) return "quad_sigma: expected >= 0";
  if (!(decode_sharpening >= 0)) return "decode_sharpening: expected >= 0";
  if (max_hamming < 0 || max_hamming > 3) {
    return "max_hamming: expected 0..3, got " + std::to_string(max_hamming);
  }
  if (!(min_bit_pixels >= 1.5)) return "min_bit_pixels: expected >= 1.5";
  if (!(max_refine_shift > 0)) return "max_refine_shift: expected > 0";
  if (!(min_pattern_bit_pixels >= 1.0)) return "min_pattern_bit_pixels: expected >= 1";
  if (const std::string msg = pattern.Check(); !msg.empty()) return "pattern." + msg;
  if (!(segmentation_noise_multiple >= 0)) return "segmentation_noise_multiple: expected >= 0";
  if (!(max_segmentation_contrast >= 5)) return "max_segmentation_contrast: expected >= 5";
  if (!(wide_border_gamma > 0 && wide_border_gamma <= 1)) {
    return "wide_border_gamma: expected in (0, 1]";
  }
  return "";
}

bool RefineTagCorners(const cv::Mat& gray, int width_at_border, const DetectorOptions& options,
                      std::array<Eigen::Vector2d, 4>* corners) {
  std::array<Eigen::Vector2d, 4> c = *corners;
  const double bit = BitPixels(c, width_at_border);
  if (bit < options.min_bit_pixels) return false;
  // The strips must stay on the two bits either side of the edge (the next
  // bit edges are one bit away), less rounding to whole pixels, a pixel's own
  // half width and the rendered/optical blur: bit - 2 px; 8 px of plateau is
  // plenty for any blur worth detecting.
  const double half_width = std::clamp(bit - 2.0, 1.5, 8.0);

  std::array<EdgeCurve, 4> edges;
  for (int k = 0; k < 4; ++k) edges[k] = StraightEdge(c[k], c[(k + 1) % 4]);
  EdgeScratch scratch;
  for (int iteration = 0; iteration < 3; ++iteration) {
    std::array<EdgeCurve, 4> fitted;
    for (int k = 0; k < 4; ++k) {
      const EdgeCurve& e = edges[k];
      // Keep the profiles clear of the neighbouring edges at the corners.
      const double end_gap = std::max(half_width + 1.5, 0.5 * bit);
      if (!EdgePoints(gray, e, half_width, end_gap, &scratch)) return false;
      std::vector<double>& ts = scratch.ts;
      std::vector<double>& ss = scratch.ss;
      ts.clear();
      ss.clear();
      for (const Eigen::Vector2d& p : scratch.points) {
        ts.push_back((p - e.origin).dot(e.dir));
        ss.push_back((p - e.origin).dot(e.normal));
      }
      fitted[k] = e;
      // Curvature only pays on long edges; short ones keep a straight line.
      const bool quadratic = e.length > 60.0;
      if (ts.size() < 0.5 * (e.length - 2 * end_gap) || !FitEdge(ts, ss, quadratic, &fitted[k])) {
        return false;
      }
    }
    for (int k = 0; k < 4; ++k) {
      if (!Intersect(fitted[(k + 3) % 4], fitted[k], &c[k])) return false;
    }
    for (int k = 0; k < 4; ++k) {
      // Re-centre: new straight frames through the new corners, carrying the
      // curvature of the fit over to the next sampling.
      EdgeCurve e = StraightEdge(c[k], c[(k + 1) % 4]);
      e.coef[2] = fitted[k].coef[2];
      e.coef[1] = -e.coef[2] * e.length;  // s(0) = s(L) = 0 on the new chord
      edges[k] = e;
    }
  }
  for (int k = 0; k < 4; ++k) {
    if ((c[k] - (*corners)[k]).norm() > options.max_refine_shift) return false;
  }
  *corners = c;
  return true;
}

const char* CornerRefinementName(CornerRefinement refinement) {
  switch (refinement) {
    case CornerRefinement::kNone:
      return "none";
    case CornerRefinement::kEdges:
      return "edges";
    case CornerRefinement::kPattern:
      return "pattern";
    case CornerRefinement::kSaddle:
      return "saddle";
  }
  return "?";
}

struct TagDetector::Impl {
  struct Family {
    PrintedFamily printed;
    TagFamilyPtr family;
    int width_at_border = 0, border_offset = 0;
    std::map<int, cv::Mat> codes;  // code images by id, made on first use

    // The code image the pattern fit matches. A wider border is Kalibr's
    // AprilGrid, whose black squares between the tags cover the corner bits
    // of each tag's quiet zone; other prints leave them white. Those four
    // bits are marked unknown (tag_pattern_fit.h), so that the fit holds for
    // both.
    const cv::Mat& Code(int id) {
      auto it = codes.find(id);
      if (it == codes.end()) {
        cv::Mat code = TagCodeImage(family.get(), id);
        if (printed.border_bits > 1) {
          const int last = code.cols - 1;
          for (const auto& [x, y] : {std::pair{0, 0}, {last, 0}, {0, last}, {last, last}}) {
            code.at<uint8_t>(y, x) = kUnknownCodeBit;
          }
        }
        it = codes.emplace(id, code).first;
      }
      return it->second;
    }
  };
  DetectorOptions options;
  std::map<PrintedFamily, Family> families;
  std::map<const apriltag_family*, const Family*> by_family;
  // One libapriltag pass for the families of a 1-bit border, on the photo;
  // one for those of a wider border, on the photo's levels seen through
  // wide_border_gamma (detector.h). Either is null when no family needs it.
  apriltag_detector_t* narrow = nullptr;
  apriltag_detector_t* wide = nullptr;
  cv::Mat wide_levels;  // the 256-entry lookup table of the wide pass

  apriltag_detector_t* NewPass() const {
    apriltag_detector_t* td = apriltag_detector_create();
    td->nthreads = options.threads;
    td->quad_decimate = 1.0f;
    td->quad_sigma = options.quad_sigma;
    td->refine_edges = true;
    td->decode_sharpening = options.decode_sharpening;
    return td;
  }

  // One pass of libapriltag on `seen` (the photo or its remapped levels),
  // its detections refined on the photo itself (`img`) and appended.
  void Pass(apriltag_detector_t* td, const cv::Mat& seen, const cv::Mat& img,
            std::vector<TagDetection>* out) {
    image_u8_t im{seen.cols, seen.rows, static_cast<int32_t>(seen.step[0]), seen.data};
    const double contrast =
        std::clamp(options.segmentation_noise_multiple * EstimateNoiseSigma(seen), 5.0,
                   options.max_segmentation_contrast);
    td->qtp.min_white_black_diff = static_cast<int>(std::lround(contrast));
    zarray_t* found = apriltag_detector_detect(td, &im);
    for (int i = 0; i < zarray_size(found); ++i) {
      apriltag_detection_t* det;
      zarray_get(found, i, &det);
      if (det->hamming > options.max_hamming) continue;
      TagDetection d;
      d.family = det->family->name;
      d.border_bits = by_family.at(det->family)->printed.border_bits;
      d.id = det->id;
      d.hamming = det->hamming;
      d.decision_margin = det->decision_margin;
      // libapriltag's pixel (x, y) spans [x, x+1): its coordinates are OpenCV's + 0.5.
      for (int k = 0; k < 4; ++k) {
        d.apriltag_corners[k] = Eigen::Vector2d(det->p[k][0] - 0.5, det->p[k][1] - 0.5);
      }
      d.corners = d.apriltag_corners;
      if (options.refine_corners) Refine(img, &d);
      out->push_back(d);
    }
    apriltag_detections_destroy(found);
  }

  // Refines d's corners in place: edges when the bits are big enough and the
  // edges hold, else the whole pattern; sets d->refinement.
  void Refine(const cv::Mat& img, TagDetection* d) {
    d->corners = d->apriltag_corners;
    d->refinement = CornerRefinement::kNone;
    Family& f = families.at(PrintedFamily{d->family, d->border_bits});
    if (RefineTagCorners(img, f.width_at_border, options, &d->corners)) {
      d->refinement = CornerRefinement::kEdges;
      return;
    }
    if (BitPixels(d->apriltag_corners, f.width_at_border) < options.min_pattern_bit_pixels) return;
    const PatternFitResult fit =
        FitTagPattern(img, f.Code(d->id), f.border_offset, f.width_at_border, d->apriltag_corners,
                      options.pattern);
    if (!fit.converged) return;
    for (int k = 0; k < 4; ++k) {
      if ((fit.corners[k] - d->apriltag_corners[k]).norm() > options.max_refine_shift) return;
    }
    d->corners = fit.corners;
    d->refinement = CornerRefinement::kPattern;
  }

  ~Impl() {
    if (narrow != nullptr) apriltag_detector_destroy(narrow);
    if (wide != nullptr) apriltag_detector_destroy(wide);
  }
};

TagDetector::TagDetector(const DetectorOptions& options) : impl_(std::make_unique<Impl>()) {
  if (const std::string msg = options.Check(); !msg.empty()) {
    throw std::invalid_argument("DetectorOptions: " + msg);
  }
  impl_->options = options;
  for (const PrintedFamily& printed : options.families) {
    Impl::Family& f = impl_->families[printed];
    if (f.family) continue;  // listed twice
    f.printed = printed;
    f.family = CreateTagFamily(printed);
    f.width_at_border = f.family->width_at_border;
    f.border_offset = (f.family->total_width - f.family->width_at_border) / 2;
    impl_->by_family[f.family.get()] = &f;
    apriltag_detector_t*& pass = printed.border_bits > 1 ? impl_->wide : impl_->narrow;
    if (pass == nullptr) pass = impl_->NewPass();
    apriltag_detector_add_family_bits(pass, f.family.get(), std::max(2, options.max_hamming));
  }
  impl_->wide_levels = cv::Mat(1, 256, CV_8UC1);
  for (int v = 0; v < 256; ++v) {
    impl_->wide_levels.at<uint8_t>(v) =
        cv::saturate_cast<uint8_t>(255.0 * std::pow(v / 255.0, options.wide_border_gamma));
  }
}

TagDetector::~TagDetector() = default;

const DetectorOptions& TagDetector::options() const { return impl_->options; }

void TagDetector::Refine(const cv::Mat& gray, TagDetection* d) {
  if (gray.type() != CV_8UC1)
    throw std::invalid_argument("TagDetector::Refine: expected a CV_8UC1 image");
  impl_->Refine(gray, d);
}

std::vector<TagDetection> TagDetector::Detect(const cv::Mat& gray) {
  if (gray.type() != CV_8UC1)
    throw std::invalid_argument("TagDetector::Detect: expected a CV_8UC1 image");
  const cv::Mat img = gray.isContinuous() ? gray : gray.clone();
  std::vector<TagDetection> out;
  if (impl_->narrow != nullptr) impl_->Pass(impl_->narrow, img, img, &out);
  if (impl_->wide != nullptr) {
    cv::Mat seen;
    cv::LUT(img, impl_->wide_levels, seen);
    impl_->Pass(impl_->wide, seen, img, &out);
  }
  return out;
}

}  // namespace rtscalib::detect

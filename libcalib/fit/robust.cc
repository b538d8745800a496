#include "libcalib/fit/robust.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>

#include "libcalib/eval/error_measures.h"
#include "libcalib/fit/parameterization.h"
#include "libcalib/fit/refine.h"
#include "libcalib/fit/unknowns.h"

namespace rtscalib {
namespace {

// Medians of the chi distribution: sqrt of chi-square's median (3 dof:
// 2.3660, 2 dof: 2 ln 2).
constexpr double kChi3Median = 1.5382, kChi2Median = 1.1774;
// Rows per robust sigma along the distance: the median of 40 chi values
// is good to about 10 %.
constexpr size_t kRun = 40;
// Iterations of the least-squares try: it starts from the extraction,
// whose error is far below a gross error's, and only has to show whether
// any row is flagged. The robust fit's own follow from its residual blocks
// (RobustSearchIterations, refine.h).
constexpr int kLeastSquaresIterations = 8;
// Robust sigmas below this fraction of the a-priori sigma are raised to it.
constexpr double kSigmaFloor = 0.01;
const char* const kGroupNames[3] = {"EDM rows", "camera rows", "pixels"};
const char* const kUnits[3] = {"m", "m", "px"};

struct Row {
  int group = 0;  // 0 EDM, 1 camera rows, 2 pixels
  int index = 0;
  double r = 0;  // |residual|, NaN when the model cannot evaluate the row
  Eigen::Vector2d delta = Eigen::Vector2d::Zero();  // pixels: the residual [px]
};

// Image points of other photos that a flagged one is compared with: the
// nearest this many in the image of its zoom.
constexpr int kNeighbours = 8;
// Cells per image side of the index that finds them.
constexpr int kNeighbourCells = 32;

// The image points of one zoom's photos in a grid over the image, to find
// the points of other photos nearest an image position.
class ImageIndex {
 public:
  ImageIndex(const std::vector<Eigen::Vector2d>& uv, const std::vector<int>& rows)
      : uv_(uv), rows_(rows) {
    Eigen::Vector2d lo = uv.empty() ? Eigen::Vector2d::Zero() : uv[0], hi = lo;
    for (const Eigen::Vector2d& x : uv) {
      lo = lo.cwiseMin(x);
      hi = hi.cwiseMax(x);
    }
    lo_ = lo;
    cell_ = std::max((hi - lo).maxCoeff() / kNeighbourCells, 1e-9);
    for (size_t i = 0; i < uv.size(); ++i) cells_[Cell(uv[i])].push_back(static_cast<int>(i));
  }
  // Up to `count` entries (indices into the constructor's lists) nearest
  // `at`, skipping those `skip` rejects, nearest first.
  template <typename Skip>
  std::vector<int> Nearest(const Eigen::Vector2d& at, int count, Skip skip) const {
    const std::pair<int, int> centre = Cell(at);
    std::vector<std::pair<double, int>> found;
    for (int ring = 0; ring <= 2 * kNeighbourCells; ++ring) {
      for (int dy = -ring; dy <= ring; ++dy) {
        for (int dx = -ring; dx <= ring; ++dx) {
          if (std::max(std::abs(dx), std::abs(dy)) != ring) continue;
          const auto it = cells_.find({centre.first + dx, centre.second + dy});
          if (it == cells_.end()) continue;
          for (int i : it->second) {
            if (!skip(i)) found.push_back({(uv_[i] - at).squaredNorm(), i});
          }
        }
      }
      // Every point beyond this ring is farther than `ring` cells.
      if (static_cast<int>(found.size()) >= count) {
        std::partial_sort(found.begin(), found.begin() + count, found.end());
        if (found[count - 1].first <= (ring * cell_) * (ring * cell_)) break;
      }
    }
    std::sort(found.begin(), found.end());
    std::vector<int> out;
    for (int k = 0; k < count && k < static_cast<int>(found.size()); ++k) {
      out.push_back(found[k].second);
    }
    return out;
  }
  int Row(int i) const { return rows_[i]; }

 private:
  std::pair<int, int> Cell(const Eigen::Vector2d& x) const {
    return {static_cast<int>(std::floor((x.x() - lo_.x()) / cell_)),
            static_cast<int>(std::floor((x.y() - lo_.y()) / cell_))};
  }
  std::vector<Eigen::Vector2d> uv_;
  std::vector<int> rows_;
  Eigen::Vector2d lo_;
  double cell_ = 1;
  std::map<std::pair<int, int>, std::vector<int>> cells_;
};

std::vector<Row> RowResiduals(const Observations& obs, const UsedRows& used,
                              const InstrumentModel& model) {
  const Observations est = WithEstimates(obs, model);
  std::vector<Row> out;
  std::vector<Record> records;
  for (int i : used.records) records.push_back(est.records[i]);
  for (const RecordResidual& rr : RecordResiduals(model, records)) {
    const int i = used.records[rr.index];
    out.push_back(
        {obs.records[i].tool == Tool::kEdm ? 0 : 1, i, rr.valid ? rr.distance : std::nan("")});
  }
  std::vector<PixelObservation> pixels;
  for (int i : used.pixels) pixels.push_back(est.pixels[i]);
  for (const PixelResidual& pr : PixelResiduals(model, pixels)) {
    out.push_back({2, used.pixels[pr.index], pr.valid ? pr.delta.norm() : std::nan(""),
                   pr.valid ? pr.delta : Eigen::Vector2d::Zero()});
  }
  return out;
}

ExcludedRow Excluded(const Observations& obs, const Row& row, const std::string& reason) {
  const int line = row.group == 2 ? obs.pixels[row.index].line : obs.records[row.index].line;
  return {row.group == 2, row.index, line, reason};
}

// Rows of each group flagged; none of a group whose flagged share exceeds
// max_fraction (then a note).
// The group of a flagged row (0 EDM, 1 camera rows, 2 pixels) in `obs`.
int GroupOf(const Observations& obs, const ExcludedRow& e) {
  return e.pixel ? 2 : (obs.records[e.index].tool == Tool::kEdm ? 0 : 1);
}

void Keep(const Observations& obs, const std::vector<Row>& rows,
          const std::vector<ExcludedRow>& flagged, const GrossErrorOptions& options,
          const char* what, RobustFitResult* out) {
  int count[3] = {0, 0, 0}, bad[3] = {0, 0, 0};
  for (const Row& r : rows) ++count[r.group];
  for (const ExcludedRow& e : flagged) ++bad[GroupOf(obs, e)];
  for (const ExcludedRow& e : flagged) {
    const int group = GroupOf(obs, e);
    if (bad[group] <= options.max_fraction * count[group]) out->gross.push_back(e);
  }
  for (int g = 0; g < 3; ++g) {
    if (bad[g] > options.max_fraction * count[g]) {
      out->notes.push_back(std::string("gross errors: ") + std::to_string(bad[g]) + " of " +
                           std::to_string(count[g]) + " " + kGroupNames[g] + " " + what +
                           ", more than fit.gross_errors.max_fraction; none excluded: the model "
                           "or the a-priori sigmas, not single rows, are wrong");
    }
  }
}

// Steps 3 and 4 (robust.h) at `model`: the rows of `usable` beyond
// `reject` robust sigmas, with the rows evaluated; the largest robust
// sigma per group into `robust_sigma`.
std::vector<ExcludedRow> Flag(const Observations& usable, const FitOptions& options,
                              const GrossErrorOptions& robust, const InstrumentModel* model,
                              std::vector<Row>* rows_out, double robust_sigma[3]) {
  // 3. Robust sigmas: per group (EDM rows, camera rows of a zoom, pixels of
  // a zoom) and, for records, along the distance: angle noise grows with d,
  // so rows sorted by d form runs of kRun rows with a sigma each (the last
  // run takes the remainder).
  const UsedRows used2 = SelectRows(usable, options, model->NumZooms(), UnknownZoom::kThrow);
  const std::vector<Row> rows = RowResiduals(usable, used2, *model);
  std::map<std::pair<int, int>, std::vector<int>> groups;  // (group, zoom) -> rows
  for (int k = 0; k < static_cast<int>(rows.size()); ++k) {
    const Row& r = rows[k];
    const int zoom = r.group == 2 ? usable.pixels[r.index].zoom
                                  : (r.group == 1 ? usable.records[r.index].zoom : 0);
    groups[{r.group, zoom}].push_back(k);
  }
  std::vector<double> sigma_of(rows.size(), 0.0);
  for (auto& [key, members] : groups) {
    if (key.first < 2) {
      std::stable_sort(members.begin(), members.end(), [&](int a, int b) {
        return usable.records[rows[a].index].d < usable.records[rows[b].index].d;
      });
    }
    const size_t run = key.first < 2 ? std::max<size_t>(kRun, 1) : members.size();
    for (size_t begin = 0; begin < members.size();) {
      size_t end = std::min(members.size(), begin + run);
      if (members.size() - end < run) end = members.size();
      std::vector<double> norms;
      for (size_t k = begin; k < end; ++k) {
        if (std::isfinite(rows[members[k]].r)) norms.push_back(rows[members[k]].r);
      }
      double s = 0;
      if (!norms.empty()) {
        std::nth_element(norms.begin(), norms.begin() + norms.size() / 2, norms.end());
        s = norms[norms.size() / 2] / (key.first == 2 ? kChi2Median : kChi3Median);
      }
      for (size_t k = begin; k < end; ++k) sigma_of[members[k]] = s;
      robust_sigma[key.first] = std::max(robust_sigma[key.first], s);
      begin = end;
    }
  }

  // The image points of each zoom, for the comparison below.
  std::map<int, std::vector<Eigen::Vector2d>> zoom_uv;
  std::map<int, std::vector<int>> zoom_rows;
  for (int k = 0; k < static_cast<int>(rows.size()); ++k) {
    if (rows[k].group != 2 || !std::isfinite(rows[k].r)) continue;
    const PixelObservation& p = usable.pixels[rows[k].index];
    zoom_uv[p.zoom].push_back(p.uv);
    zoom_rows[p.zoom].push_back(k);
  }
  std::map<int, ImageIndex> index;
  for (const auto& [zoom, uv] : zoom_uv) index.emplace(zoom, ImageIndex(uv, zoom_rows[zoom]));
  // The residual of an image point relative to the other photos' points
  // around it in the image: what a plane through their residuals over the
  // image (per coordinate, least squares) leaves at the point. A lens term
  // the model lacks moves every photo's points at one image position alike
  // (the residual is a field over the image), so that plane follows it, at
  // the edge of the image too; a detector's gross error is one corner off,
  // and a photo with a gross error of its own (a wrong reading, a wrong
  // zoom) moves its points where the other photos' stay. Its own residual
  // when fewer other points are there.
  auto unlike_others = [&](size_t k) {
    const PixelObservation& p = usable.pixels[rows[k].index];
    const ImageIndex& at = index.at(p.zoom);
    const std::vector<int> near = at.Nearest(p.uv, kNeighbours, [&](int i) {
      return usable.pixels[rows[at.Row(i)].index].shot == p.shot;
    });
    if (static_cast<int>(near.size()) < kNeighbours) return rows[k].r;
    Eigen::Matrix<double, kNeighbours, 3> a;
    Eigen::Matrix<double, kNeighbours, 2> b;
    const Eigen::Vector2d far = usable.pixels[rows[at.Row(near.back())].index].uv - p.uv;
    const double scale = far.norm() + 1e-12;
    for (int n = 0; n < kNeighbours; ++n) {
      const Row& other = rows[at.Row(near[n])];
      const Eigen::Vector2d d = (usable.pixels[other.index].uv - p.uv) / scale;
      a.row(n) << 1.0, d.x(), d.y();
      b.row(n) = other.delta.transpose();
    }
    // The plane's value at the point (its constant term); neighbours on a
    // line give the minimum-norm least-squares solution.
    const Eigen::Matrix<double, 3, 2> plane = a.completeOrthogonalDecomposition().solve(b);
    return (rows[k].delta - plane.row(0).transpose()).norm();
  };

  // 4. Rows beyond `reject` robust sigmas. An image point is gross only
  // when it is also that far from what the other photos show at its place
  // in the image (unlike_others): a model that lacks a lens term (a wide
  // lens fitted without rational_distortion) misses every photo's points
  // there alike, and those points are the data that show it.
  std::vector<ExcludedRow> flagged;
  const double apriori[3] = {options.sigma_edm_m, options.sigma_cam_m, options.sigma_pixel_px};
  for (size_t k = 0; k < rows.size(); ++k) {
    const Row& r = rows[k];
    // Noise-free data leave round-off (1e-14 m) with a robust sigma of
    // 1e-16: the sigma never goes below 1 % of the a-priori one.
    const double s = std::max(sigma_of[k], kSigmaFloor * apriori[r.group]);
    const double limit = robust.reject * s;
    if (std::isfinite(r.r) && !(r.r > limit && s > 0)) continue;
    const double apart = std::isfinite(r.r) && r.group == 2 ? unlike_others(k) : r.r;
    if (std::isfinite(r.r) && !(apart > limit)) continue;
    char buf[320];
    std::snprintf(buf, sizeof buf,
                  "residual %.4g %s after the robust fit, %.1f robust sigmas (sigma %.3g %s of "
                  "the %s like it; limit %.3g sigmas)",
                  r.r, kUnits[r.group], s > 0 ? r.r / s : 0.0, s, kUnits[r.group],
                  kGroupNames[r.group], robust.reject);
    std::string reason = buf;
    if (r.group == 2 && std::isfinite(r.r)) {
      std::snprintf(buf, sizeof buf,
                    "; %.4g px from what the %d nearest points of other photos show there", apart,
                    kNeighbours);
      reason += buf;
    }
    flagged.push_back(Excluded(usable, r, reason));
  }
  *rows_out = rows;
  return flagged;
}

}  // namespace

std::string GrossErrorOptions::Check() const {
  if (!(loss_scale > 0) || !std::isfinite(loss_scale))
    return "fit.gross_errors.loss_scale must be > 0 [sigmas]";
  if (!(reject > 1) || !std::isfinite(reject))
    return "fit.gross_errors.reject must be > 1 [sigmas]";
  if (!(max_fraction > 0 && max_fraction < 1))
    return "fit.gross_errors.max_fraction must be in (0, 1)";
  return "";
}

RobustFitResult FindGrossErrorsByFit(const Observations& obs, const FitOptions& options,
                                     const GrossErrorOptions& robust, InstrumentModel* model,
                                     bool suspect) {
  const std::string problem = robust.Check();
  if (!problem.empty()) throw std::invalid_argument(problem);
  RobustFitResult out;
  if (!robust.enabled) return out;
  const UsedRows used = SelectRows(obs, options, model->NumZooms(), UnknownZoom::kThrow);

  // 1. Rows the start cannot evaluate. Boards and points of unknown position
  // get their starting values first, as the refinement gives them (SPEC 7):
  // without them their rows have no position to be evaluated at.
  InstrumentModel seeded = *model;
  StartUnknowns(obs, used, FactsOf(obs, used), &seeded);
  const std::vector<Row> at_start = RowResiduals(obs, used, seeded);
  std::vector<ExcludedRow> unusable;
  for (const Row& r : at_start) {
    if (!std::isfinite(r.r)) {
      unusable.push_back(Excluded(obs, r,
                                  "the starting model cannot evaluate this row (a known point "
                                  "behind the camera or a pixel outside the distortion's "
                                  "trusted region)"));
    }
  }
  Keep(obs, at_start, unusable, robust, "cannot be evaluated at the start", &out);
  Observations usable = obs;
  std::vector<int> record_map, pixel_map;  // usable index -> obs index
  {
    std::vector<bool> drop_r(obs.records.size()), drop_p(obs.pixels.size());
    for (const ExcludedRow& e : out.gross) (e.pixel ? drop_p : drop_r)[e.index] = true;
    usable.records.clear();
    usable.pixels.clear();
    for (size_t i = 0; i < obs.records.size(); ++i) {
      if (drop_r[i]) continue;
      usable.records.push_back(obs.records[i]);
      record_map.push_back(static_cast<int>(i));
    }
    for (size_t i = 0; i < obs.pixels.size(); ++i) {
      if (drop_p[i]) continue;
      usable.pixels.push_back(obs.pixels[i]);
      pixel_map.push_back(static_cast<int>(i));
    }
  }

  // 2. The rows flagged at the least-squares solution (grouped residual
  // blocks, the cost of a plain refinement): when none is, the data hold no
  // gross error that a least-squares fit leaves visible, and the robust fit
  // is skipped (it costs a clean run several times a plain fit, one residual
  // block per row: calibrate_benchmark's BM_CalibrateClean against
  // BM_CalibrateCleanWithoutGrossErrorHandling). A
  // row whose error least squares hides completely (one that alone decides
  // a parameter) has no redundancy, and the robust fit could not tell it
  // either. Otherwise the Cauchy fit from the start decides.
  const InstrumentModel start = *model;
  std::vector<Row> rows;
  std::vector<ExcludedRow> flagged;
  bool least_squares_clean = false;
  if (!suspect && out.gross.empty()) try {
    FitOptions o = options;
    o.loss = RobustLoss::kNone;
    o.reestimate_sigmas = false;
    o.compute_covariance = false;
    o.max_iterations = std::min(options.max_iterations, kLeastSquaresIterations);
    Refine(usable, o, model);
    flagged = Flag(usable, options, robust, model, &rows, out.robust_sigma);
    least_squares_clean = flagged.empty();
  } catch (const std::exception&) {
    // A row least squares cannot take (non-finite cost): the robust fit decides.
  }
  if (!least_squares_clean) {
    *model = start;
    FitOptions o = options;
    o.loss = RobustLoss::kCauchy;
    o.loss_scale = robust.loss_scale;
    o.reestimate_sigmas = false;
    o.compute_covariance = false;
    o.max_iterations = std::min(options.max_iterations, RobustSearchIterations(usable));
    Refine(usable, o, model);
    for (double& s : out.robust_sigma) s = 0;
    flagged = Flag(usable, options, robust, model, &rows, out.robust_sigma);
  }
  const size_t before = out.gross.size();
  Keep(usable, rows, flagged, robust, "beyond the limit after the robust fit", &out);
  for (size_t k = before; k < out.gross.size(); ++k) {
    ExcludedRow& e = out.gross[k];
    e.index = e.pixel ? pixel_map[e.index] : record_map[e.index];
  }
  std::sort(out.gross.begin(), out.gross.end());
  return out;
}

}  // namespace rtscalib

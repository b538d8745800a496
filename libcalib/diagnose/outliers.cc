#include "libcalib/diagnose/outliers.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

namespace rtscalib {
namespace {

// Medians of chi2(1) and chi2(2): robust scale = median(e^2) / these.
constexpr double kMedianChi2Dof1 = 0.454936423119573;
constexpr double kMedianChi2Dof2 = 1.386294361119891;  // 2 ln 2
constexpr int kMinStratum = 10;

double Median(std::vector<double> v) {
  if (v.empty()) return 0;
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + mid, v.end());
  return v[mid];
}

struct Stratum {
  std::vector<double> along2, across2;  // records; pixels use across2 for |duv|^2
  double s_along2 = 0, s_across2 = 0;
};

}  // namespace

OutlierReport TestOutliers(const Observations& obs, const Linearization& lin, const Reduced& red,
                           const std::vector<ObservationResidual>& residuals, double significance,
                           int max_listed) {
  OutlierReport out;
  const Eigen::MatrixXd& q = red.base.basis();
  // Observations in the fit, with their mean leverage.
  struct Item {
    ObsGroup group;
    int index;
    double h = 0;
    int rows = 0;
  };
  std::map<std::pair<int, int>, Item> items;  // (pixel?, index)
  for (int i = 0; i < lin.NumRows(); ++i) {
    const ResidualRow& row = lin.rows[i];
    Item& it = items[{row.group == ObsGroup::kPixel ? 1 : 0, row.index}];
    it.group = row.group;
    it.index = row.index;
    it.h += q.cols() > 0 ? q.row(i).squaredNorm() : 0.0;
    if (lin.profiled_leverage.size() > i) it.h += lin.profiled_leverage[i];
    ++it.rows;
  }
  const int num_records = static_cast<int>(obs.records.size());
  auto residual_of = [&](const Item& it) -> const ObservationResidual& {
    return residuals[it.group == ObsGroup::kPixel ? num_records + it.index : it.index];
  };
  auto stratum_key = [&](const ObservationResidual& r, bool coarse) {
    const int bin = r.group == ObsGroup::kPixel || coarse
                        ? 0
                        : static_cast<int>(std::floor(2.0 * std::log2(r.d)));
    return std::make_tuple(static_cast<int>(r.group), r.group == ObsGroup::kEdm ? 0 : r.zoom, bin,
                           coarse);
  };
  std::map<std::tuple<int, int, int, bool>, Stratum> strata;
  for (const auto& [key, it] : items) {
    const ObservationResidual& r = residual_of(it);
    if (!r.valid) continue;
    for (bool coarse : {false, true}) {
      Stratum& s = strata[stratum_key(r, coarse)];
      if (r.group == ObsGroup::kPixel) {
        s.across2.push_back(r.delta.squaredNorm());
      } else {
        s.along2.push_back(r.along * r.along);
        s.across2.push_back(std::max(r.delta.squaredNorm() - r.along * r.along, 0.0));
      }
    }
  }
  for (auto& [key, s] : strata) {
    s.s_along2 = Median(s.along2) / kMedianChi2Dof1;
    s.s_across2 = Median(s.across2) / kMedianChi2Dof2;
  }

  std::vector<OutlierEntry> all;
  for (const auto& [key, it] : items) {
    const ObservationResidual& r = residual_of(it);
    if (!r.valid) continue;
    const Stratum* s = &strata[stratum_key(r, false)];
    if (static_cast<int>(s->across2.size()) < kMinStratum) s = &strata[stratum_key(r, true)];
    const double h = std::min(it.h / std::max(it.rows, 1), 0.99);
    double t = 0;
    int dof = 0;
    if (r.group == ObsGroup::kPixel) {
      if (s->s_across2 <= 0) continue;
      t = r.delta.squaredNorm() / s->s_across2;
      dof = 2;
    } else {
      if (s->s_along2 <= 0 || s->s_across2 <= 0) continue;
      const double across2 = std::max(r.delta.squaredNorm() - r.along * r.along, 0.0);
      t = r.along * r.along / s->s_along2 + across2 / s->s_across2;
      dof = 3;
    }
    t /= 1.0 - h;
    OutlierEntry e;
    e.group = it.group;
    e.index = it.index;
    e.p_value = ChiSquareSurvival(t, dof);
    e.w = t;  // the statistic until the listed entries get their w below
    e.size = r.size;
    all.push_back(e);
  }
  out.tested = static_cast<int>(all.size());
  if (all.empty()) return out;
  const double alpha = significance / out.tested;
  out.critical_w = NormalCritical(0.5 * alpha);
  for (OutlierEntry& e : all) {
    e.flagged = e.p_value < alpha;
    if (e.flagged) ++out.flagged;
  }
  std::sort(all.begin(), all.end(), [](const OutlierEntry& a, const OutlierEntry& b) {
    return a.p_value != b.p_value ? a.p_value < b.p_value : a.w > b.w;
  });
  const int listed = std::min<int>(static_cast<int>(all.size()), std::max(max_listed, out.flagged));
  for (int i = 0; i < listed && i < 200; ++i) {
    OutlierEntry e = all[i];
    const double t = e.w;
    e.w = e.p_value > 0 ? NormalCritical(0.5 * e.p_value) : std::sqrt(t);
    e.where = Where(obs, e.group, e.index);
    out.worst.push_back(e);
  }
  return out;
}

}  // namespace rtscalib

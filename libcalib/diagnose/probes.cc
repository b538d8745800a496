#include "libcalib/diagnose/probes.h"

#include <algorithm>
#include <limits>

namespace rtscalib {
namespace {

Eigen::MatrixXd Columns(const Eigen::MatrixXd& m, const ColumnBlock& b) {
  return m.middleCols(b.first, b.size);
}

// `projected` (a probe's columns after some projection) with the columns
// that kept less than kAbsorbed of their norm before the fit's projection
// (Reduced::column_norm of the block) set to zero.
Eigen::MatrixXd Prune(Eigen::MatrixXd projected, const Reduced& red, const ColumnBlock& b) {
  for (int j = 0; j < b.size; ++j) {
    if (!(projected.col(j).norm() >= kAbsorbed * red.column_norm[b.first + j])) {
      projected.col(j).setZero();
    }
  }
  return projected;
}

}  // namespace

ProbeAnalysis AnalyseProbes(const Linearization& lin, const Reduced& red,
                            const std::vector<const ColumnBlock*>& catalogue, double significance,
                            int max_terms) {
  ProbeAnalysis out;
  for (const ColumnBlock& b : lin.blocks) {
    if (!b.is_probe) continue;
    ProbeResult r;
    r.block = &b;
    out.probes.push_back(r);
  }
  out.tests = static_cast<int>(out.probes.size());
  if (out.probes.empty()) return out;
  out.level = significance / out.tests;
  const int n = lin.NumRows();
  const int g = lin.num_clusters;
  const int dof_base = red.base.rank();

  // 1. Against the fitted model alone.
  for (ProbeResult& r : out.probes) {
    r.raw = TestColumns(red.r, Prune(Columns(red.extra, *r.block), red, *r.block), red.cluster, g,
                        dof_base);
    r.raw_significant = r.raw.rank > 0 && r.raw.p_value < out.level;
  }

  // 2. On top of every catalogue effect the data see.
  Projector cat(n);
  {
    int cols = 0;
    for (const ColumnBlock* b : catalogue) cols += b->size;
    Eigen::MatrixXd c(n, cols);
    int k = 0;
    for (const ColumnBlock* b : catalogue) {
      c.middleCols(k, b->size) = Columns(red.extra, *b);
      k += b->size;
    }
    cat.Add(c);
  }
  const Eigen::VectorXd y = cat.Apply(red.r);
  std::vector<Eigen::MatrixXd> t_cat(out.probes.size());
  for (size_t j = 0; j < out.probes.size(); ++j) {
    const ColumnBlock& b = *out.probes[j].block;
    t_cat[j] = Prune(cat.Apply(Columns(red.extra, b)), red, b);
  }
  std::vector<int> selected;
  Projector sel(n);
  for (int iter = 0; iter < max_terms; ++iter) {
    const Eigen::VectorXd ys = sel.Apply(y);
    int best = -1;
    double best_p = 1.0, best_wald = 0.0;
    for (size_t j = 0; j < out.probes.size(); ++j) {
      if (std::find(selected.begin(), selected.end(), static_cast<int>(j)) != selected.end())
        continue;
      const ColumnTest t =
          TestColumns(ys, Prune(sel.Apply(t_cat[j]), red, *out.probes[j].block), red.cluster, g,
                      dof_base + cat.rank() + sel.rank());
      if (t.rank == 0) continue;
      if (t.p_value < best_p || (t.p_value == best_p && t.wald > best_wald)) {
        best = static_cast<int>(j);
        best_p = t.p_value;
        best_wald = t.wald;
      }
    }
    if (best < 0 || best_p >= out.level) break;
    selected.push_back(best);
    sel.Add(t_cat[best]);
  }
  // Joint estimates of the selected probes.
  for (int s : selected) {
    Projector others(n);
    for (int o : selected) {
      if (o != s) others.Add(t_cat[o]);
    }
    ProbeResult& r = out.probes[s];
    r.selected = true;
    r.joint = TestColumns(others.Apply(y), Prune(others.Apply(t_cat[s]), red, *r.block),
                          red.cluster, g, dof_base + cat.rank() + others.rank());
  }
  out.selected = selected;

  // 3a. Significant on top of the catalogue but not selected: the selected
  // probe that removes most of it holds the same structure.
  for (size_t j = 0; j < out.probes.size(); ++j) {
    ProbeResult& r = out.probes[j];
    if (!r.raw_significant || r.selected) continue;
    const ColumnTest on_catalogue = TestColumns(y, t_cat[j], red.cluster, g, dof_base + cat.rank());
    if (!(on_catalogue.rank > 0 && on_catalogue.p_value < out.level)) continue;
    double best = std::numeric_limits<double>::infinity();
    for (int s : selected) {
      Projector ps(n);
      ps.Add(t_cat[s]);
      const ColumnTest t = TestColumns(ps.Apply(y), Prune(ps.Apply(t_cat[j]), red, *r.block),
                                       red.cluster, g, dof_base + cat.rank() + ps.rank());
      if (t.wald < best) {
        best = t.wald;
        r.same_as = out.probes[s].block->name;
      }
    }
    if (r.same_as.empty()) r.same_as = "the structure selected above";
  }

  // 3. What the catalogue explains: per catalogue effect, its projector and
  // the residual without it, built once.
  bool any = false;
  for (const ProbeResult& r : out.probes) {
    any = any || (r.raw_significant && !r.selected && r.same_as.empty());
  }
  if (!any) return out;
  std::vector<Projector> without;
  std::vector<Eigen::VectorXd> y_without;
  for (const ColumnBlock* b : catalogue) {
    without.emplace_back(n);
    without.back().Add(Columns(red.extra, *b));
    y_without.push_back(without.back().Apply(red.r));
  }
  for (ProbeResult& r : out.probes) {
    if (!r.raw_significant || r.selected || !r.same_as.empty()) continue;
    double best = std::numeric_limits<double>::infinity();
    for (size_t c = 0; c < catalogue.size(); ++c) {
      const ColumnTest t = TestColumns(
          y_without[c], Prune(without[c].Apply(Columns(red.extra, *r.block)), red, *r.block),
          red.cluster, g, dof_base + without[c].rank());
      if (t.wald < best) {
        best = t.wald;
        r.explained_by = catalogue[c]->name;
      }
    }
  }
  return out;
}

}  // namespace rtscalib

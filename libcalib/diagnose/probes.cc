#include "libcalib/diagnose/probes.h"

#include <algorithm>
#include <limits>

namespace rtscalib {
namespace {

Eigen::MatrixXd::ConstColsBlockXpr Columns(const Eigen::MatrixXd& m, const ColumnBlock& b) {
  return m.middleCols(b.first, b.size);
}

// Column j of block b, after some projection, kept less than kAbsorbed of
// its norm before the fit's projection (Reduced::column_norm of the block).
bool Absorbed(const Eigen::Ref<const Eigen::MatrixXd>& projected, int j, const Reduced& red,
              const ColumnBlock& b) {
  return !(projected.col(j).norm() >= kAbsorbed * red.column_norm[b.first + j]);
}

// Sets the absorbed columns of `projected` (a probe's columns after some
// projection) to zero.
void ZeroAbsorbed(Eigen::Ref<Eigen::MatrixXd> projected, const Reduced& red, const ColumnBlock& b) {
  for (int j = 0; j < b.size; ++j) {
    if (Absorbed(projected, j, red, b)) projected.col(j).setZero();
  }
}

// TestColumns of a probe's columns `t` (after some projection) without its
// absorbed columns; `t` is copied only when one of them is absorbed.
ColumnTest TestProbe(const Eigen::Ref<const Eigen::VectorXd>& y,
                     const Eigen::Ref<const Eigen::MatrixXd>& t, const Reduced& red,
                     const ColumnBlock& b, int num_clusters, int dof_used) {
  for (int j = 0; j < b.size; ++j) {
    if (Absorbed(t, j, red, b)) {
      Eigen::MatrixXd pruned = t;
      ZeroAbsorbed(pruned, red, b);
      return TestColumns(y, pruned, red.cluster, num_clusters, dof_used);
    }
  }
  return TestColumns(y, t, red.cluster, num_clusters, dof_used);
}

// Probes' columns side by side in one matrix, so that one product over a
// projector's n x rank basis projects them all (what costs when each probe
// has a few columns); probe j holds columns [offset[j], offset[j + 1]).
struct SideBySide {
  Eigen::MatrixXd all;
  std::vector<Eigen::Index> offset{0};

  SideBySide(const Eigen::MatrixXd& extra, const std::vector<const ColumnBlock*>& blocks) {
    for (const ColumnBlock* b : blocks) offset.push_back(offset.back() + b->size);
    all.resize(extra.rows(), offset.back());
    for (size_t j = 0; j < blocks.size(); ++j) Block(j) = Columns(extra, *blocks[j]);
  }
  Eigen::MatrixXd::ColsBlockXpr Block(size_t j) {
    return all.middleCols(offset[j], offset[j + 1] - offset[j]);
  }
};

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
  const int dof_base = red.Rank();

  // 1. Against the fitted model alone.
  for (ProbeResult& r : out.probes) {
    r.raw = TestProbe(red.r, Columns(red.extra, *r.block), red, *r.block, g, dof_base);
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
  // Every probe's columns through the catalogue's projector, absorbed
  // columns set to zero.
  std::vector<const ColumnBlock*> probe_blocks;
  for (const ProbeResult& r : out.probes) probe_blocks.push_back(r.block);
  SideBySide cat_cols(red.extra, probe_blocks);
  cat.Project(cat_cols.all);
  auto t_cat = [&](size_t j) { return cat_cols.Block(j); };
  for (size_t j = 0; j < out.probes.size(); ++j) ZeroAbsorbed(t_cat(j), red, *out.probes[j].block);
  // y and every probe's columns through the selected probes' projector,
  // brought up to date by each selection's new directions only
  // (Projector::Project).
  SideBySide t_sel = cat_cols;
  Eigen::VectorXd ys = y;
  std::vector<int> selected;
  Projector sel(n);
  // sel after each step: first[i] spans the first i selected probes.
  std::vector<Projector> first;
  for (int iter = 0; iter < max_terms; ++iter) {
    int best = -1;
    double best_p = 1.0, best_wald = 0.0;
    for (size_t j = 0; j < out.probes.size(); ++j) {
      if (std::find(selected.begin(), selected.end(), static_cast<int>(j)) != selected.end())
        continue;
      const ColumnTest t = TestProbe(ys, t_sel.Block(j), red, *out.probes[j].block, g,
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
    const int known = sel.rank();
    first.push_back(sel);
    sel.Add(t_cat(best));
    sel.Project(ys, known);
    sel.Project(t_sel.all, known);
  }
  // Joint estimates of the selected probes.
  // The others of selected[i] are added in selection order, as the
  // selection added them: the first i are first[i], so only the later ones
  // are added to its copy (half the additions of building each anew).
  for (size_t i = 0; i < selected.size(); ++i) {
    const int s = selected[i];
    Projector others = first[i];
    for (size_t o = i + 1; o < selected.size(); ++o) others.Add(t_cat(selected[o]));
    ProbeResult& r = out.probes[s];
    r.selected = true;
    r.joint = TestProbe(others.Apply(y), others.Apply(t_cat(s)), red, *r.block, g,
                        dof_base + cat.rank() + others.rank());
  }
  out.selected = selected;

  // 3a. Significant on top of the catalogue but not selected: the selected
  // probe that removes most of it holds the same structure. Each selected
  // probe's projector and y through it are the same for every such probe:
  // built once, when the first one needs them.
  std::vector<Projector> alone;
  std::vector<Eigen::VectorXd> y_alone;
  for (size_t j = 0; j < out.probes.size(); ++j) {
    ProbeResult& r = out.probes[j];
    if (!r.raw_significant || r.selected) continue;
    const ColumnTest on_catalogue = TestColumns(y, t_cat(j), red.cluster, g, dof_base + cat.rank());
    if (!(on_catalogue.rank > 0 && on_catalogue.p_value < out.level)) continue;
    double best = std::numeric_limits<double>::infinity();
    if (alone.empty()) {
      for (int s : selected) {
        alone.emplace_back(n);
        alone.back().Add(t_cat(s));
        y_alone.push_back(alone.back().Apply(y));
      }
    }
    for (size_t i = 0; i < selected.size(); ++i) {
      const Projector& ps = alone[i];
      const ColumnTest t = TestProbe(y_alone[i], ps.Apply(t_cat(j)), red, *r.block, g,
                                     dof_base + cat.rank() + ps.rank());
      if (t.wald < best) {
        best = t.wald;
        r.same_as = out.probes[selected[i]].block->name;
      }
    }
    if (r.same_as.empty()) r.same_as = "the structure selected above";
  }

  // 3. What the catalogue explains, for the structure significant alone and
  // held by nothing selected: per catalogue effect, its projector, the
  // residual without it and every such probe's columns through it.
  std::vector<ProbeResult*> open;
  std::vector<const ColumnBlock*> open_blocks;
  for (ProbeResult& r : out.probes) {
    if (!r.raw_significant || r.selected || !r.same_as.empty()) continue;
    open.push_back(&r);
    open_blocks.push_back(r.block);
  }
  if (open.empty()) return out;
  const SideBySide open_cols(red.extra, open_blocks);
  std::vector<double> best(open.size(), std::numeric_limits<double>::infinity());
  for (const ColumnBlock* b : catalogue) {
    Projector without(n);
    without.Add(Columns(red.extra, *b));
    const Eigen::VectorXd y_without = without.Apply(red.r);
    SideBySide t = open_cols;
    without.Project(t.all);
    for (size_t i = 0; i < open.size(); ++i) {
      const ColumnTest test =
          TestProbe(y_without, t.Block(i), red, *open[i]->block, g, dof_base + without.rank());
      if (test.wald < best[i]) {
        best[i] = test.wald;
        open[i]->explained_by = b->name;
      }
    }
  }
  return out;
}

}  // namespace rtscalib

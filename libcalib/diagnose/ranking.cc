#include "libcalib/diagnose/ranking.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>

#include "libcalib/eval/error_measures.h"
#include "libcalib/fit/unknowns.h"

namespace rtscalib {
namespace {

void Finish(GroupRms* g) {
  g->edm_m = g->edm_n > 0 ? std::sqrt(g->edm_ss / g->edm_n) : 0.0;
  g->cam_m = g->cam_n > 0 ? std::sqrt(g->cam_ss / g->cam_n) : 0.0;
  g->records_m =
      g->edm_n + g->cam_n > 0 ? std::sqrt((g->edm_ss + g->cam_ss) / (g->edm_n + g->cam_n)) : 0.0;
  g->pixels_px = g->pixels_n > 0 ? std::sqrt(g->pixels_ss / g->pixels_n) : 0.0;
}

std::array<double, 4> Cov2(const Eigen::MatrixXd& c) {
  std::array<double, 4> out{};
  if (c.rows() >= 1) out[0] = c(0, 0);
  if (c.rows() >= 2) out = {c(0, 0), c(0, 1), c(1, 0), c(1, 1)};
  return out;
}

// sum_g n_g log(RSS_g(after) / RSS_g(before)) over the observation groups:
// -2 x the change of the Gaussian log-likelihood with one free variance per
// group (so a group whose noise estimate the missing effect inflated is not
// down-weighted in the comparison).
double GroupLogRatio(const Linearization& lin, const Eigen::VectorXd& before,
                     const Eigen::VectorXd& after) {
  double b[3] = {0, 0, 0}, a[3] = {0, 0, 0};
  int rows[3] = {0, 0, 0};
  for (int i = 0; i < lin.NumRows(); ++i) {
    const int g = static_cast<int>(lin.rows[i].group);
    b[g] += before[i] * before[i];
    a[g] += after[i] * after[i];
    ++rows[g];
  }
  double sum = 0;
  for (int g = 0; g < 3; ++g) {
    if (rows[g] > 0 && b[g] > 0) sum += rows[g] * std::log(std::max(a[g], 1e-300) / b[g]);
  }
  return sum;
}

}  // namespace

double GroupRms::WhitenedRss(const double sigma[3]) const {
  return edm_ss / (sigma[0] * sigma[0]) + cam_ss / (sigma[1] * sigma[1]) +
         pixels_ss / (sigma[2] * sigma[2]);
}

double GroupRms::Bic(int num_parameters) const {
  const double rows[3] = {3.0 * edm_n, 3.0 * cam_n, 2.0 * pixels_n};
  const double ss[3] = {edm_ss, cam_ss, pixels_ss};
  double n = 0, bic = 0;
  for (int g = 0; g < 3; ++g) {
    if (rows[g] == 0) continue;
    n += rows[g];
    bic += rows[g] * std::log(std::max(ss[g], 1e-300) / rows[g]);
  }
  return n > 0 ? bic + num_parameters * std::log(n) : 0.0;
}

GroupRms RmsOfWhitened(const Linearization& lin, const Eigen::VectorXd& r) {
  GroupRms g;
  for (int i = 0; i < lin.NumRows(); ++i) {
    const int k = static_cast<int>(lin.rows[i].group);
    const double v = r[i] * lin.sigma[k];
    (k == 0 ? g.edm_ss : k == 1 ? g.cam_ss : g.pixels_ss) += v * v;
  }
  g.edm_n = lin.num_observations[0];
  g.cam_n = lin.num_observations[1];
  g.pixels_n = lin.num_observations[2];
  Finish(&g);
  return g;
}

GroupRms RmsOfModel(const Observations& observed, const InstrumentModel& model,
                    const FitOptions& fit) {
  const Observations obs = WithEstimates(observed, model);
  GroupRms g;
  for (const RecordResidual& r : RecordResiduals(model, obs.records)) {
    const Record& rec = obs.records[r.index];
    if (!r.valid || fit.critical_region.Contains(rec.theta)) continue;
    if (rec.tool == Tool::kEdm) {
      g.edm_ss += r.distance * r.distance;
      ++g.edm_n;
    } else {
      g.cam_ss += r.distance * r.distance;
      ++g.cam_n;
    }
  }
  for (const PixelResidual& p : PixelResiduals(model, obs.pixels)) {
    if (!p.valid ||
        fit.critical_region.Contains(obs.pixels[p.index].theta))
      continue;
    g.pixels_ss += p.delta.squaredNorm();
    ++g.pixels_n;
  }
  Finish(&g);
  return g;
}

GroupRms RmsLess(const Linearization& lin, const GroupRms& before,
                 const Eigen::VectorXd& explained) {
  GroupRms g = before;
  for (int i = 0; i < lin.NumRows(); ++i) {
    const int k = static_cast<int>(lin.rows[i].group);
    const double v = explained[i] * lin.sigma[k];
    (k == 0 ? g.edm_ss : k == 1 ? g.cam_ss : g.pixels_ss) -= v * v;
  }
  g.edm_ss = std::max(g.edm_ss, 0.0);
  g.cam_ss = std::max(g.cam_ss, 0.0);
  g.pixels_ss = std::max(g.pixels_ss, 0.0);
  Finish(&g);
  return g;
}

double RelativeGain(const GroupRms& before, const GroupRms& after) {
  double gain = 0;
  auto fall = [&gain](int n, double b, double a) {
    if (n > 0 && b > 0) gain = std::max(gain, (b - a) / b);
  };
  fall(before.edm_n, before.edm_m, after.edm_m);
  fall(before.cam_n, before.cam_m, after.cam_m);
  fall(before.pixels_n, before.pixels_px, after.pixels_px);
  return gain;
}

std::string ConfigLine(const InstrumentModel& model, Effect e) {
  std::vector<std::string> names = model.effects.Names();
  names.push_back(Info(e).name);
  std::string line = "model.effects: [";
  for (size_t i = 0; i < names.size(); ++i) line += (i ? ", " : "") + names[i];
  return line + "]";
}

namespace {

// The candidate effects' column blocks of the linearisation.
std::vector<const ColumnBlock*> EffectBlocks(const Linearization& lin) {
  std::vector<const ColumnBlock*> effects;
  for (const ColumnBlock& b : lin.blocks) {
    if (b.is_effect) effects.push_back(&b);
  }
  return effects;
}

// Whether the data see the effect at all (any column not identically zero).
bool Observable(const ColumnBlock& b, const Reduced& red) {
  for (int j = b.first; j < b.first + b.size; ++j) {
    if (red.column_norm[j] > 0) return true;
  }
  return false;
}

// The largest fraction of a column the model's parameters cannot absorb.
double Kept(const ColumnBlock& b, const Reduced& red) {
  double k = 0;
  for (int j = b.first; j < b.first + b.size; ++j) k = std::max(k, red.kept_fraction[j]);
  return k;
}

// Normal matrices of [model parameters, candidate columns], for the
// correlations of an effect with the model and for what absorbs a redundant one.
struct Normals {
  Eigen::MatrixXd nbb, nbx, nxx, nbb_inv;
  int pb = 0;
  Normals(const Linearization& lin, const std::vector<const ColumnBlock*>& effects) {
    int num_effect_cols = 0;
    for (const ColumnBlock* b : effects)
      num_effect_cols = std::max(num_effect_cols, b->first + b->size);
    const auto jx = lin.extra.leftCols(num_effect_cols);  // a view: no copy of n rows
    nbb = lin.base.transpose() * lin.base;
    nbx = lin.base.transpose() * jx;
    nxx = jx.transpose() * jx;
    pb = static_cast<int>(nbb.rows());
    nbb_inv = PseudoInverseSpd(nbb, 1e-14);
  }
};

// Which model parameters absorb a redundant effect: the largest terms of its
// columns' least-squares expansion in the model's columns.
std::string AbsorbedBy(const ColumnBlock& b, const Normals& n, const Linearization& lin,
                       const Reduced& red) {
  const Eigen::MatrixXd coef = n.nbb_inv * n.nbx.middleCols(b.first, b.size);
  std::vector<std::pair<double, int>> share;
  for (int j = 0; j < n.pb; ++j) {
    double s2 = 0;
    for (int k = 0; k < b.size; ++k) {
      const double norm = red.column_norm[b.first + k];
      if (norm > 0) s2 = std::max(s2, std::abs(coef(j, k)) * std::sqrt(n.nbb(j, j)) / norm);
    }
    share.push_back({s2, j});
  }
  std::sort(share.rbegin(), share.rend());
  std::string names;
  for (size_t i = 0; i < share.size() && i < 3 && share[i].first > 0.1; ++i) {
    names += (i ? ", " : "") + lin.base_names[share[i].second];
  }
  return names.empty() ? std::string("several parameters") : names;
}

// The model parameter most correlated with the effect once it is added
// (covariance of the augmented normal matrix): sets r->rho, r->correlated_with.
void StrongestCorrelation(const ColumnBlock& b, const Normals& n, const Linearization& lin,
                          RankedEffect* r) {
  const int k = b.size, pb = n.pb;
  Eigen::MatrixXd aug(pb + k, pb + k);
  aug.topLeftCorner(pb, pb) = n.nbb;
  aug.topRightCorner(pb, k) = n.nbx.middleCols(b.first, k);
  aug.bottomLeftCorner(k, pb) = n.nbx.middleCols(b.first, k).transpose();
  aug.bottomRightCorner(k, k) = n.nxx.block(b.first, b.first, k, k);
  const Eigen::MatrixXd c = PseudoInverseSpd(aug, 1e-14);
  for (int i = pb; i < pb + k; ++i) {
    for (int j = 0; j < pb; ++j) {
      const double d = std::sqrt(c(i, i) * c(j, j));
      if (!(d > 0)) continue;
      const double rho = c(i, j) / d;
      if (std::abs(rho) > std::abs(r->rho)) {
        r->rho = rho;
        r->correlated_with = lin.base_names[j];
      }
    }
  }
  // The parameters projected out cluster by cluster (each photo's own board
  // pose, Linearization::num_profiled) are no columns of base: a column's
  // multiple correlation with them, sqrt(1 - (|after| / |before|)^2).
  if (lin.extra_norm.size() == lin.extra.cols()) {
    for (int j = b.first; j < b.first + k; ++j) {
      const double before = lin.extra_norm[j];
      if (!(before > 0)) continue;
      const double kept = std::min(1.0, lin.extra.col(j).norm() / before);
      const double multiple = std::sqrt(std::max(0.0, 1.0 - kept * kept));
      if (multiple > std::abs(r->rho)) {
        r->rho = multiple;
        r->correlated_with = "the boards' poses (each photo's own; multiple correlation)";
      }
    }
  }
}

// What the ranking needs of every effect, computed once.
struct Context {
  const RankingInput& in;
  const RankingOptions& o;
  const Linearization& lin;
  const Reduced& red;
  const Projector& nu;
  Normals normals;
  Eigen::VectorXd y;  // residual with the unexplained harmonics projected out
  int dof = 0;
  double log_n = 0;
  double level = 0;
  GroupRms current;
};

// One candidate effect scored: the test conditional on the unexplained
// harmonics (delta BIC, Wald, p), its linear estimate in report units, the
// rms after, its strongest correlation; or why it cannot be tested.
RankedEffect ScoreEffect(const ColumnBlock& b, const Context& cx) {
  const Linearization& lin = cx.lin;
  const Reduced& red = cx.red;
  RankedEffect r;
  r.effect = b.effect;
  r.name = b.name;
  r.num_params = b.size;
  r.before = cx.current;
  r.after = cx.current;
  r.after_source = "linearised";
  r.config_line = ConfigLine(*cx.in.model, b.effect);
  r.needs = WhatWouldHelp(b.effect, *cx.in.coverage, *cx.in.model);
  r.observable = Observable(b, red);
  r.redundant = r.observable && Kept(b, red) < cx.o.redundant_fraction;
  if (!r.observable || r.redundant) {
    r.identifiable = false;
    r.delta_bic = r.num_params * cx.log_n;
    r.note = !r.observable ? "the data do not see this effect at all"
                           : "the model's parameters absorb this effect (to first order): " +
                                 AbsorbedBy(b, cx.normals, lin, red) +
                                 "; it cannot be told apart from them with these data";
    return r;
  }
  const Eigen::MatrixXd t_e = red.extra.middleCols(b.first, b.size);
  const ColumnTest t = TestColumns(cx.y, cx.nu.Apply(t_e), red.cluster, lin.num_clusters, cx.dof);
  r.num_params = t.rank;
  r.delta_rss = t.delta_rss;
  r.delta_bic = GroupLogRatio(lin, cx.y, cx.y - t.fitted) + t.rank * cx.log_n;
  r.wald = t.wald;
  r.p_value = t.p_value;
  const ColumnTest plain = TestColumns(red.r, t_e, red.cluster, lin.num_clusters, red.Rank());
  // The fall the effect's columns take out of each group's sum of squares,
  // from the fit's own residuals: red.r also carries the step the model's own
  // columns would take with the linearisation's group weights (the fit
  // weighs by zoom and photo), which no added effect buys.
  r.after = RmsLess(lin, cx.current, plain.fitted);
  r.linear_after = r.after;

  // r regressed on its own derivative gives minus the Gauss-Newton step.
  if (IsKinematic(b.effect)) {
    for (int k = 0; k < b.size && k < 2; ++k) r.si[k] = -t.beta[k];
    r.si_cov = Cov2(t.cov);
    r.value = ToReportUnits(b.effect, r.si, r.si_cov);
  } else if (b.effect == Effect::kFocus) {
    // Linearised at zero (WithCandidates): the estimate is minus the step.
    for (int k = 0; k < b.size; ++k) {
      const auto [zoom, index] = b.distortion[k];
      r.focus.push_back({zoom, kFocusParamNames[index], index, -t.beta[k],
                         std::sqrt(std::max(t.cov(k, k), 0.0))});
    }
  } else if (IsBoardEffect(b.effect)) {
    // Linearised at zero (WithCandidates), likewise.
    for (int k = 0; k < b.size; ++k) {
      const auto [first_id, index] = b.boards[k];
      r.board_warp.push_back({first_id, Info(b.effect).param_names[index], index, -t.beta[k],
                              std::sqrt(std::max(t.cov(k, k), 0.0))});
    }
  } else if (IsDistortion(b.effect)) {
    for (int k = 0; k < b.size; ++k) {
      const auto [zoom, index] = b.distortion[k];
      r.distortion.push_back({zoom, kDistortionCoefficientNames[index], index,
                              cx.in.model->cams[zoom].distortion[index] - t.beta[k],
                              std::sqrt(std::max(t.cov(k, k), 0.0))});
    }
  }

  StrongestCorrelation(b, cx.normals, lin, &r);
  r.identifiable = std::abs(r.rho) <= cx.o.identifiable_rho;
  // Statistical significance alone is not enough on exact data, where the
  // fitted noise is round-off and a 1e-11 arcsec term is "significant":
  // the effect must also lower the rms by more than the numerical floor.
  const double floor = r.before.MainUnit() == std::string("px") ? kPixelFloor : kPointFloorM;
  r.significant = t.rank > 0 && t.p_value < cx.level && r.delta_bic < 0 &&
                  r.before.Main() - r.after.Main() > floor;
  r.gain = RelativeGain(r.before, r.after);
  if (!r.identifiable) {
    char buf[160];
    std::snprintf(buf, sizeof(buf), "strongly correlated with %s (rho %+.3f)",
                  r.correlated_with.c_str(), r.rho);
    r.note = buf;
  }
  return r;
}

// Terms the kinematics contain (dh): redundant, with their value read off
// the model (equivalents.h) instead of a test.
RankedEffect ContainedEntry(Effect e, const Context& cx) {
  RankedEffect r;
  r.effect = e;
  r.name = Info(e).name;
  r.num_params = Info(e).num_params;
  r.before = r.after = cx.current;
  r.after_source = "model";
  r.redundant = true;
  r.identifiable = false;
  r.delta_bic = r.num_params * cx.log_n;
  r.config_line = ConfigLine(*cx.in.model, e);
  r.note = "contained in the dh model (links and tools); not fitted twice";
  r.needs = {"model.kinematics: spherical, to estimate it as a term of its own"};
  if (cx.in.equivalents && cx.in.equivalents->valid) {
    r.has_equivalent = true;
    r.si = cx.in.equivalents->value[static_cast<int>(e)];
    r.equivalent = ToReportUnits(e, r.si, {0, 0, 0, 0});
  }
  return r;
}

const ColumnBlock* BlockOf(Effect e, const std::vector<const ColumnBlock*>& effects) {
  for (const ColumnBlock* b : effects) {
    if (b->effect == e) return b;
  }
  return nullptr;
}

// Aliases among the best three significant effects: another significant
// effect, added first, leaves this one insignificant (the data cannot tell
// them apart).
void FindAliases(const std::vector<const ColumnBlock*>& effects, const Context& cx, Ranking* out) {
  const Reduced& red = cx.red;
  size_t best = 0;  // the best three significant effects
  while (best < out->entries.size() && best < 3 && out->entries[best].significant) ++best;
  // Effect by effect added first: its projector (the nuisance and its
  // columns) and the residual through it, built when first needed, serve
  // each of the best three.
  for (const RankedEffect& o : out->entries) {
    if (!o.significant) continue;
    std::optional<Projector> p;
    Eigen::VectorXd y;
    for (size_t i = 0; i < best; ++i) {
      RankedEffect& r = out->entries[i];
      if (o.effect == r.effect) continue;
      if (!p) {
        const ColumnBlock* bo = BlockOf(o.effect, effects);
        p = cx.nu;
        p->Add(red.extra.middleCols(bo->first, bo->size));
        y = p->Apply(red.r);
      }
      const ColumnBlock* be = BlockOf(r.effect, effects);
      const ColumnTest t =
          TestColumns(y, p->Apply(red.extra.middleCols(be->first, be->size)), red.cluster,
                      cx.lin.num_clusters, red.Rank() + p->rank());
      if (!(t.rank > 0 && t.p_value < out->level)) r.aliases.push_back(o.name);
    }
  }
}

// Significant effects that stay significant once the best one is added
// (what the next rungs of the ladder will likely add).
void AlsoAfterBest(const std::vector<const ColumnBlock*>& effects, const Context& cx,
                   Ranking* out) {
  if (out->entries.empty() || !out->entries.front().recommended) return;
  // After a refit far from the first order (a fall the linear step did not
  // predict to within a tenth), the linear residual is not where the next
  // rung starts: a new diagnosis of the refitted model tells.
  const RankedEffect& first = out->entries.front();
  if (first.after_source == "refined" &&
      std::abs(first.after.Main() - first.linear_after.Main()) >
          0.1 * std::abs(first.before.Main() - first.after.Main())) {
    return;
  }
  const Reduced& red = cx.red;
  const ColumnBlock* best = BlockOf(out->entries.front().effect, effects);
  Projector p = cx.nu;
  p.Add(red.extra.middleCols(best->first, best->size));
  const Eigen::VectorXd yb = p.Apply(red.r);
  const GroupRms after_best = RmsOfWhitened(cx.lin, yb);
  out->after_best_tested = true;
  for (size_t i = 1; i < out->entries.size(); ++i) {
    const RankedEffect& o = out->entries[i];
    if (!o.significant) continue;
    const ColumnBlock* bo = BlockOf(o.effect, effects);
    const ColumnTest t = TestColumns(yb, p.Apply(red.extra.middleCols(bo->first, bo->size)),
                                     red.cluster, cx.lin.num_clusters, red.Rank() + p.rank());
    const double gain = RelativeGain(after_best, RmsLess(cx.lin, after_best, t.fitted));
    if (t.rank > 0 && t.p_value < out->level && gain >= cx.o.min_gain) {
      out->also_after_best.push_back(o.name);
    }
  }
}

// The linear prediction is first order: the leading `refine_top`
// significant effects are refitted, and the refit's rms, values, delta BIC
// and gain replace the linear ones: the fall the user will see when adding
// the effect. The refit is the calibration's Refine from the fitted model
// with the effect added at zero (every effect is linear in its parameters
// there, effects.h, so its first step is the linear estimate with every
// other parameter moved with it; the linear estimate alone, without those
// compensating moves, can start a strongly correlated effect far off), the
// estimated boards and points free, the linearisation's weights held. An
// effect whose linear gain is below a quarter of min_gain is not refitted:
// a step that small is first order to within its own square. A refit that
// fails keeps the linear prediction (after_source).
void ConfirmByRefinement(const Context& cx, Ranking* out) {
  const RankingInput& in = cx.in;
  const Linearization& lin = cx.lin;
  // The fitted model's own rms over the same rows as a refit's, so that a
  // refit's delta BIC compares like with like.
  std::optional<GroupRms> before;
  int leading = 0;
  for (RankedEffect& r : out->entries) {
    if (leading >= cx.o.refine_top || !r.significant) break;
    ++leading;
    if (r.gain < 0.25 * cx.o.min_gain) continue;
    InstrumentModel m = *in.model;
    m.effects.Add(r.effect);
    m.sigmas = {};
    FitOptions fo = in.fit;
    fo.reestimate_sigmas = false;  // the same weights as the linearisation
    fo.sigma_edm_m = lin.sigma[0];
    fo.sigma_cam_m = lin.sigma[1];
    fo.sigma_pixel_px = lin.sigma[2];
    // The values' sigmas stay the linear test's (robust) ones: the refit's
    // covariance would cost more than the refit.
    fo.compute_covariance = false;
    fo.max_iterations = std::min(fo.max_iterations, kRefitIterations);
    fo.verbose = false;
    FitSummary fit;
    try {
      fit = Refine(*in.obs, fo, &m);
    } catch (const std::exception&) {
      continue;
    }
    if (!before) before = RmsOfModel(*in.obs, *in.model, in.fit);
    const GroupRms after = RmsOfModel(*in.obs, m, in.fit);
    r.after = after;
    r.after_source = "refined";
    if (!fit.converged) {
      r.note += std::string(r.note.empty() ? "" : "; ") + "the refit stopped after " +
                std::to_string(fit.iterations) +
                " iterations before converging: the fall is at least this";
    }
    r.delta_bic = after.Bic(r.num_params) - before->Bic(0);
    r.significant = r.delta_bic < 0;  // the Wald test held; the refit must still pay its way
    r.gain = RelativeGain(*before, after);
    if (IsKinematic(r.effect)) {
      r.si = m.EffectValue(r.effect);
      r.value = ToReportUnits(r.effect, r.si, r.si_cov);
    } else if (r.effect == Effect::kFocus) {
      for (FocusValue& f : r.focus) f.value = m.cams[f.zoom].focus[f.index];
    } else if (IsBoardEffect(r.effect)) {
      for (WarpValue& w : r.board_warp) {
        if (const BoardWarp* fitted = m.WarpOf(w.first_id)) w.value = fitted->w[w.index];
      }
    } else if (IsDistortion(r.effect)) {
      for (DistortionValue& d : r.distortion) d.value = m.cams[d.zoom].distortion[d.index];
    }
  }
}

// Recommended effects first (significant, worth adding, not redundant),
// then the other significant ones, then the rest; within each by delta BIC
// to a hundredth (aliases such as radial and rational distortion refit to
// the same minimum, and round-off must not reorder them: they keep the
// order before).
void Order(Ranking* out) {
  std::stable_sort(out->entries.begin(), out->entries.end(),
                   [](const RankedEffect& a, const RankedEffect& b) {
                     if (a.recommended != b.recommended) return a.recommended;
                     if (a.significant != b.significant) return a.significant;
                     return std::round(100 * a.delta_bic) < std::round(100 * b.delta_bic);
                   });
}

}  // namespace

void AddAtEstimate(const RankedEffect& r, InstrumentModel* m) {
  m->effects.Add(r.effect);
  m->sigmas = {};
  if (IsKinematic(r.effect)) {
    m->EffectValue(r.effect) = r.si;
  } else if (r.effect == Effect::kFocus) {
    for (CameraTool& cam : m->cams) cam.focus.fill(0.0);
    for (const FocusValue& f : r.focus) m->cams[f.zoom].focus[f.index] = f.value;
  } else if (IsBoardEffect(r.effect)) {
    SyncBoardWarps(m);  // a warp at zero for every board
    for (const WarpValue& w : r.board_warp) {
      if (BoardWarp* warp = m->WarpOf(w.first_id)) warp->w[w.index] = w.value;
    }
    SyncBoardWarps(m);
  } else {
    for (const DistortionValue& d : r.distortion) m->cams[d.zoom].distortion[d.index] = d.value;
  }
}

Ranking RankEffects(const RankingInput& in, const RankingOptions& o) {
  const Linearization& lin = *in.lin;
  const Reduced& red = *in.red;
  const int n = lin.NumRows();
  Ranking out;
  out.num_rows = n;
  out.current = RmsOfWhitened(lin, lin.r);

  const std::vector<const ColumnBlock*> effects = EffectBlocks(lin);
  // The family-wise level is shared by the effects that can be tested.
  for (const ColumnBlock* b : effects) {
    if (Observable(*b, red) && Kept(*b, red) >= o.redundant_fraction) ++out.tested;
  }
  out.level = o.significance / std::max(out.tested, 1);

  const Context cx{in,
                   o,
                   lin,
                   red,
                   *in.nuisance,
                   Normals(lin, effects),
                   in.nuisance->Apply(red.r),
                   red.Rank() + in.nuisance->rank(),
                   std::log(std::max(n, 2)),
                   out.level,
                   out.current};
  for (const ColumnBlock* b : effects) out.entries.push_back(ScoreEffect(*b, cx));
  for (Effect e : in.contained) out.entries.push_back(ContainedEntry(e, cx));

  // The linear order picks the effects to refit; the refits' numbers make
  // the final order.
  Order(&out);
  ConfirmByRefinement(cx, &out);
  for (RankedEffect& r : out.entries) {
    if (r.after_source != "refined") r.linear_after = r.after;
    r.worthwhile = r.gain >= o.min_gain;
    r.recommended = r.significant && r.worthwhile && !r.redundant;
  }
  Order(&out);
  FindAliases(effects, cx, &out);
  AlsoAfterBest(effects, cx, &out);
  for (RankedEffect& r : out.entries) {
    r.rms_before = r.before.Main();
    r.rms_after = r.after.Main();
    r.rms_unit = r.before.MainUnit();
  }
  return out;
}

std::vector<EstimatePart> EstimateParts(const RankedEffect& r) {
  const EffectInfo& info = Info(r.effect);
  std::vector<EstimatePart> out;
  if (r.effect == Effect::kFocus) {
    for (const FocusValue& f : r.focus) {
      out.push_back({"zoom " + std::to_string(f.zoom), f.name,
                     f.value * kFocusReportScale[f.index], f.sigma * kFocusReportScale[f.index],
                     kFocusReportUnits[f.index]});
    }
  } else if (IsBoardEffect(r.effect)) {
    const double scale = ReportScale(r.effect);
    for (const WarpValue& w : r.board_warp) {
      out.push_back({"board " + std::to_string(w.first_id), w.name, w.value * scale,
                     w.sigma * scale, info.report_units[w.index]});
    }
  } else if (IsKinematic(r.effect)) {
    for (int k = 0; k < r.value.num; ++k) {
      out.push_back({"", info.param_names[k], r.value.value[k], r.value.sigma[k],
                     info.report_units[k]});
    }
  }
  return out;
}

}  // namespace rtscalib

#include "libcalib/diagnose/linearization.h"

#include <ceres/ceres.h>

#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <map>
#include <memory>
#include <stdexcept>
#include <tuple>

#include "libcalib/eval/error_measures.h"
#include "libcalib/fit/cost_functions.h"
#include "libcalib/fit/parameterization.h"
#include "libcalib/model/kinematics.h"

namespace rtscalib {

const char* GroupName(ObsGroup g) {
  switch (g) {
    case ObsGroup::kEdm:
      return "edm";
    case ObsGroup::kCam:
      return "cam";
    case ObsGroup::kPixel:
      return "pixels";
  }
  return "";
}

const char* ReadingName(Reading r) {
  switch (r) {
    case Reading::kPhi:
      return "phi";
    case Reading::kTheta:
      return "theta";
    case Reading::kDistance:
      return "distance";
  }
  return "";
}

const ColumnBlock* Linearization::Find(const std::string& name) const {
  for (const ColumnBlock& b : blocks) {
    if (b.name == name) return &b;
  }
  return nullptr;
}

namespace {

std::string Deg(double rad) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.1f", rad * 180.0 / M_PI);
  return buf;
}

// d (model prediction) / d (reading) of one observation, by central
// differences; zero where the model cannot evaluate.
struct ReadingDerivatives {
  Eigen::Vector3d dphi = Eigen::Vector3d::Zero();
  Eigen::Vector3d dtheta = Eigen::Vector3d::Zero();
  Eigen::Vector3d dd = Eigen::Vector3d::Zero();
};

constexpr double kAngleStep = 1e-6;     // rad: round-off ~1e-16 * 50 m / 1e-6 << signal
constexpr double kDistanceStep = 1e-4;  // m

ReadingDerivatives RecordDerivatives(const InstrumentModel& m, const Record& r, bool need[3]) {
  ReadingDerivatives out;
  auto predict = [&](double phi, double theta, double d, Eigen::Vector3d* x) {
    try {
      *x = r.tool == Tool::kEdm ? PredictEdm(m, phi, theta, d)
                                : PredictCam(m, r.zoom, phi, theta, r.u, r.v, d);
      return true;
    } catch (const std::exception&) {
      return false;
    }
  };
  Eigen::Vector3d a, b;
  if (need[0] && predict(r.phi + kAngleStep, r.theta, r.d, &a) &&
      predict(r.phi - kAngleStep, r.theta, r.d, &b)) {
    out.dphi = (a - b) / (2 * kAngleStep);
  }
  if (need[1] && predict(r.phi, r.theta + kAngleStep, r.d, &a) &&
      predict(r.phi, r.theta - kAngleStep, r.d, &b)) {
    out.dtheta = (a - b) / (2 * kAngleStep);
  }
  if (need[2] && r.tool == Tool::kEdm && predict(r.phi, r.theta, r.d + kDistanceStep, &a) &&
      predict(r.phi, r.theta, r.d - kDistanceStep, &b)) {
    out.dd = (a - b) / (2 * kDistanceStep);
  }
  return out;
}

ReadingDerivatives PixelDerivatives(const InstrumentModel& m, const PixelObservation& p,
                                    bool need[3]) {
  ReadingDerivatives out;
  Eigen::Vector2d a, b;
  auto diff = [&](double dphi, double dtheta, Eigen::Vector3d* out3) {
    if (PredictPixel(m, p.zoom, p.phi + dphi, p.theta + dtheta, p.X, &a) &&
        PredictPixel(m, p.zoom, p.phi - dphi, p.theta - dtheta, p.X, &b)) {
      out3->head<2>() = (a - b) / (2 * kAngleStep);
    }
  };
  if (need[0]) diff(kAngleStep, 0, &out.dphi);
  if (need[1]) diff(0, kAngleStep, &out.dtheta);
  return out;
}

double ProbeVariable(const Probe& probe, double phi, double theta, double d, double unit_length) {
  switch (probe.variable) {
    case Reading::kPhi:
      return phi;
    case Reading::kTheta:
      return theta;
    case Reading::kDistance:
      return 2.0 * M_PI * d / unit_length;
  }
  return 0.0;
}

// The model with every candidate effect enabled (kinematic ones at zero):
// the fit's own parameterisation of it frees exactly the candidates' columns
// on top of the fitted model's, so the diagnosis decides nothing itself.
InstrumentModel WithCandidates(const InstrumentModel& model,
                               const std::vector<Effect>& candidates) {
  InstrumentModel work = model;
  for (Effect e : candidates) {
    if (work.effects.Has(e))
      throw std::invalid_argument(std::string(Info(e).name) + " is already in the model");
    work.effects.Add(e);
    if (IsKinematic(e)) work.EffectValue(e) = {0.0, 0.0};
  }
  return work;
}

// Column blocks of `extra` for the candidates, in candidate order, from the
// parameterisation's columns that belong to each (distortion groups: on the
// zooms with data only). Returns, per (block, tangent column), its column of
// `extra`; every other free column is a base column.
std::map<std::pair<const double*, int>, int> CandidateColumns(const Parameterization& param,
                                                              const std::vector<Effect>& candidates,
                                                              const std::vector<bool>& zoom_used,
                                                              std::vector<ColumnBlock>* blocks) {
  std::map<std::pair<const double*, int>, int> extra_col;
  int next_col = 0;
  for (Effect e : candidates) {
    ColumnBlock b;
    b.name = Info(e).name;
    b.is_effect = true;
    b.effect = e;
    b.first = next_col;
    for (const BlockDecision& d : param.Blocks()) {
      for (size_t k = 0; k < d.columns.size(); ++k) {
        const FreeColumn& c = d.columns[k];
        if (c.effect != e || (c.zoom >= 0 && !zoom_used[c.zoom])) continue;
        extra_col[{d.block, static_cast<int>(k)}] = b.first + b.size;
        b.param_names.push_back(c.name);
        if (IsDistortion(e)) b.distortion.push_back({c.zoom, c.index});
        ++b.size;
      }
    }
    next_col += b.size;
    blocks->push_back(b);
  }
  return extra_col;
}

// A residual block's observations with the cluster they are tested in:
// records by pointing and face (EDM and camera rows of one pointing share
// it), pixels by shot.
struct ClusteredGroup {
  ObservationGroup group;
  int cluster = 0;
};
std::vector<ClusteredGroup> Cluster(const Observations& obs,
                                    const std::vector<ObservationGroup>& groups,
                                    Linearization* lin) {
  std::vector<ClusteredGroup> out;
  std::map<std::tuple<int, double, double>, int> record_cluster;
  for (const ObservationGroup& g : groups) {
    if (g.kind == ObsGroup::kPixel) {
      lin->cluster_names.push_back("shot " + g.shot);
      out.push_back({g, lin->num_clusters++});
      continue;
    }
    const Record& r = obs.records[g.indices.front()];
    const auto key = std::make_tuple(r.face, r.phi, r.theta);
    auto c = record_cluster.find(key);
    if (c == record_cluster.end()) {
      c = record_cluster.insert({key, lin->num_clusters++}).first;
      lin->cluster_names.push_back("face " + std::to_string(r.face) + ", phi " + Deg(r.phi) +
                                   " deg, theta " + Deg(r.theta) + " deg");
    }
    out.push_back({g, c->second});
  }
  return out;
}

// The residual blocks of the refinement, whitened by the fit's sigmas;
// groups the model cannot evaluate are skipped (and counted). Fills the
// row bookkeeping of `lin`.
std::vector<ceres::ResidualBlockId> AddResiduals(const Observations& obs,
                                                 const std::vector<ClusteredGroup>& groups,
                                                 const Parameterization& param,
                                                 InstrumentModel* work, ceres::Problem* problem,
                                                 Linearization* lin) {
  std::vector<ceres::ResidualBlockId> residual_ids;
  for (const ClusteredGroup& cg : groups) {
    const ObservationGroup& g = cg.group;
    std::vector<double*> blocks;
    std::unique_ptr<ceres::CostFunction> cost(
        MakeGroupCost(obs, g, 1.0 / lin->sigma[static_cast<int>(g.kind)], param, work, &blocks));
    std::vector<double> test(cost->num_residuals());
    if (!cost->Evaluate(blocks.data(), test.data(), nullptr)) {
      ++lin->not_evaluable;
      continue;
    }
    residual_ids.push_back(problem->AddResidualBlock(cost.release(), nullptr, blocks));
    const int per = g.kind == ObsGroup::kPixel ? 2 : 3;
    for (int i : g.indices) {
      for (int c = 0; c < per; ++c) lin->rows.push_back({g.kind, i, c, cg.cluster, g.face});
      ++lin->num_observations[static_cast<int>(g.kind)];
    }
  }
  return residual_ids;
}

// One Jacobian evaluation: r, the base columns (the fit's free parameters,
// in the parameterisation's order) and the candidates' columns of `extra`
// (`extra_col`); `num_extra_cols` sizes `extra` (candidates and probes).
void EvaluateColumns(ceres::Problem* problem, const std::vector<ceres::ResidualBlockId>& ids,
                     const std::vector<const BlockDecision*>& free_blocks,
                     const std::map<std::pair<const double*, int>, int>& extra_col,
                     int num_extra_cols, int num_threads, Linearization* lin) {
  ceres::Problem::EvaluateOptions eopt;
  eopt.residual_blocks = ids;
  eopt.apply_loss_function = false;
  eopt.num_threads = num_threads;
  // Per Jacobian column: its base column or its extra column.
  std::vector<int> base_col, to_extra;
  for (const BlockDecision* d : free_blocks) {
    eopt.parameter_blocks.push_back(d->block);
    for (size_t k = 0; k < d->columns.size(); ++k) {
      auto it = extra_col.find({d->block, static_cast<int>(k)});
      if (it != extra_col.end()) {
        base_col.push_back(-1);
        to_extra.push_back(it->second);
      } else {
        base_col.push_back(static_cast<int>(lin->base_names.size()));
        to_extra.push_back(-1);
        lin->base_names.push_back(d->columns[k].name);
        lin->base_columns.push_back(d->columns[k]);
      }
    }
  }
  double cost = 0;
  std::vector<double> residuals;
  ceres::CRSMatrix jac;
  if (!problem->Evaluate(eopt, &cost, &residuals, nullptr, &jac)) {
    throw std::runtime_error("the model could not be evaluated at the fitted parameters");
  }
  const int n = static_cast<int>(residuals.size());
  if (n != static_cast<int>(lin->rows.size()) ||
      jac.num_cols != static_cast<int>(base_col.size())) {
    throw std::logic_error("linearization: row or column bookkeeping does not match Ceres");
  }
  lin->r = Eigen::Map<const Eigen::VectorXd>(residuals.data(), n);
  lin->base = Eigen::MatrixXd::Zero(n, lin->base_names.size());
  lin->extra = Eigen::MatrixXd::Zero(n, num_extra_cols);
  for (int i = 0; i < n; ++i) {
    for (int k = jac.rows[i]; k < jac.rows[i + 1]; ++k) {
      const int c = jac.cols[k];
      if (base_col[c] >= 0) {
        lin->base(i, base_col[c]) = jac.values[k];
      } else {
        lin->extra(i, to_extra[c]) = jac.values[k];
      }
    }
  }
}

// Probes: d r / d reading times the harmonic, per face, in the columns of
// `extra` from `first_col` on (central differences of the model's
// predictions, cached per observation).
void AddProbeColumns(const Observations& obs, const InstrumentModel& model,
                     const std::vector<Probe>& probes, int first_col, Linearization* lin) {
  bool need[3] = {false, false, false};
  for (const Probe& p : probes) need[static_cast<int>(p.reading)] = true;
  std::map<std::pair<int, int>, ReadingDerivatives> cache;  // (group kind != pixel, index)
  int col = first_col;
  for (const Probe& p : probes) {
    ColumnBlock b;
    b.is_probe = true;
    b.probe = p;
    b.first = col;
    b.size = 2;
    b.name = std::string(ReadingName(p.reading)) + " error, harmonic " +
             std::to_string(p.harmonic) + " of " + ReadingName(p.variable) + ", face " +
             std::to_string(p.face);
    b.param_names = {b.name + " [cos]", b.name + " [sin]"};
    lin->blocks.push_back(b);
    col += 2;
  }
  for (int i = 0; i < lin->NumRows(); ++i) {
    const ResidualRow& row = lin->rows[i];
    const bool pixel = row.group == ObsGroup::kPixel;
    auto it = cache.find({pixel ? 1 : 0, row.index});
    if (it == cache.end()) {
      ReadingDerivatives d = pixel ? PixelDerivatives(model, obs.pixels[row.index], need)
                                   : RecordDerivatives(model, obs.records[row.index], need);
      const double s = 1.0 / lin->sigma[static_cast<int>(row.group)];
      d.dphi *= s;
      d.dtheta *= s;
      d.dd *= s;
      it = cache.insert({{pixel ? 1 : 0, row.index}, d}).first;
    }
    const ReadingDerivatives& d = it->second;
    double phi, theta, dist;
    if (pixel) {
      phi = obs.pixels[row.index].phi;
      theta = obs.pixels[row.index].theta;
      dist = 0;
    } else {
      phi = obs.records[row.index].phi;
      theta = obs.records[row.index].theta;
      dist = obs.records[row.index].d;
    }
    for (size_t k = 0; k < probes.size(); ++k) {
      const Probe& p = probes[k];
      if (p.face != row.face) continue;
      if (p.variable == Reading::kDistance && row.group != ObsGroup::kEdm) continue;
      const double deriv = p.reading == Reading::kPhi     ? d.dphi[row.component]
                           : p.reading == Reading::kTheta ? d.dtheta[row.component]
                                                          : d.dd[row.component];
      const double x =
          p.harmonic * ProbeVariable(p, phi, theta, dist, model.edm_cyclic_unit_length);
      const int c = first_col + 2 * static_cast<int>(k);
      lin->extra(i, c) = deriv * std::cos(x);
      lin->extra(i, c + 1) = deriv * std::sin(x);
    }
  }
}

}  // namespace

Linearization Linearize(const Observations& obs, const InstrumentModel& model,
                        const LinearizeOptions& options) {
  const std::string msg = options.fit.Check();
  if (!msg.empty()) throw std::invalid_argument(msg);
  Linearization lin;
  for (int g = 0; g < 3; ++g) lin.sigma[g] = options.sigma[g];
  lin.edm_cyclic_unit_length = model.edm_cyclic_unit_length;

  InstrumentModel work = WithCandidates(model, options.candidates);
  // Rows the fit uses; the model is already fitted, so rows of a zoom it has
  // no camera for are skipped rather than reported.
  const UsedRows rows = SelectRows(obs, options.fit, model.NumZooms(), UnknownZoom::kSkip);
  lin.excluded_critical = rows.excluded_critical;
  std::vector<bool> zoom_used(model.NumZooms(), false);
  for (int i : rows.records) {
    if (obs.records[i].tool == Tool::kCam) zoom_used[obs.records[i].zoom] = true;
  }
  for (int i : rows.pixels) zoom_used[obs.pixels[i].zoom] = true;

  const Parameterization param(&work, options.fit, FactsOf(obs, rows));
  const auto extra_col = CandidateColumns(param, options.candidates, zoom_used, &lin.blocks);
  const int num_candidate_cols =
      lin.blocks.empty() ? 0 : lin.blocks.back().first + lin.blocks.back().size;

  const std::vector<ClusteredGroup> groups =
      Cluster(obs, GroupObservations(obs, rows, /*one_per_observation=*/false), &lin);
  ceres::Problem::Options popt;
  popt.manifold_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(popt);
  const std::vector<ceres::ResidualBlockId> residual_ids =
      AddResiduals(obs, groups, param, &work, &problem, &lin);
  if (residual_ids.empty()) {
    throw std::invalid_argument("nothing to diagnose: no observation outside the critical regions");
  }

  const std::vector<const BlockDecision*> free_blocks = param.Apply(&problem, false);
  EvaluateColumns(&problem, residual_ids, free_blocks, extra_col,
                  num_candidate_cols + 2 * static_cast<int>(options.probes.size()),
                  options.fit.num_threads, &lin);
  if (!options.probes.empty())
    AddProbeColumns(obs, model, options.probes, num_candidate_cols, &lin);
  return lin;
}

Reduced Reduce(const Linearization& lin) {
  const int n = lin.NumRows();
  Reduced red(n);
  red.base.Add(lin.base, 1e-9);
  red.r = red.base.Apply(lin.r);
  red.extra = red.base.Apply(lin.extra);
  red.cluster.resize(n);
  for (int i = 0; i < n; ++i) red.cluster[i] = lin.rows[i].cluster;
  const int m = static_cast<int>(lin.extra.cols());
  red.kept_fraction = Eigen::VectorXd::Zero(m);
  red.column_norm = Eigen::VectorXd::Zero(m);
  for (int j = 0; j < m; ++j) {
    red.column_norm[j] = lin.extra.col(j).norm();
    if (red.column_norm[j] > 0) red.kept_fraction[j] = red.extra.col(j).norm() / red.column_norm[j];
  }
  return red;
}

}  // namespace rtscalib

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
#include "libcalib/fit/manifolds.h"
#include "libcalib/model/kinematics.h"

namespace rtscalib::diagnose {

const char* GroupName(ObsGroup g) {
  switch (g) {
    case ObsGroup::kEdm:
      return "edm";
    case ObsGroup::kCam:
      return "cam";
    default:
      return "pixels";
  }
}

const char* ReadingName(Reading r) {
  switch (r) {
    case Reading::kPhi:
      return "phi";
    case Reading::kTheta:
      return "theta";
    default:
      return "distance";
  }
}

const ColumnBlock* Linearization::Find(const std::string& name) const {
  for (const ColumnBlock& b : blocks) {
    if (b.name == name) return &b;
  }
  return nullptr;
}

namespace {

// Where one tangent column of a parameter block goes: a base column (block <
// 0) or column `offset` of candidate block `block`.
struct ColumnTarget {
  int block = -1;
  int offset = 0;
  std::string name;
};

struct BlockDecision {
  BlockKind kind = BlockKind::kFree;
  int size = 0;
  std::vector<int> frozen;
  std::vector<ColumnTarget> tangent;  // one per tangent column
};

// The free/frozen decisions of Refine's Parameterization (libcalib/fit/refine.cc),
// plus the candidates' own columns.
class FreeBlocks {
 public:
  FreeBlocks(InstrumentModel* work, const InstrumentModel& fitted, const FitOptions& o,
             const std::vector<Effect>& candidates, const std::vector<int>& zooms_with_data,
             std::vector<ColumnBlock>* blocks) {
    InstrumentModel& m = *work;
    const bool dh = m.kinematics == Kinematics::kDh;
    auto base_cols = [&](const std::string& prefix, std::initializer_list<std::string> names) {
      std::vector<ColumnTarget> t;
      for (const std::string& n : names) t.push_back({-1, 0, prefix + n});
      return t;
    };
    auto pose = [&](PoseBlock* p, const std::string& name, BlockKind rot) {
      if (rot == BlockKind::kQuaternion) {
        Set(p->q.data(), {rot, 4, {}, base_cols(name + ".rotation[", {"x]", "y]", "z]"})});
      } else if (rot == BlockKind::kNoRoll) {
        Set(p->q.data(), {rot, 4, {}, base_cols(name + ".rotation[", {"x]", "y]"})});
      } else {
        Set(p->q.data(), {BlockKind::kConstant, 4, {}, {}});
      }
    };
    pose(&m.base, "base", BlockKind::kQuaternion);
    Set(m.base.t.data(), {BlockKind::kFree, 3, {}, base_cols("base.t[", {"x]", "y]", "z]"})});
    if (dh) {
      Set(m.links[0].p.data(),
          {BlockKind::kSubset, 4, {kDhD, kDhGamma}, base_cols("link1.", {"alpha", "a"})});
      Set(m.links[1].p.data(), {BlockKind::kConstant, 4, {}, {}});
      pose(&m.edm, "edm", BlockKind::kNoRoll);
      Set(m.edm.t.data(), {BlockKind::kFree, 3, {}, base_cols("edm.t[", {"x]", "y]", "z]"})});
    } else {
      pose(&m.edm, "edm", BlockKind::kConstant);
      Set(m.edm.t.data(), {BlockKind::kSubset, 3, {2}, base_cols("edm.t[", {"x]", "y]"})});
    }

    // Candidate blocks first (their column layout), then the cameras.
    std::vector<int> candidate_of_index(camera::kNumDistortion, -1);
    std::vector<bool> enabled_index(camera::kNumDistortion, false);
    for (Effect e : fitted.effects.List()) {
      if (IsDistortion(e)) {
        for (int i : Info(e).distortion_indices) enabled_index[i] = true;
      }
    }
    int next_col = 0;
    for (Effect e : candidates) {
      ColumnBlock b;
      b.name = Info(e).name;
      b.is_effect = true;
      b.effect = e;
      b.first = next_col;
      if (IsKinematic(e)) {
        b.size = Info(e).num_params;
        std::vector<ColumnTarget> t;
        for (int k = 0; k < b.size; ++k) {
          b.param_names.push_back(b.name + "[" + std::to_string(k) + "]");
          t.push_back({static_cast<int>(blocks->size()), k, b.param_names.back()});
        }
        Set(m.EffectValue(e).data(), {BlockKind::kFree, b.size, {}, t});
      } else {
        for (int z : zooms_with_data) {
          for (int i : Info(e).distortion_indices) {
            b.distortion.push_back({z, i});
            b.param_names.push_back("cam[" + std::to_string(z) + "]." + kDistortionNames[i]);
          }
        }
        b.size = static_cast<int>(b.distortion.size());
        for (int i : Info(e).distortion_indices)
          candidate_of_index[i] = static_cast<int>(blocks->size());
      }
      next_col += b.size;
      blocks->push_back(b);
    }
    for (int z : zooms_with_data) {
      CameraTool& cam = m.cams[z];
      const std::string zs = "cam[" + std::to_string(z) + "]";
      pose(&cam.flange_from_cam, zs, BlockKind::kQuaternion);
      Set(cam.flange_from_cam.t.data(),
          {BlockKind::kFree, 3, {}, base_cols(zs + ".t[", {"x]", "y]", "z]"})});
      if (o.fit_intrinsics) {
        Set(cam.intrinsics.data(),
            {BlockKind::kFree, 4, {}, base_cols(zs + ".", {"fx", "fy", "cx", "cy"})});
      } else {
        Set(cam.intrinsics.data(), {BlockKind::kConstant, 4, {}, {}});
      }
      BlockDecision dist{BlockKind::kSubset, camera::kNumDistortion, {}, {}};
      for (int i = 0; i < camera::kNumDistortion; ++i) {
        const std::string name = zs + "." + kDistortionNames[i];
        if (enabled_index[i]) {
          dist.tangent.push_back({-1, 0, name});
        } else if (candidate_of_index[i] >= 0) {
          const ColumnBlock& b = (*blocks)[candidate_of_index[i]];
          int offset = 0;
          for (size_t k = 0; k < b.distortion.size(); ++k) {
            if (b.distortion[k] == std::make_pair(z, i)) offset = static_cast<int>(k);
          }
          dist.tangent.push_back({candidate_of_index[i], offset, name});
        } else {
          dist.frozen.push_back(i);
        }
      }
      Set(cam.distortion.data(), dist);
    }
    for (Effect e : fitted.effects.List()) {
      if (!IsKinematic(e)) continue;
      std::vector<ColumnTarget> t;
      for (int k = 0; k < Info(e).num_params; ++k) {
        t.push_back({-1, 0, std::string(Info(e).name) + "[" + std::to_string(k) + "]"});
      }
      Set(m.EffectValue(e).data(), {BlockKind::kFree, Info(e).num_params, {}, t});
    }
    num_extra_ = next_col;
  }

  int ActiveSize(const BlockLayout& layout) const {
    int n = 0;
    for (size_t i = 0; i < layout.blocks.size(); ++i) {
      auto it = decisions_.find(layout.blocks[i]);
      if (it == decisions_.end() || it->second.kind != BlockKind::kConstant) n += layout.sizes[i];
    }
    return n;
  }

  // Applies manifolds and constants; returns the non-constant blocks present
  // in the problem, in a fixed order, with their decisions.
  std::vector<std::pair<double*, const BlockDecision*>> Apply(ceres::Problem* problem) const {
    std::vector<std::pair<double*, const BlockDecision*>> out;
    for (const auto& [cp, d] : order_) {
      double* p = const_cast<double*>(cp);
      if (!problem->HasParameterBlock(p)) continue;
      ParameterizeBlock(problem, p, d->kind, d->size, d->frozen);
      if (d->kind == BlockKind::kConstant) continue;
      out.push_back({p, d});
    }
    return out;
  }

  int num_extra() const { return num_extra_; }

 private:
  static constexpr const char* kDistortionNames[camera::kNumDistortion] = {
      "k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6", "s1", "s2", "s3", "s4", "taux", "tauy"};

  void Set(const double* p, BlockDecision d) {
    if (d.kind == BlockKind::kSubset && static_cast<int>(d.frozen.size()) == d.size) {
      d.kind = BlockKind::kConstant;
      d.tangent.clear();
    }
    auto [it, inserted] = decisions_.insert({p, std::move(d)});
    if (!inserted) return;
    order_.push_back({p, &it->second});
  }

  std::map<const double*, BlockDecision> decisions_;
  std::vector<std::pair<const double*, const BlockDecision*>> order_;
  int num_extra_ = 0;
};

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
    default:
      return 2.0 * M_PI * d / unit_length;
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

  InstrumentModel work = model;
  for (Effect e : options.candidates) {
    if (work.effects.Has(e))
      throw std::invalid_argument(std::string(Info(e).name) + " is already in the model");
    if (IsKinematic(e)) {
      work.effects.Add(e);
      work.EffectValue(e) = {0.0, 0.0};
    }
  }

  // Rows the fit uses (critical regions and unknown zooms excluded as in Refine).
  const double zmin = options.fit.min_zenith_rad, zmax = options.fit.max_zenith_rad;
  std::vector<int> records, pixels;
  std::vector<bool> zoom_used(model.NumZooms(), false);
  for (size_t i = 0; i < obs.records.size(); ++i) {
    const Record& r = obs.records[i];
    if (InCriticalRegion(r.theta, zmin, zmax)) {
      ++lin.excluded_critical;
      continue;
    }
    if (r.tool == Tool::kCam) {
      if (r.zoom < 0 || r.zoom >= model.NumZooms()) continue;
      zoom_used[r.zoom] = true;
    }
    records.push_back(static_cast<int>(i));
  }
  for (size_t i = 0; i < obs.pixels.size(); ++i) {
    const PixelObservation& p = obs.pixels[i];
    if (InCriticalRegion(p.theta, zmin, zmax)) {
      ++lin.excluded_critical;
      continue;
    }
    if (p.zoom < 0 || p.zoom >= model.NumZooms()) continue;
    zoom_used[p.zoom] = true;
    pixels.push_back(static_cast<int>(i));
  }
  std::vector<int> zooms_with_data;
  for (int z = 0; z < model.NumZooms(); ++z) {
    if (zoom_used[z]) zooms_with_data.push_back(z);
  }

  FreeBlocks decisions(&work, model, options.fit, options.candidates, zooms_with_data, &lin.blocks);

  // Residual groups as in Refine: records per pointing and tool, pixels per shot.
  struct Group {
    ObsGroup kind;
    int zoom;
    double phi, theta;
    int face;
    int cluster;
    std::vector<int> indices;
  };
  std::vector<Group> groups;
  std::map<std::tuple<int, double, double>, int> record_cluster;
  std::map<std::tuple<std::string, int, double, double>, int> shot_group;  // -> groups index
  {
    std::map<std::tuple<bool, int, double, double>, int> index;
    for (int i : records) {
      const Record& r = obs.records[i];
      const bool edm = r.tool == Tool::kEdm;
      const auto key = std::make_tuple(edm, edm ? -1 : r.zoom, r.phi, r.theta);
      auto it = index.find(key);
      if (it == index.end()) {
        const auto ckey = std::make_tuple(r.face, r.phi, r.theta);
        auto c = record_cluster.find(ckey);
        if (c == record_cluster.end()) {
          c = record_cluster.insert({ckey, lin.num_clusters++}).first;
          lin.cluster_names.push_back("face " + std::to_string(r.face) + ", phi " + Deg(r.phi) +
                                      " deg, theta " + Deg(r.theta) + " deg");
        }
        index[key] = static_cast<int>(groups.size());
        groups.push_back({edm ? ObsGroup::kEdm : ObsGroup::kCam,
                          edm ? -1 : r.zoom,
                          r.phi,
                          r.theta,
                          r.face,
                          c->second,
                          {i}});
      } else {
        groups[it->second].indices.push_back(i);
      }
    }
    for (int i : pixels) {
      const PixelObservation& p = obs.pixels[i];
      const auto key = std::make_tuple(p.shot, p.zoom, p.phi, p.theta);
      auto it = shot_group.find(key);
      if (it == shot_group.end()) {
        shot_group[key] = static_cast<int>(groups.size());
        lin.cluster_names.push_back("shot " + p.shot);
        groups.push_back(
            {ObsGroup::kPixel, p.zoom, p.phi, p.theta, p.face, lin.num_clusters++, {i}});
      } else {
        groups[it->second].indices.push_back(i);
      }
    }
  }

  ceres::Problem::Options popt;
  popt.manifold_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(popt);
  std::vector<ceres::ResidualBlockId> residual_ids;
  for (const Group& g : groups) {
    std::unique_ptr<ceres::CostFunction> cost;
    std::vector<double*> blocks;
    const double inv_sigma = 1.0 / lin.sigma[static_cast<int>(g.kind)];
    if (g.kind == ObsGroup::kPixel) {
      auto* f = new ShotResidual;
      f->layout = LayoutFor(&work, g.zoom);
      f->phi = g.phi;
      f->theta = g.theta;
      f->inv_sigma = inv_sigma;
      for (int i : g.indices) f->points.push_back({obs.pixels[i].X, obs.pixels[i].uv});
      blocks = f->layout.blocks;
      cost.reset(
          MakeCost(f, 2 * static_cast<int>(g.indices.size()), decisions.ActiveSize(f->layout)));
    } else {
      auto* f = new RecordGroupResidual;
      f->layout = LayoutFor(&work, g.zoom);
      f->edm = g.kind == ObsGroup::kEdm;
      f->phi = g.phi;
      f->theta = g.theta;
      for (int i : g.indices) {
        const Record& r = obs.records[i];
        f->rows.push_back({r.u, r.v, r.d, r.x, inv_sigma});
      }
      blocks = f->layout.blocks;
      cost.reset(
          MakeCost(f, 3 * static_cast<int>(g.indices.size()), decisions.ActiveSize(f->layout)));
    }
    std::vector<double> test(cost->num_residuals());
    if (!cost->Evaluate(blocks.data(), test.data(), nullptr)) {
      ++lin.not_evaluable;
      continue;
    }
    residual_ids.push_back(problem.AddResidualBlock(cost.release(), nullptr, blocks));
    const int per = g.kind == ObsGroup::kPixel ? 2 : 3;
    for (int i : g.indices) {
      for (int c = 0; c < per; ++c) lin.rows.push_back({g.kind, i, c, g.cluster, g.face});
      ++lin.num_observations[static_cast<int>(g.kind)];
    }
  }
  if (residual_ids.empty()) {
    throw std::invalid_argument("nothing to diagnose: no observation outside the critical regions");
  }

  const auto free_blocks = decisions.Apply(&problem);
  ceres::Problem::EvaluateOptions eopt;
  eopt.residual_blocks = residual_ids;
  eopt.apply_loss_function = false;
  eopt.num_threads = options.fit.num_threads;
  std::vector<const ColumnTarget*> col_target;
  for (const auto& [p, d] : free_blocks) {
    eopt.parameter_blocks.push_back(p);
    for (const ColumnTarget& t : d->tangent) col_target.push_back(&t);
  }
  double cost = 0;
  std::vector<double> residuals;
  ceres::CRSMatrix jac;
  if (!problem.Evaluate(eopt, &cost, &residuals, nullptr, &jac)) {
    throw std::runtime_error("the model could not be evaluated at the fitted parameters");
  }
  const int n = static_cast<int>(residuals.size());
  if (n != static_cast<int>(lin.rows.size()) ||
      jac.num_cols != static_cast<int>(col_target.size())) {
    throw std::logic_error("linearization: row or column bookkeeping does not match Ceres");
  }
  lin.r = Eigen::Map<const Eigen::VectorXd>(residuals.data(), n);

  // Base columns in tangent order; extra columns at their block offsets.
  std::vector<int> base_col(col_target.size(), -1), extra_col(col_target.size(), -1);
  for (size_t c = 0; c < col_target.size(); ++c) {
    const ColumnTarget& t = *col_target[c];
    if (t.block < 0) {
      base_col[c] = static_cast<int>(lin.base_names.size());
      lin.base_names.push_back(t.name);
    } else {
      extra_col[c] = lin.blocks[t.block].first + t.offset;
    }
  }
  const int num_candidate_cols = decisions.num_extra();
  const int num_probe_cols = 2 * static_cast<int>(options.probes.size());
  lin.base = Eigen::MatrixXd::Zero(n, lin.base_names.size());
  lin.extra = Eigen::MatrixXd::Zero(n, num_candidate_cols + num_probe_cols);
  for (int i = 0; i < n; ++i) {
    for (int k = jac.rows[i]; k < jac.rows[i + 1]; ++k) {
      const int c = jac.cols[k];
      if (base_col[c] >= 0) {
        lin.base(i, base_col[c]) = jac.values[k];
      } else {
        lin.extra(i, extra_col[c]) = jac.values[k];
      }
    }
  }

  // Probes: d r / d reading times the harmonic, per face.
  if (!options.probes.empty()) {
    bool need[3] = {false, false, false};
    for (const Probe& p : options.probes) need[static_cast<int>(p.reading)] = true;
    std::map<std::pair<int, int>, ReadingDerivatives> cache;  // (group kind != pixel, index)
    int col = num_candidate_cols;
    for (const Probe& p : options.probes) {
      ColumnBlock b;
      b.is_probe = true;
      b.probe = p;
      b.first = col;
      b.size = 2;
      b.name = std::string(ReadingName(p.reading)) + " error, harmonic " +
               std::to_string(p.harmonic) + " of " + ReadingName(p.variable) + ", face " +
               std::to_string(p.face);
      b.param_names = {b.name + " [cos]", b.name + " [sin]"};
      lin.blocks.push_back(b);
      col += 2;
    }
    for (int i = 0; i < n; ++i) {
      const ResidualRow& row = lin.rows[i];
      const bool pixel = row.group == ObsGroup::kPixel;
      auto it = cache.find({pixel ? 1 : 0, row.index});
      if (it == cache.end()) {
        ReadingDerivatives d = pixel ? PixelDerivatives(model, obs.pixels[row.index], need)
                                     : RecordDerivatives(model, obs.records[row.index], need);
        const double s = 1.0 / lin.sigma[static_cast<int>(row.group)];
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
      for (size_t k = 0; k < options.probes.size(); ++k) {
        const Probe& p = options.probes[k];
        if (p.face != row.face) continue;
        if (p.variable == Reading::kDistance && row.group != ObsGroup::kEdm) continue;
        const double deriv = p.reading == Reading::kPhi     ? d.dphi[row.component]
                             : p.reading == Reading::kTheta ? d.dtheta[row.component]
                                                            : d.dd[row.component];
        const double x =
            p.harmonic * ProbeVariable(p, phi, theta, dist, model.edm_cyclic_unit_length);
        const int c = num_candidate_cols + 2 * static_cast<int>(k);
        lin.extra(i, c) = deriv * std::cos(x);
        lin.extra(i, c + 1) = deriv * std::sin(x);
      }
    }
  }
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

}  // namespace rtscalib::diagnose

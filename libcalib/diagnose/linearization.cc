#include "libcalib/diagnose/linearization.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>
#include <tuple>

#include "libcalib/eval/error_measures.h"
#include "libcalib/fit/cost_functions.h"
#include "libcalib/fit/parameter_layout.h"
#include "libcalib/fit/parameterization.h"
#include "libcalib/fit/unknowns.h"
#include "libcalib/model/focus.h"
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

// The zoom of a row's observation (-1 for EDM rows).
int ZoomOf(const Observations& obs, const ResidualRow& row) {
  if (row.group == ObsGroup::kPixel) return obs.pixels[row.index].zoom;
  if (row.group == ObsGroup::kCam) return obs.records[row.index].zoom;
  return -1;
}

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
                                    double focus_distance, bool need[3]) {
  ReadingDerivatives out;
  Eigen::Vector2d a, b;
  auto diff = [&](double dphi, double dtheta, Eigen::Vector3d* out3) {
    if (PredictPixel(m, p.zoom, p.phi + dphi, p.theta + dtheta, p.X, &a, focus_distance) &&
        PredictPixel(m, p.zoom, p.phi - dphi, p.theta - dtheta, p.X, &b, focus_distance)) {
      out3->head<2>() = (a - b) / (2 * kAngleStep);
    }
  };
  if (need[0]) diff(kAngleStep, 0, &out.dphi);
  if (need[1]) diff(0, kAngleStep, &out.dtheta);
  return out;
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
    if (e == Effect::kFocus) {
      for (CameraTool& cam : work.cams) cam.focus.fill(0.0);
    }
  }
  // board_warp: a warp at zero for every board of estimated pose.
  SyncBoardWarps(&work);
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
        if (IsCameraEffect(e)) b.distortion.push_back({c.zoom, c.index});
        if (IsBoardEffect(e)) b.boards.push_back({c.board, c.index});
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

// The local parameters' columns of the Jacobian (LocalColumns: boards of
// unknown pose, points of unknown position), sparse until projected out.
struct LocalJacobian {
  std::vector<int> unit;  // per local column: its board or point
  std::vector<std::vector<std::pair<int, double>>> entries;  // per local column: (row, value)
};

// The parameter blocks of the model's boards and points, each with the
// board or point it belongs to (a board's rotation and translation are one).
std::map<const double*, int> LocalUnits(InstrumentModel* work) {
  std::map<const double*, int> units;
  int next = 0;
  for (EstimatedBoard& b : work->boards) {
    units[b.pose.q.data()] = next;
    units[b.pose.t.data()] = next++;
  }
  for (EstimatedPoint& p : work->points) units[p.x.data()] = next++;
  return units;
}

// One Jacobian evaluation: r, the base columns (the fit's free global
// parameters, in the parameterisation's order), the local ones (`local`,
// blocks in `local_units`) and the candidates' columns of `extra`
// (`extra_col`); `num_extra_cols` sizes `extra` (candidates and probes).
void EvaluateColumns(ceres::Problem* problem, const std::vector<ceres::ResidualBlockId>& ids,
                     const std::vector<const BlockDecision*>& free_blocks,
                     const std::map<std::pair<const double*, int>, int>& extra_col,
                     const std::map<const double*, int>& local_units, int num_extra_cols,
                     int num_threads, Linearization* lin, LocalJacobian* local) {
  ceres::Problem::EvaluateOptions eopt;
  eopt.residual_blocks = ids;
  eopt.apply_loss_function = false;
  eopt.num_threads = num_threads;
  // Per Jacobian column: its base column, its extra column or its local column.
  std::vector<int> base_col, to_extra, to_local;
  for (const BlockDecision* d : free_blocks) {
    eopt.parameter_blocks.push_back(d->block);
    const auto unit = local_units.find(d->block);
    for (size_t k = 0; k < d->columns.size(); ++k) {
      auto it = extra_col.find({d->block, static_cast<int>(k)});
      base_col.push_back(-1);
      to_extra.push_back(-1);
      to_local.push_back(-1);
      if (it != extra_col.end()) {
        to_extra.back() = it->second;
      } else if (unit != local_units.end()) {
        to_local.back() = static_cast<int>(local->unit.size());
        local->unit.push_back(unit->second);
      } else {
        base_col.back() = static_cast<int>(lin->base_names.size());
        lin->base_names.push_back(d->columns[k].name);
        lin->base_columns.push_back(d->columns[k]);
      }
    }
  }
  local->entries.assign(local->unit.size(), {});
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
      } else if (to_extra[c] >= 0) {
        lin->extra(i, to_extra[c]) = jac.values[k];
      } else if (jac.values[k] != 0.0) {
        local->entries[to_local[c]].push_back({i, jac.values[k]});
      }
    }
  }
}

double HarmonicVariable(const Probe& probe, double phi, double theta, double d,
                        double unit_length) {
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

// Steps of the image motions' central differences on camera records: a
// relative scale, a shift [px], a rotation [rad]; F_CAM is linear in them to
// ~1e-12 over such steps, and round-off (1e-16 x 50 m / 1e-6) stays far
// below any signal.
constexpr double kMotionStep[kNumImageMotions] = {1e-6, 1e-3, 1e-3, 1e-6};

// The model with zoom z's image moved by `step` of motion k (image-motion
// probes of camera records): scale (fx, fy), shift (cx or cy), or a turn of
// the camera about its optical axis.
InstrumentModel MovedImage(const InstrumentModel& model, int zoom, int motion, double step) {
  InstrumentModel m = model;
  m.sigmas = ModelSigmas();
  CameraTool& cam = m.cams[zoom];
  switch (motion) {
    case 0:
      cam.intrinsics[0] *= 1.0 + step;
      cam.intrinsics[1] *= 1.0 + step;
      break;
    case 1:
      cam.intrinsics[2] += step;
      break;
    case 2:
      cam.intrinsics[3] += step;
      break;
    default: {
      // The image turned by +w about the principal point is the camera
      // turned by -w about its z axis.
      Rigid3 tool = cam.flange_from_cam.ToRigid();
      tool.rotation =
          tool.rotation * Eigen::AngleAxisd(-step, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      cam.flange_from_cam = PoseBlock::FromRigid(tool);
      break;
    }
  }
  return m;
}

int TrendSize(const Probe& p, const std::vector<SessionVariable>& variables) {
  switch (p.form) {
    case TrendForm::kLinear:
    case TrendForm::kInverse:
      return 1;
    case TrendForm::kQuadratic:
      return 2;
    case TrendForm::kCategories:
      return static_cast<int>(variables.at(p.session_variable).categories.size());
  }
  return 1;
}

// Columns of a probe in `extra`.
int ProbeSize(const Probe& p, const std::vector<SessionVariable>& variables) {
  switch (p.kind) {
    case ProbeKind::kHarmonic:
      return 2;
    case ProbeKind::kReadingTrend:
      return TrendSize(p, variables);
    case ProbeKind::kImageMotion:
      return kNumImageMotions * TrendSize(p, variables);
    case ProbeKind::kImageField:
      return p.field == ImageField::kPosition ? 14 : 6;
  }
  return 0;
}

const char* const kMotionNames[kNumImageMotions] = {"scale", "shift u", "shift v", "rotation"};

std::string FormName(TrendForm f) {
  switch (f) {
    case TrendForm::kLinear:
      return "linear";
    case TrendForm::kInverse:
      return "1/x";
    case TrendForm::kQuadratic:
      return "P1, P2";
    case TrendForm::kCategories:
      return "per category";
  }
  return "";
}

// The block name of a probe (reports refer to probes by it).
std::string ProbeName(const Probe& p, const std::vector<SessionVariable>& variables) {
  switch (p.kind) {
    case ProbeKind::kHarmonic:
      return std::string(ReadingName(p.reading)) + " error, harmonic " +
             std::to_string(p.harmonic) + " of " + ReadingName(p.variable) + ", face " +
             std::to_string(p.face);
    case ProbeKind::kReadingTrend:
      return std::string(ReadingName(p.reading)) + (p.per_metre ? " scale" : " error") +
             " against " + variables.at(p.session_variable).name + " (" + FormName(p.form) + ")";
    case ProbeKind::kImageMotion:
      return "image motion of zoom " + std::to_string(p.zoom) + " against " +
             variables.at(p.session_variable).name + " (" + FormName(p.form) + ")";
    case ProbeKind::kImageField:
      return "image field of zoom " + std::to_string(p.zoom) + " (" +
             (p.field == ImageField::kPosition ? "position" : "radius") + ")";
  }
  return "";
}

// The monomials x^a y^b, 2 <= a + b <= 3, of the position field.
constexpr int kFieldPowers[7][2] = {{2, 0}, {1, 1}, {0, 2}, {3, 0}, {2, 1}, {1, 2}, {0, 3}};
// Powers of the radius along (4) and across (2) the radial direction.
constexpr int kRadialPowers[6] = {3, 5, 7, 9, 3, 5};

// Displacement [px] of image field column `k` at pixel `uv` of `cam`.
Eigen::Vector2d FieldColumn(const Probe& p, int k, const CameraTool& cam,
                            const Eigen::Vector2d& uv) {
  const double hw = 0.5 * cam.width, hh = 0.5 * cam.height;
  const double x = (uv.x() - hw) / hw, y = (uv.y() - hh) / hh;
  if (p.field == ImageField::kPosition) {
    const int m = k % 7;
    const double value = std::pow(x, kFieldPowers[m][0]) * std::pow(y, kFieldPowers[m][1]);
    return k < 7 ? Eigen::Vector2d(value, 0) : Eigen::Vector2d(0, value);
  }
  // Radius in pixels over the half-diagonal (1 at the corners).
  const Eigen::Vector2d d(uv.x() - hw, uv.y() - hh);
  const double rho = d.norm() / std::hypot(hw, hh);
  if (!(rho > 0)) return Eigen::Vector2d::Zero();
  const Eigen::Vector2d along = d / d.norm();
  const Eigen::Vector2d across(-along.y(), along.x());
  const double value = std::pow(rho, kRadialPowers[k]);
  return k < 4 ? Eigen::Vector2d(value * along) : Eigen::Vector2d(value * across);
}

// The value of a probe's variable at row `row`, NaN where the probe does
// not apply (harmonics: their own variable).
double ProbeValue(const Probe& p, const ResidualRow& row,
                  const std::vector<SessionVariable>& variables) {
  const bool pixel = row.group == ObsGroup::kPixel;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (p.kind == ProbeKind::kReadingTrend && p.reading == Reading::kDistance &&
      row.group != ObsGroup::kEdm) {
    return nan;
  }
  if (p.kind == ProbeKind::kImageField) return pixel ? 0.0 : nan;
  const SessionVariable& v = variables.at(p.session_variable);
  return pixel ? v.pixel.at(row.index) : v.record.at(row.index);
}

// Image-motion derivatives of one observation (whitened): columns scale,
// shift u, shift v, rotation; rows the observation's components.
using MotionDerivatives = Eigen::Matrix<double, 3, kNumImageMotions>;

// Probe columns in `extra` from `first_col` on: d r / d reading times the
// harmonic or trend functions, image motions times the trend functions,
// image fields (central differences of the model's predictions, cached per
// observation).
void AddProbeColumns(const Observations& obs, const InstrumentModel& model,
                     const std::vector<Probe>& probes, int first_col, Linearization* lin) {
  const std::vector<SessionVariable>& variables = lin->variables;
  bool need[3] = {false, false, false};
  bool motions = false;
  for (const Probe& p : probes) {
    if (p.kind == ProbeKind::kHarmonic || p.kind == ProbeKind::kReadingTrend) {
      need[static_cast<int>(p.reading)] = true;
    }
    motions = motions || p.kind == ProbeKind::kImageMotion;
  }
  std::vector<int> first(probes.size());
  std::vector<ColumnBlock*> blocks;
  int col = first_col;
  for (size_t k = 0; k < probes.size(); ++k) {
    const Probe& p = probes[k];
    ColumnBlock b;
    b.is_probe = true;
    b.probe = p;
    b.first = col;
    b.size = ProbeSize(p, variables);
    b.name = ProbeName(p, variables);
    for (int j = 0; j < b.size; ++j) {
      if (p.kind == ProbeKind::kHarmonic) {
        b.param_names.push_back(b.name + (j == 0 ? " [cos]" : " [sin]"));
      } else if (p.kind == ProbeKind::kImageMotion) {
        const int per = b.size / kNumImageMotions;
        b.param_names.push_back(b.name + " [" + kMotionNames[j / per] + " " +
                                std::to_string(j % per) + "]");
      } else {
        b.param_names.push_back(b.name + " [" + std::to_string(j) + "]");
      }
    }
    first[k] = col;
    col += b.size;
    lin->blocks.push_back(b);
  }

  // Trend functions over the rows each probe applies to.
  std::vector<TrendBasis> basis(probes.size());
  for (size_t k = 0; k < probes.size(); ++k) {
    const Probe& p = probes[k];
    if (p.kind != ProbeKind::kReadingTrend && p.kind != ProbeKind::kImageMotion) continue;
    TrendBasis& b = basis[k];
    b.form = p.form;
    b.size = TrendSize(p, variables);
    double sum = 0, lo = std::numeric_limits<double>::infinity(), hi = -lo;
    int n = 0;
    for (int i = 0; i < lin->NumRows(); ++i) {
      const ResidualRow& row = lin->rows[i];
      if (p.kind == ProbeKind::kImageMotion &&
          (row.group == ObsGroup::kEdm || ZoomOf(obs, row) != p.zoom)) {
        continue;
      }
      const double x = ProbeValue(p, row, variables);
      if (!std::isfinite(x)) continue;
      sum += p.form == TrendForm::kInverse ? 1.0 / x : x;
      lo = std::min(lo, x);
      hi = std::max(hi, x);
      ++n;
    }
    b.mean = n > 0 ? sum / n : 0.0;
    b.lo = n > 0 ? lo : 0.0;
    b.hi = n > 0 ? hi : 1.0;
    lin->blocks[lin->blocks.size() - probes.size() + k].basis = b;
  }

  // Where the model puts each image point (observed + sigma r, r = (model -
  // observed) / sigma): image motions and fields are evaluated there, not
  // at the observed pixel. At the observed one a column would carry the
  // point's own noise (a field's slope times the noise), which correlates
  // with the residual it is tested against; for a probe the fit nearly
  // absorbs (a radial field beside k1, k2, k3 keeps a few thousandths of
  // its norm) that part is all that is left, and pure noise would test as
  // structure.
  std::vector<Eigen::Vector2d> predicted(obs.pixels.size(), Eigen::Vector2d::Zero());
  for (int i = 0; i < lin->NumRows(); ++i) {
    const ResidualRow& row = lin->rows[i];
    if (row.group != ObsGroup::kPixel) continue;
    predicted[row.index][row.component] =
        obs.pixels[row.index].uv[row.component] +
        lin->r[i] * lin->sigma[static_cast<int>(ObsGroup::kPixel)];
  }

  // Per observation: reading derivatives and image motions (whitened).
  std::map<std::pair<int, int>, ReadingDerivatives> cache;  // (group kind != pixel, index)
  std::map<std::pair<int, int>, MotionDerivatives> motion_cache;
  std::map<int, std::array<InstrumentModel, 2 * kNumImageMotions>> moved;  // per zoom
  const std::vector<double> focus = PredictionFocusDistances(model, obs.pixels, &obs.targets);
  double f[kMaxTrendFunctions];
  for (int i = 0; i < lin->NumRows(); ++i) {
    const ResidualRow& row = lin->rows[i];
    const bool pixel = row.group == ObsGroup::kPixel;
    const double s = 1.0 / lin->sigma[static_cast<int>(row.group)];
    const std::pair<int, int> key{pixel ? 1 : 0, row.index};
    auto it = cache.find(key);
    if (it == cache.end()) {
      ReadingDerivatives d =
          pixel ? PixelDerivatives(model, obs.pixels[row.index], focus[row.index], need)
                : RecordDerivatives(model, obs.records[row.index], need);
      d.dphi *= s;
      d.dtheta *= s;
      d.dd *= s;
      it = cache.insert({key, d}).first;
    }
    const ReadingDerivatives& d = it->second;
    const MotionDerivatives* motion = nullptr;
    if (motions && row.group != ObsGroup::kEdm) {
      auto mt = motion_cache.find(key);
      if (mt == motion_cache.end()) {
        MotionDerivatives m = MotionDerivatives::Zero();
        const int zoom = ZoomOf(obs, row);
        if (pixel) {
          const CameraTool& cam = model.cams[zoom];
          const Eigen::Vector2d c(cam.intrinsics[2], cam.intrinsics[3]);
          const Eigen::Vector2d x = predicted[row.index] - c;
          m.block<2, 1>(0, 0) = x;
          m.block<2, 1>(0, 1) = Eigen::Vector2d(1, 0);
          m.block<2, 1>(0, 2) = Eigen::Vector2d(0, 1);
          m.block<2, 1>(0, 3) = Eigen::Vector2d(-x.y(), x.x());
        } else {
          auto mv = moved.find(zoom);
          if (mv == moved.end()) {
            std::array<InstrumentModel, 2 * kNumImageMotions> models;
            for (int k = 0; k < kNumImageMotions; ++k) {
              models[2 * k] = MovedImage(model, zoom, k, kMotionStep[k]);
              models[2 * k + 1] = MovedImage(model, zoom, k, -kMotionStep[k]);
            }
            mv = moved.emplace(zoom, std::move(models)).first;
          }
          const Record& r = obs.records[row.index];
          for (int k = 0; k < kNumImageMotions; ++k) {
            try {
              const Eigen::Vector3d a =
                  PredictCam(mv->second[2 * k], zoom, r.phi, r.theta, r.u, r.v, r.d);
              const Eigen::Vector3d b =
                  PredictCam(mv->second[2 * k + 1], zoom, r.phi, r.theta, r.u, r.v, r.d);
              m.col(k) = (a - b) / (2 * kMotionStep[k]);
            } catch (const std::exception&) {
              // Not evaluable: no column (the row's group was evaluable, so rare).
            }
          }
        }
        m *= s;
        mt = motion_cache.insert({key, m}).first;
      }
      motion = &mt->second;
    }
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
      const int c = first[k];
      const double deriv = p.reading == Reading::kPhi     ? d.dphi[row.component]
                           : p.reading == Reading::kTheta ? d.dtheta[row.component]
                                                          : d.dd[row.component];
      switch (p.kind) {
        case ProbeKind::kHarmonic: {
          if (p.face != row.face) break;
          if (p.variable == Reading::kDistance && row.group != ObsGroup::kEdm) break;
          const double x = p.harmonic * HarmonicVariable(p, phi, theta, dist,
                                                         model.edm_cyclic_unit_length);
          lin->extra(i, c) = deriv * std::cos(x);
          lin->extra(i, c + 1) = deriv * std::sin(x);
          break;
        }
        case ProbeKind::kReadingTrend: {
          const double x = ProbeValue(p, row, variables);
          if (!std::isfinite(x)) break;
          basis[k].Evaluate(x, f);
          const double scale = p.per_metre ? dist : 1.0;
          for (int j = 0; j < basis[k].size; ++j) lin->extra(i, c + j) = deriv * scale * f[j];
          break;
        }
        case ProbeKind::kImageMotion: {
          if (!motion || ZoomOf(obs, row) != p.zoom) break;
          const double x = ProbeValue(p, row, variables);
          if (!std::isfinite(x)) break;
          basis[k].Evaluate(x, f);
          const int per = basis[k].size;
          for (int m = 0; m < kNumImageMotions; ++m) {
            for (int j = 0; j < per; ++j) {
              lin->extra(i, c + m * per + j) = (*motion)(row.component, m) * f[j];
            }
          }
          break;
        }
        case ProbeKind::kImageField: {
          if (!pixel || ZoomOf(obs, row) != p.zoom) break;
          const CameraTool& cam = model.cams[p.zoom];
          const int size = p.field == ImageField::kPosition ? 14 : 6;
          for (int j = 0; j < size; ++j) {
            lin->extra(i, c + j) =
                s * FieldColumn(p, j, cam, predicted[row.index])[row.component];
          }
          break;
        }
      }
    }
  }
}

// Projects the local parameters' columns out of r, base and extra, block by
// block (LocalColumns): the boards and points whose rows overlap are one
// block, whose columns (scaled to unit norm) are orthonormalised by a
// pivoted QR; every row of the block then loses its part along them.
void ProjectLocal(const LocalJacobian& local, Linearization* lin) {
  const int n = lin->NumRows();
  lin->local.columns = static_cast<int>(local.unit.size());
  lin->local.leverage = Eigen::VectorXd::Zero(n);
  if (local.unit.empty()) return;
  // Units that share a row are one block (union-find over the units).
  const int units = 1 + *std::max_element(local.unit.begin(), local.unit.end());
  std::vector<int> parent(units);
  for (int u = 0; u < units; ++u) parent[u] = u;
  auto find = [&](int u) {
    while (parent[u] != u) u = parent[u] = parent[parent[u]];
    return u;
  };
  std::vector<int> unit_of_row(n, -1);
  for (size_t c = 0; c < local.unit.size(); ++c) {
    for (const auto& [row, value] : local.entries[c]) {
      int& u = unit_of_row[row];
      if (u < 0) {
        u = local.unit[c];
      } else {
        parent[find(u)] = find(local.unit[c]);
      }
    }
  }
  std::map<int, std::vector<int>> rows_of, cols_of;  // per block root
  for (int i = 0; i < n; ++i) {
    if (unit_of_row[i] >= 0) rows_of[find(unit_of_row[i])].push_back(i);
  }
  for (size_t c = 0; c < local.unit.size(); ++c) {
    if (!local.entries[c].empty()) cols_of[find(local.unit[c])].push_back(static_cast<int>(c));
  }
  for (const auto& [root, rows] : rows_of) {
    const std::vector<int>& cols = cols_of[root];
    std::map<int, int> at;  // row -> index within the block
    for (size_t k = 0; k < rows.size(); ++k) at[rows[k]] = static_cast<int>(k);
    Eigen::MatrixXd l = Eigen::MatrixXd::Zero(rows.size(), cols.size());
    for (size_t k = 0; k < cols.size(); ++k) {
      for (const auto& [row, value] : local.entries[cols[k]]) l(at[row], k) = value;
      const double norm = l.col(k).norm();
      if (norm > 0) l.col(k) /= norm;
    }
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(l);
    qr.setThreshold(1e-10);
    const int rank = static_cast<int>(qr.rank());
    if (rank == 0) continue;
    const Eigen::MatrixXd q =
        qr.householderQ() * Eigen::MatrixXd::Identity(l.rows(), rank);
    auto project = [&](auto& m) {
      Eigen::MatrixXd part = m(rows, Eigen::all);
      part -= q * (q.transpose() * part);
      m(rows, Eigen::all) = part;
    };
    project(lin->base);
    project(lin->extra);
    lin->local.leverage(rows) += q.rowwise().squaredNorm();
    lin->local.rank += rank;
    lin->local.blocks.push_back({rows, q});
  }
}

}  // namespace

void LocalColumns::Project(Eigen::Ref<Eigen::VectorXd> v) const {
  for (const Block& b : blocks) {
    Eigen::VectorXd part = v(b.rows);
    part -= b.q * (b.q.transpose() * part);
    v(b.rows) = part;
  }
}

void TrendBasis::Evaluate(double x, double* f) const {
  switch (form) {
    case TrendForm::kLinear:
      f[0] = x - mean;
      return;
    case TrendForm::kInverse:
      f[0] = 1.0 / x - mean;
      return;
    case TrendForm::kQuadratic: {
      const double t = hi > lo ? 2.0 * (x - lo) / (hi - lo) - 1.0 : 0.0;
      f[0] = t;
      f[1] = 0.5 * (3.0 * t * t - 1.0);
      return;
    }
    case TrendForm::kCategories:
      for (int c = 0; c < size; ++c) f[c] = static_cast<int>(x) == c ? 1.0 : 0.0;
      return;
  }
}

Linearization Linearize(const Observations& obs, const InstrumentModel& model,
                        const LinearizeOptions& options) {
  const std::string msg = options.fit.Check();
  if (!msg.empty()) throw std::invalid_argument(msg);
  Linearization lin;
  for (int g = 0; g < 3; ++g) lin.sigma[g] = options.sigma[g];
  lin.variables = options.variables;
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

  const Parameterization param(&work, options.fit,
                               options.facts ? *options.facts : FactsOf(obs, rows));
  const auto extra_col = CandidateColumns(param, options.candidates, zoom_used, &lin.blocks);
  const int num_candidate_cols =
      lin.blocks.empty() ? 0 : lin.blocks.back().first + lin.blocks.back().size;

  const std::vector<ClusteredGroup> groups =
      Cluster(obs, GroupObservations(obs, rows), &lin);
  ceres::Problem::Options popt;
  popt.manifold_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(popt);
  const std::vector<ceres::ResidualBlockId> residual_ids =
      AddResiduals(obs, groups, param, &work, &problem, &lin);
  if (residual_ids.empty()) {
    throw std::invalid_argument("nothing to diagnose: no observation outside the critical regions");
  }

  const std::vector<const BlockDecision*> free_blocks = param.Apply(&problem, false);
  int num_probe_cols = 0;
  for (const Probe& p : options.probes) num_probe_cols += ProbeSize(p, options.variables);
  LocalJacobian local;
  EvaluateColumns(&problem, residual_ids, free_blocks, extra_col,
                  options.local_as_base ? std::map<const double*, int>() : LocalUnits(&work),
                  num_candidate_cols + num_probe_cols, options.fit.num_threads, &lin, &local);
  // The probes' derivatives need every point's position: the estimated
  // boards' corners where the pixels leave them empty.
  if (!options.probes.empty()) {
    AddProbeColumns(WithEstimates(obs, model), model, options.probes, num_candidate_cols, &lin);
  }
  lin.extra_norm = lin.extra.colwise().norm().transpose();
  ProjectLocal(local, &lin);
  return lin;
}

Reduced Reduce(const Linearization& lin) {
  const int n = lin.NumRows();
  Reduced red(n);
  red.base.Add(lin.base, 1e-9);
  red.local_rank = lin.local.rank;
  Eigen::VectorXd r = lin.r;
  lin.local.Project(r);
  red.r = red.base.Apply(r);
  red.extra = red.base.Apply(lin.extra);
  red.cluster.resize(n);
  for (int i = 0; i < n; ++i) red.cluster[i] = lin.rows[i].cluster;
  const int m = static_cast<int>(lin.extra.cols());
  red.kept_fraction = Eigen::VectorXd::Zero(m);
  red.column_norm = Eigen::VectorXd::Zero(m);
  for (int j = 0; j < m; ++j) {
    red.column_norm[j] = j < lin.extra_norm.size() ? lin.extra_norm[j] : lin.extra.col(j).norm();
    if (red.column_norm[j] > 0) red.kept_fraction[j] = red.extra.col(j).norm() / red.column_norm[j];
  }
  return red;
}

}  // namespace rtscalib

#include "libcalib/plan/planner.h"

#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>

#include "libcalib/diagnose/linearization.h"
#include "libcalib/fit/parameterization.h"
#include "libcalib/model/effects.h"
#include "libcalib/model/kinematics.h"
#include "libcalib/plan/shot_order.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Eigenvalues of the Jacobi-scaled information of every candidate and the
// fixed data below this fraction of the largest are directions the targets
// cannot determine (the fit's TangentCovariance drops 1e-14 of a single
// session; a plan claims less: 1e-10 leaves round-off of the summed
// candidates well clear).
constexpr double kRankTolerance = 1e-10;
// The greedy steps' information gets this much of the identity (in the
// scaled, determined coordinates, where the whole pool's eigenvalues are
// >= kRankTolerance of the largest, ~1): a direction no chosen shot has seen
// yet has variance 1e8 and its goals pull hardest.
constexpr double kRidge = 1e-8;
// Candidates evaluated exactly per greedy step (of the largest first-order
// reduction).
constexpr int kShortlist = 12;

std::string UnitOfColumn(const FreeColumn& c) {
  const std::string& n = c.name;
  if (n.find(".rotation[") != std::string::npos) return "rad";
  if (n.find(".t[") != std::string::npos) return "m";
  if (n.find(".fx") != std::string::npos || n.find(".fy") != std::string::npos ||
      n.find(".cx") != std::string::npos || n.find(".cy") != std::string::npos)
    return "px";
  if (n.rfind("link", 0) == 0) return n.find(".a") == n.size() - 2 ? "m" : "rad";
  if (c.effect && *c.effect == Effect::kFocus)
    return n.find(".kf") != std::string::npos ? "m" : "px m";
  return "1";
}

// Local parameters (boards, points, board warps): the session's own, not
// constants of the instrument.
bool IsNuisance(const FreeColumn& c) {
  return c.name.rfind("board", 0) == 0 || c.name.rfind("point[", 0) == 0;
}

// A linear functional of the parameters with what it stands for.
struct Functional {
  std::string name;
  Eigen::VectorXd g;  // gradient, original units, divided by the goal when there is one
  int constant = -1;  // index into the constants, or -1 (projection cells)
  int zoom = -1;      // projection cells: the zoom
  int cell = -1;      // projection cells: cell index (two functionals per cell)
};

struct Factor {
  Eigen::MatrixXd l;  // q x r, l l^T = the candidate's information (reduced coordinates)
};

// Information of rows `rows` of `j` (n x p).
Eigen::MatrixXd Information(const Eigen::MatrixXd& j, const std::vector<int>& rows) {
  if (rows.empty()) return Eigen::MatrixXd::Zero(j.cols(), j.cols());
  const Eigen::MatrixXd part = j(rows, Eigen::all);
  return part.transpose() * part;
}

// l with l l^T = m (m symmetric positive semi-definite), columns of the
// eigenvalues above a tiny fraction of the largest.
Eigen::MatrixXd FactorOf(const Eigen::MatrixXd& m) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(m);
  const Eigen::VectorXd& lambda = eig.eigenvalues();
  const double top = lambda.size() ? lambda[lambda.size() - 1] : 0.0;
  std::vector<int> keep;
  for (int i = 0; i < lambda.size(); ++i) {
    if (lambda[i] > 1e-13 * top && lambda[i] > 0) keep.push_back(i);
  }
  Eigen::MatrixXd l(m.rows(), keep.size());
  for (size_t k = 0; k < keep.size(); ++k) {
    l.col(k) = eig.eigenvectors().col(keep[k]) * std::sqrt(lambda[keep[k]]);
  }
  return l;
}

// sqrt(lambda_max) of a 2x2 symmetric matrix.
double WorstSigma(double a, double b, double d) {
  const double mean = 0.5 * (a + d);
  const double r = std::sqrt(0.25 * (a - d) * (a - d) + b * b);
  return std::sqrt(std::max(mean + r, 0.0));
}

}  // namespace

std::string PlanOptions::Check() const {
  if (max_shots < 0) return "plan.max_shots: expected an integer >= 0";
  if (candidates_per_board < 1) return "plan.candidates_per_board: expected an integer >= 1";
  if (!(fill > 0 && fill <= 1)) return "plan.fill: expected a number in (0, 1]";
  if (faces.empty()) return "plan.faces: expected a non-empty list of 1 and/or 2";
  for (int f : faces) {
    if (f != 1 && f != 2) return "plan.faces: expected 1 or 2, got " + std::to_string(f);
  }
  for (int z : zooms) {
    if (z < 0) return "plan.zooms: expected zoom levels >= 0, got " + std::to_string(z);
  }
  for (const auto& [name, sigma] : goal.sigmas) {
    if (!(sigma > 0)) return "plan.goal.sigmas." + name + ": expected a sigma > 0";
  }
  if (goal.projection_px < 0) return "plan.goal.projection_px: expected a number >= 0";
  return projection.Check();
}

namespace {

// `m` as a camera on its own: no kinematics, its frame the reference
// (IdealModel's base and camera tool).
InstrumentModel CameraOnItsOwn(InstrumentModel m) {
  m.kinematics = Kinematics::kNone;
  m.base = PoseBlock();
  for (CameraTool& cam : m.cams) cam.flange_from_cam = PoseBlock();
  return m;
}

}  // namespace

InstrumentModel PlanningModel(const PlanSession& session) {
  const ModelSettings& ms = session.calibration.model;
  InstrumentModel m = session.prior;
  m.kinematics = ms.kinematics;
  m.edm_cyclic_unit_length = ms.edm_cyclic_unit_length;
  EffectSet effects;
  for (Effect e : ms.effects.List()) {
    effects.Add(e);
    if (IsKinematic(e) && !session.prior.effects.Has(e)) m.EffectValue(e) = {0.0, 0.0};
  }
  for (Effect e : session.prior.effects.List()) {
    // An effect of the prior that will not be estimated is left out of the
    // planning model: its value is part of the truth, not of the design.
    if (IsKinematic(e) && !effects.Has(e)) m.EffectValue(e) = {0.0, 0.0};
  }
  m.effects = effects;
  if (m.kinematics == Kinematics::kNone) m = CameraOnItsOwn(m);
  if (m.effects.Has(Effect::kFocus) && !session.prior.effects.Has(Effect::kFocus)) {
    for (CameraTool& cam : m.cams) cam.focus.fill(0.0);
  }
  RemoveContainedEffects(&m);
  HoldDistortion(ms.distortion_choices, ms.cameras, &m);
  m.boards.clear();
  if (!session.board_poses_known) {
    for (const auto& [placement, scene] : session.scenes) {
      for (const TagBoard& b : scene.boards) {
        EstimatedBoard eb;
        eb.board = b;
        eb.board.pose_known = false;
        eb.placement = placement;
        eb.pose = PoseBlock::FromRigid(b.ref_from_board);
        m.boards.push_back(eb);
      }
    }
  }
  SyncBoardWarps(&m);
  m.sigmas = {};
  return m;
}

namespace {

// The session's first board (a camera on its own plans its poses), or null.
const TagBoard* FirstBoard(const PlanSession& session) {
  for (const auto& [placement, scene] : session.scenes) {
    if (!scene.boards.empty()) return &scene.boards.front();
  }
  return nullptr;
}

// The scene of a board held at `cam_from_board`, its pose to be estimated.
TargetScene HeldBoard(const TagBoard& board, const Rigid3& cam_from_board) {
  TargetScene scene;
  scene.boards.push_back(board);
  scene.boards.back().ref_from_board = cam_from_board;
  scene.boards.back().pose_known = false;
  return scene;
}

// The scenes `shots` are taken of: the session's, and for a shot with a
// board pose (a camera on its own) its own placement with the session's
// first board there, in place of the session's board placements that no
// shot uses.
PlacedScenes ScenesOfShots(const PlanSession& session, const std::vector<PlanShot>& shots) {
  PlacedScenes out;
  std::set<std::string> used;
  bool posed = false;
  for (const PlanShot& s : shots) {
    used.insert(s.pointing.placement);
    if (!s.board_pose) continue;
    posed = true;
    const TagBoard* board = FirstBoard(session);
    if (!board) throw std::invalid_argument("SimulatePlannedShots: a board pose without a board");
    out[s.pointing.placement] = HeldBoard(*board, s.cam_from_board);
  }
  for (const auto& [placement, scene] : session.scenes) {
    if (!posed || used.count(placement)) out.emplace(placement, scene);
  }
  return out;
}

}  // namespace

Observations SimulatePlannedShots(const PlanSession& session, const std::vector<PlanShot>& shots,
                                  double pixel_sigma_px, std::uint64_t seed) {
  SimulationOptions sim;
  sim.seed = seed;
  sim.truth = session.prior;
  sim.noise.pixel_px = pixel_sigma_px;
  sim.plan.sweeps = false;
  sim.plan.grid_phi_steps = 0;
  sim.plan.grid_theta_steps = 0;
  std::set<int> faces, zooms;
  for (const PlanShot& s : shots) {
    sim.shots.given.push_back(s.pointing);
    faces.insert(s.pointing.face);
    zooms.insert(s.pointing.zoom);
  }
  sim.plan.faces.assign(faces.begin(), faces.end());
  sim.plan.zooms.assign(zooms.begin(), zooms.end());
  const PlacedScenes scenes = ScenesOfShots(session, shots);
  if (scenes.size() == 1 && scenes.begin()->first.empty()) {
    sim.targets = scenes.begin()->second;
  } else {
    sim.placements = scenes;
  }
  // Board poses are in the camera's frame: the truth as a camera on its own.
  const bool posed =
      std::any_of(shots.begin(), shots.end(), [](const PlanShot& s) { return s.board_pose; });
  if (posed) sim.truth = CameraOnItsOwn(sim.truth);
  Observations obs = Simulate(sim).obs;
  if (!session.board_poses_known || posed) {
    for (PixelObservation& p : obs.pixels) {
      p.X_known = false;  // the corner's position is the estimated board's
      p.X.setZero();
    }
    for (const auto& [placement, scene] : scenes) {
      for (TagBoard b : scene.boards) {
        b.pose_known = false;
        bool seen = false;
        for (const TagBoard& t : obs.targets.boards) seen = seen || t.first_id == b.first_id;
        if (!seen) obs.targets.boards.push_back(b);
      }
    }
  }
  return obs;
}

namespace {

// The candidate pool: the simulator's pattern, dense and without jitter, at
// the planning model, noise-free.
// A camera on its own: one photo per candidate pose (`poses`), face 1;
// a chessboard's photo only where the board is whole in it (OpenCV finds
// no part of one).
Observations CandidatePixels(const PlanSession& session, const InstrumentModel& model,
                             const PlanOptions& o, const std::vector<int>& zooms,
                             const std::map<std::string, CandidatePose>& poses) {
  SimulationOptions sim;
  sim.truth = model;
  sim.plan.sweeps = false;
  sim.plan.grid_phi_steps = 0;
  sim.plan.grid_theta_steps = 0;
  sim.plan.faces = o.faces;
  sim.plan.zooms = zooms;
  sim.shots.shots_per_board = o.candidates_per_board;
  sim.shots.fill = o.fill;
  sim.shots.pointing_jitter = 0;
  if (!poses.empty()) {
    sim.plan.faces = {1};
    for (const auto& [placement, pose] : poses) {
      PlannedShot shot;
      shot.zoom = pose.zoom;
      shot.theta = M_PI / 2;
      shot.placement = placement;
      shot.name = placement;
      sim.shots.given.push_back(shot);
      sim.placements[placement] = session.scenes.at(placement);
    }
  } else if (session.scenes.size() == 1 && session.scenes.begin()->first.empty()) {
    sim.targets = session.scenes.begin()->second;
  } else {
    sim.placements = session.scenes;
  }
  Observations obs = Simulate(sim).obs;
  if (!poses.empty() && FirstBoard(session)->kind == BoardKind::kChessboard) {
    std::map<std::string, int> shown;
    for (const PixelObservation& p : obs.pixels) ++shown[p.shot];
    const int whole = FirstBoard(session)->NumTags();
    obs.pixels.erase(
        std::remove_if(obs.pixels.begin(), obs.pixels.end(),
                       [&](const PixelObservation& p) { return shown[p.shot] < whole; }),
        obs.pixels.end());
  }
  for (PixelObservation& p : obs.pixels) {
    p.X_known = session.board_poses_known;
    p.shot = "candidate " + p.shot;
  }
  return obs;
}

struct Pool {
  std::vector<PlanShot> shots;
  std::vector<std::vector<int>> rows;  // per candidate: rows of the linearisation
  std::vector<int> fixed_rows;
};

}  // namespace

PlanResult PlanShots(const PlanSession& given, const PlanOptions& o) {
  const std::string msg = o.Check();
  if (!msg.empty()) throw std::invalid_argument(msg);
  std::vector<int> zooms = o.zooms;
  if (zooms.empty()) {
    for (int z = 0; z < given.prior.NumZooms(); ++z) zooms.push_back(z);
  }
  for (int z : zooms) {
    if (z >= given.prior.NumZooms()) {
      throw std::invalid_argument("plan.zooms: zoom " + std::to_string(z) +
                                  " is not in the a-priori model (it has " +
                                  std::to_string(given.prior.NumZooms()) + " zoom levels)");
    }
  }
  // A camera on its own: the board's candidate poses, each a placement; of
  // the session's own placements those of the photos it has (an earlier
  // run's) stay, the rest only lent their board.
  const bool camera_only = given.calibration.model.kinematics == Kinematics::kNone;
  PlanSession session = given;
  std::map<std::string, CandidatePose> poses;
  if (camera_only) {
    const TagBoard* board = FirstBoard(given);
    if (!board) {
      throw std::invalid_argument(
          "plan: a camera on its own plans where a board is held: the session has no board");
    }
    const InstrumentModel camera = PlanningModel(given);
    std::set<std::string> measured;
    for (const PixelObservation& p : given.fixed.pixels) measured.insert(p.placement);
    for (auto it = session.scenes.begin(); it != session.scenes.end();) {
      it = measured.count(it->first) ? std::next(it) : session.scenes.erase(it);
    }
    session.fixed.records.clear();  // a camera on its own has no readings to record
    session.board_poses_known = false;
    for (int z : zooms) {
      for (CandidatePose& c : CandidateBoardPoses(camera, z, *board)) {
        session.scenes[c.placement] = HeldBoard(*board, c.cam_from_board);
        poses[c.placement] = c;
      }
    }
  }
  const InstrumentModel model = PlanningModel(session);
  FitOptions fit = session.calibration.fit;
  fit.fit_intrinsics = session.calibration.model.intrinsics != IntrinsicsMode::kFixed;

  // Observations: the fixed ones, then every candidate photo.
  Observations all = session.fixed;
  const size_t fixed_pixels = all.pixels.size();
  const Observations candidates = CandidatePixels(session, model, o, zooms, poses);
  all.pixels.insert(all.pixels.end(), candidates.pixels.begin(), candidates.pixels.end());
  if (candidates.pixels.empty() && session.fixed.records.empty() && fixed_pixels == 0) {
    throw std::invalid_argument(
        "plan: no candidate photo shows 8 corners of a board: check the targets' sizes and "
        "distances against the zooms' fields of view");
  }
  LinearizeOptions lo;
  lo.fit = fit;
  lo.sigma[0] = fit.sigma_edm_m;
  lo.sigma[1] = fit.sigma_cam_m;
  lo.sigma[2] = fit.sigma_pixel_px;
  lo.local_as_base = true;
  const Linearization lin = Linearize(all, model, lo);
  const int p = static_cast<int>(lin.base.cols());

  // Rows per candidate (by shot name), the rest fixed.
  Pool pool;
  std::map<std::string, int> candidate_of;
  for (size_t i = fixed_pixels; i < all.pixels.size(); ++i) {
    const PixelObservation& px = all.pixels[i];
    auto it = candidate_of.find(px.shot);
    if (it == candidate_of.end()) {
      PlanShot s;
      s.pointing.face = px.face;
      s.pointing.zoom = px.zoom;
      // The reading as the instrument gives it, in [0, 2 pi) (SPEC 1).
      s.pointing.phi = std::fmod(px.phi, 2.0 * M_PI);
      if (s.pointing.phi < 0) s.pointing.phi += 2.0 * M_PI;
      s.pointing.theta = px.theta;
      s.pointing.placement = px.placement;
      s.focus_distance = px.focus_distance;
      if (const auto pose = poses.find(px.placement); pose != poses.end()) {
        s.pointing.phi = 0;  // a camera on its own: no reading
        s.board_pose = true;
        s.cam_from_board = pose->second.cam_from_board;
        s.board = pose->second.words;
        s.board_outline = BoardOutline(model, px.zoom, *FirstBoard(session), s.cam_from_board);
      }
      it = candidate_of.insert({px.shot, static_cast<int>(pool.shots.size())}).first;
      pool.shots.push_back(s);
      pool.rows.emplace_back();
    }
    ++pool.shots[it->second].points;
  }
  for (int i = 0; i < lin.NumRows(); ++i) {
    const ResidualRow& row = lin.rows[i];
    if (row.group == ObsGroup::kPixel && row.index >= static_cast<int>(fixed_pixels)) {
      pool.rows[candidate_of.at(all.pixels[row.index].shot)].push_back(i);
    } else {
      pool.fixed_rows.push_back(i);
    }
  }
  const int n_cand = static_cast<int>(pool.shots.size());

  // Information: fixed and per candidate, Jacobi-scaled by the whole pool.
  const Eigen::MatrixXd info_fixed = Information(lin.base, pool.fixed_rows);
  std::vector<Eigen::MatrixXd> info(n_cand);
  Eigen::MatrixXd info_all = info_fixed;
  // A camera on its own: a candidate's board pose is its own placement's,
  // estimated from that photo alone, so what the photo tells of the rest
  // is its information with the pose eliminated (the Schur complement,
  // exact); the pose columns are then empty and drop out of the design as
  // undetermined directions that no goal asks for, which keeps its size to
  // the camera's parameters (and the poses of photos taken already).
  std::map<std::string, std::vector<int>> pose_columns;  // placement -> its board's columns
  if (camera_only) {
    for (int j = 0; j < p; ++j) {
      const std::string& name = lin.base_names[j];
      const size_t at = name.find('@');
      if (name.rfind("board[", 0) != 0 || at == std::string::npos) continue;
      const size_t end = name.find_first_of("/]", at);
      pose_columns[name.substr(at + 1, end - at - 1)].push_back(j);
    }
  }
  for (int c = 0; c < n_cand; ++c) {
    info[c] = Information(lin.base, pool.rows[c]);
    const auto own = pose_columns.find(pool.shots[c].pointing.placement);
    if (own != pose_columns.end() && pool.shots[c].board_pose) {
      const std::vector<int>& k = own->second;
      const Eigen::MatrixXd b = info[c](Eigen::all, k);
      const Eigen::MatrixXd pose = info[c](k, k);
      info[c] -= b * pose.completeOrthogonalDecomposition().pseudoInverse() * b.transpose();
      info[c](Eigen::all, k).setZero();
      info[c](k, Eigen::all).setZero();
    }
    info_all += info[c];
  }
  Eigen::VectorXd scale(p);
  for (int j = 0; j < p; ++j) scale[j] = info_all(j, j) > 0 ? 1.0 / std::sqrt(info_all(j, j)) : 0.0;
  const Eigen::MatrixXd scaled_all = scale.asDiagonal() * info_all * scale.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig_all(scaled_all);
  std::vector<int> range_cols;
  const double top = eig_all.eigenvalues()[p - 1];
  for (int i = 0; i < p; ++i) {
    if (eig_all.eigenvalues()[i] > kRankTolerance * top) range_cols.push_back(i);
  }
  // Reduced coordinates: x_red = U^T S^-1 x; a functional g becomes U^T S g.
  const Eigen::MatrixXd u = eig_all.eigenvectors()(Eigen::all, range_cols);
  const Eigen::MatrixXd to_red = u.transpose() * scale.asDiagonal();  // q x p, applied to g
  const int q = static_cast<int>(range_cols.size());
  auto reduce = [&](const Eigen::MatrixXd& m) { return to_red * m * to_red.transpose(); };
  const Eigen::MatrixXd red_fixed = reduce(info_fixed);
  std::vector<Factor> factor(n_cand);
  for (int c = 0; c < n_cand; ++c) factor[c].l = FactorOf(reduce(info[c]));
  // The part of a functional in the undetermined directions (relative).
  auto undetermined_fraction = [&](const Eigen::VectorXd& g) {
    const Eigen::VectorXd sg = scale.asDiagonal() * g;
    const double n = sg.norm();
    if (n == 0) return 1.0;
    return std::sqrt(std::max(0.0, 1.0 - (u.transpose() * sg).squaredNorm() / (n * n)));
  };

  // Constants: every instrument column, and the effects in report units.
  PlanResult result;
  result.candidates = n_cand;
  result.fixed_observations = lin.num_observations[0] + lin.num_observations[1];
  std::vector<Functional> constants;
  std::map<std::string, int> column_of;
  for (int j = 0; j < p; ++j) column_of[lin.base_names[j]] = j;
  for (Effect e : model.effects.List()) {
    if (!IsKinematic(e)) continue;
    const EffectInfo& info_e = Info(e);
    std::array<int, 2> cols{-1, -1};
    for (int j = 0; j < p; ++j) {
      const FreeColumn& c = lin.base_columns[j];
      if (c.effect == e && c.index < 2) cols[c.index] = j;
    }
    if (cols[0] < 0) continue;
    const std::array<double, 2> si = model.EffectValue(e);
    const std::array<double, 4> zero{};
    for (int k = 0; k < info_e.num_params; ++k) {
      Functional f;
      f.name = std::string(info_e.name) + "." + info_e.param_names[k];
      f.g = Eigen::VectorXd::Zero(p);
      for (int j = 0; j < info_e.num_params; ++j) {
        if (cols[j] < 0) continue;
        const double h = 1e-7 * std::max(std::abs(si[j]), 1e-6);
        std::array<double, 2> a = si, b = si;
        a[j] += h;
        b[j] -= h;
        f.g[cols[j]] =
            (ToReportUnits(e, a, zero).value[k] - ToReportUnits(e, b, zero).value[k]) / (2 * h);
      }
      if (!f.g.allFinite()) continue;  // a phase at zero amplitude
      f.constant = static_cast<int>(result.constants.size());
      PredictedConstant pc;
      pc.name = f.name;
      pc.unit = info_e.report_units[k];
      result.constants.push_back(pc);
      constants.push_back(f);
    }
  }
  for (int j = 0; j < p; ++j) {
    const FreeColumn& c = lin.base_columns[j];
    if (IsNuisance(c) || (c.effect && IsKinematic(*c.effect))) continue;
    Functional f;
    f.name = c.name;
    f.g = Eigen::VectorXd::Unit(p, j);
    f.constant = static_cast<int>(result.constants.size());
    PredictedConstant pc;
    pc.name = c.name;
    pc.unit = UnitOfColumn(c);
    result.constants.push_back(pc);
    constants.push_back(f);
  }
  // Free parameters that no observation of the pool touches at all (an EDM
  // effect in a session without EDM rows): estimated, never determined.
  std::set<std::string> absent;
  {
    InstrumentModel copy = model;
    const Parameterization param(
        &copy, fit, FactsOf(all, SelectRows(all, fit, model.NumZooms(), UnknownZoom::kSkip)));
    std::set<Effect> listed;
    for (const BlockDecision& d : param.Blocks()) {
      for (const FreeColumn& c : d.columns) {
        if (column_of.count(c.name) || IsNuisance(c)) continue;
        std::vector<std::pair<std::string, std::string>> names;  // name, unit
        if (c.effect && IsKinematic(*c.effect)) {
          if (!listed.insert(*c.effect).second) continue;
          const EffectInfo& ie = Info(*c.effect);
          for (int k = 0; k < ie.num_params; ++k)
            names.push_back({std::string(ie.name) + "." + ie.param_names[k], ie.report_units[k]});
        } else {
          names.push_back({c.name, UnitOfColumn(c)});
        }
        for (const auto& [name, unit] : names) {
          PredictedConstant pc;
          pc.name = name;
          pc.unit = unit;
          pc.determined = false;
          absent.insert(name);
          result.constants.push_back(pc);
        }
      }
    }
  }
  // Goals on constants.
  std::vector<Functional> goals;
  std::vector<std::string> unreachable;  // goals on constants no observation touches
  for (const auto& [name, sigma] : o.goal.sigmas) {
    int found = -1;
    for (size_t k = 0; k < constants.size(); ++k) {
      if (constants[k].name == name) found = static_cast<int>(k);
    }
    if (found < 0 && absent.count(name)) {
      for (PredictedConstant& pc : result.constants) {
        if (pc.name == name) pc.goal = sigma;
      }
      unreachable.push_back(name);
      continue;
    }
    if (found < 0) {
      std::string valid;
      for (size_t k = 0; k < constants.size() && k < 40; ++k)
        valid += (k ? ", " : "") + constants[k].name;
      throw std::invalid_argument("plan.goal.sigmas." + name +
                                  ": not a constant this model estimates; expected one of " +
                                  valid + (constants.size() > 40 ? ", ..." : ""));
    }
    result.constants[found].goal = sigma;
    Functional f = constants[found];
    f.g /= sigma;
    goals.push_back(f);
  }
  // Projection: d pixel / d parameters on the map's grid, per zoom, from the
  // same linearisation of points at the map's range (the session's facts,
  // so that the same blocks are free).
  std::vector<Functional> cells;
  {
    Observations grid;
    std::vector<int> point_of_cell;  // per functional: its point in `grid`
    for (int z : zooms) {
      // The uncertainty map's own grid (its cell centres, SPEC 2's pixel centre).
      UncertaintyMap map;
      map.cols = o.projection.cols;
      map.rows = o.projection.rows;
      map.width = model.cams[z].width;
      map.height = model.cams[z].height;
      for (int r = 0; r < o.projection.rows; ++r) {
        for (int col = 0; col < o.projection.cols; ++col) {
          const double uu = map.CellU(col);
          const double vv = map.CellV(r);
          PixelObservation px;
          px.face = 1;
          px.zoom = z;
          px.phi = o.projection.phi;
          px.theta = o.projection.theta;
          px.shot = "grid " + std::to_string(z) + " " + std::to_string(r * o.projection.cols + col);
          px.target = r * o.projection.cols + col;
          try {
            px.X = PredictCam(model, z, px.phi, px.theta, uu, vv, o.projection.range_m);
          } catch (const std::exception&) {
            continue;  // outside the trusted region: no value, as in the maps
          }
          px.uv = Eigen::Vector2d(uu, vv);
          px.X_known = true;
          grid.pixels.push_back(px);
        }
      }
    }
    if (!grid.pixels.empty()) {
      LinearizeOptions go = lo;
      go.sigma[2] = 1.0;  // rows in pixels
      go.facts = FactsOf(all, SelectRows(all, fit, model.NumZooms(), UnknownZoom::kSkip));
      const Linearization gl = Linearize(grid, model, go);
      std::vector<int> to_col(gl.base.cols(), -1);
      for (int j = 0; j < gl.base.cols(); ++j) {
        const auto it = column_of.find(gl.base_names[j]);
        if (it != column_of.end()) to_col[j] = it->second;
      }
      for (int i = 0; i < gl.NumRows(); ++i) {
        const ResidualRow& row = gl.rows[i];
        const PixelObservation& px = grid.pixels[row.index];
        Functional f;
        f.zoom = px.zoom;
        f.cell = px.target;
        f.name = "projection zoom " + std::to_string(px.zoom);
        f.g = Eigen::VectorXd::Zero(p);
        for (int j = 0; j < gl.base.cols(); ++j) {
          if (to_col[j] >= 0) f.g[to_col[j]] = gl.base(i, j);
        }
        if (o.goal.projection_px > 0) f.g /= o.goal.projection_px;
        cells.push_back(f);
        point_of_cell.push_back(row.index);
      }
    }
    if (camera_only) {
      // Up to the camera's rotation, as its uncertainty map (over every
      // cell: where the photos will fall is what is being planned).
      for (int z : zooms) {
        std::vector<size_t> first;  // functionals k, k + 1: one grid point's u and v
        std::vector<Eigen::Matrix<double, 2, 3>> by_rotation;
        for (size_t k = 0; k + 1 < cells.size(); k += 2) {
          if (cells[k].zoom != z) continue;
          const PixelObservation& px = grid.pixels[point_of_cell[k]];
          first.push_back(k);
          by_rotation.push_back(PixelByRotation(model, z, px.phi, px.theta, px.X));
        }
        Eigen::MatrixXd g(2 * first.size(), p);
        for (size_t i = 0; i < first.size(); ++i) {
          g.row(2 * i) = cells[first[i]].g.transpose();
          g.row(2 * i + 1) = cells[first[i] + 1].g.transpose();
        }
        TakeOutRotation(by_rotation, {}, &g);
        for (size_t i = 0; i < first.size(); ++i) {
          cells[first[i]].g = g.row(2 * i).transpose();
          cells[first[i] + 1].g = g.row(2 * i + 1).transpose();
        }
      }
    }
  }
  // Reduced functionals.
  auto red = [&](const std::vector<Functional>& fs) {
    Eigen::MatrixXd g(q, fs.size());
    for (size_t k = 0; k < fs.size(); ++k) g.col(k) = to_red * fs[k].g;
    return g;
  };
  const Eigen::MatrixXd g_goals = red(goals);
  const Eigen::MatrixXd g_cells = red(cells);
  const Eigen::MatrixXd g_consts = red(constants);

  // Goal state at an information matrix (reduced, without the ridge): the
  // ratios sigma / goal of each goal and the worst cell per zoom.
  auto covariance = [&](const Eigen::MatrixXd& m, double ridge) {
    Eigen::MatrixXd a = m;
    a.diagonal().array() += ridge;
    return Eigen::LLT<Eigen::MatrixXd>(a).solve(Eigen::MatrixXd::Identity(q, q)).eval();
  };
  // The covariance a fit of the information `a` reports (the
  // pseudo-inverse, as TangentCovariance), with the directions `a` does not
  // determine yet: a goal with a part there is not met.
  struct Pseudo {
    Eigen::MatrixXd cov, null;
  };
  auto exact = [&](const Eigen::MatrixXd& a) {
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> e(a);
    const double t = q ? e.eigenvalues()[q - 1] : 0.0;
    Eigen::VectorXd d = Eigen::VectorXd::Zero(q);
    std::vector<int> nd;
    for (int i = 0; i < q; ++i) {
      if (e.eigenvalues()[i] > kRankTolerance * t) {
        d[i] = 1.0 / e.eigenvalues()[i];
      } else {
        nd.push_back(i);
      }
    }
    Pseudo out;
    out.cov = e.eigenvectors() * d.asDiagonal() * e.eigenvectors().transpose();
    out.null = e.eigenvectors()(Eigen::all, nd);
    return out;
  };
  auto in_null = [](const Pseudo& ps, const Eigen::VectorXd& g) {
    return ps.null.cols() > 0 && (ps.null.transpose() * g).norm() > 1e-6 * g.norm();
  };
  auto unmet = [&](const Pseudo& ps, std::vector<char>* goal_unmet, std::vector<char>* cell_unmet) {
    const Eigen::MatrixXd& cov = ps.cov;
    bool any = false;
    goal_unmet->assign(goals.size(), 0);
    cell_unmet->assign(cells.size(), 0);
    for (size_t k = 0; k < goals.size(); ++k) {
      const double v = g_goals.col(k).dot(cov * g_goals.col(k));
      (*goal_unmet)[k] = !(v <= 1.0) || in_null(ps, g_goals.col(k));
      any = any || (*goal_unmet)[k];
    }
    if (o.goal.projection_px > 0) {
      for (size_t k = 0; k + 1 < cells.size(); k += 2) {
        const Eigen::VectorXd pa = cov * g_cells.col(k), pb = cov * g_cells.col(k + 1);
        const double s =
            WorstSigma(g_cells.col(k).dot(pa), g_cells.col(k).dot(pb), g_cells.col(k + 1).dot(pb));
        if (!(s <= 1.0) || in_null(ps, g_cells.col(k)) || in_null(ps, g_cells.col(k + 1))) {
          (*cell_unmet)[k] = (*cell_unmet)[k + 1] = 1;
          any = true;
        }
      }
    }
    return any;
  };
  // Undetermined goals: no number of these shots reaches them.
  std::vector<char> goal_possible(goals.size(), 1);
  for (size_t k = 0; k < goals.size(); ++k) {
    if (undetermined_fraction(goals[k].g) > 1e-6) goal_possible[k] = 0;
  }
  const bool no_goal = o.goal.Empty();
  Eigen::MatrixXd m = red_fixed;
  std::vector<char> chosen(n_cand, 0);
  std::vector<int> order;
  auto log_det = [&](const Eigen::MatrixXd& a) {
    Eigen::MatrixXd b = a;
    b.diagonal().array() += kRidge;
    const Eigen::LLT<Eigen::MatrixXd> llt(b);
    return 2.0 * llt.matrixLLT().diagonal().array().log().sum();
  };
  // Phi over every goal functional (A) at cov.
  auto phi_all = [&](const Eigen::MatrixXd& cov) {
    double s = 0;
    for (int k = 0; k < g_goals.cols(); ++k) s += g_goals.col(k).dot(cov * g_goals.col(k));
    if (o.goal.projection_px > 0) {
      for (int k = 0; k < g_cells.cols(); ++k) s += g_cells.col(k).dot(cov * g_cells.col(k));
    }
    return s;
  };
  bool met = false;
  std::vector<char> goal_unmet, cell_unmet;
  int min_per_zoom = o.min_shots_per_zoom;
  if (min_per_zoom < 0) {
    bool cam_records = false;
    for (const Record& r : session.fixed.records) cam_records = cam_records || r.tool == Tool::kCam;
    min_per_zoom = cam_records ? 0 : 16;
  }
  // Photos per zoom: those measured already, then the chosen ones.
  std::map<int, int> per_zoom;
  for (int z : zooms) per_zoom[z] = 0;
  {
    std::set<std::pair<int, std::string>> measured;
    for (const PixelObservation& p : session.fixed.pixels) {
      if (per_zoom.count(p.zoom) && measured.insert({p.zoom, p.shot}).second) ++per_zoom[p.zoom];
    }
  }
  // Zooms below their minimum (only their candidates count while there are).
  auto short_zooms = [&] {
    std::set<int> out;
    for (const auto& [z, n] : per_zoom) {
      if (n < min_per_zoom) out.insert(z);
    }
    return out;
  };
  while (static_cast<int>(order.size()) < std::min(o.max_shots, n_cand)) {
    const Eigen::MatrixXd cov = covariance(m, kRidge);
    const std::set<int> below = short_zooms();
    if (!no_goal && below.empty()) {
      unmet(exact(m), &goal_unmet, &cell_unmet);
      bool left = false;
      for (size_t k = 0; k < goals.size(); ++k) {
        if (!goal_possible[k]) goal_unmet[k] = 0;  // no shot helps: not a target
        left = left || goal_unmet[k];
      }
      for (char c : cell_unmet) left = left || c;
      if (!left) {
        met = true;
        break;
      }
    }
    // Weight W = sum of the unmet functionals' outer products (A), or none (D).
    Eigen::MatrixXd w = Eigen::MatrixXd::Zero(q, q);
    if (!no_goal && below.empty()) {
      for (size_t k = 0; k < goals.size(); ++k) {
        if (goal_unmet[k]) w.noalias() += g_goals.col(k) * g_goals.col(k).transpose();
      }
      for (size_t k = 0; k < cells.size(); ++k) {
        if (cell_unmet[k]) w.noalias() += g_cells.col(k) * g_cells.col(k).transpose();
      }
    }
    // Below a zoom's minimum: D-optimal among that zoom's candidates.
    const bool d_step = no_goal || !below.empty();
    const Eigen::MatrixXd pwp = d_step ? cov : (cov * w * cov).eval();
    // First-order reductions, then the exact ones on the shortlist.
    std::vector<std::pair<double, int>> first;
    for (int c = 0; c < n_cand; ++c) {
      if (chosen[c] || factor[c].l.cols() == 0) continue;
      if (!below.empty() && !below.count(pool.shots[c].pointing.zoom)) continue;
      const Eigen::MatrixXd& l = factor[c].l;
      first.push_back({(l.transpose() * pwp * l).trace(), c});
    }
    if (first.empty()) break;
    const size_t k_short = std::min<size_t>(kShortlist, first.size());
    std::partial_sort(first.begin(), first.begin() + static_cast<long>(k_short), first.end(),
                      [](const auto& a, const auto& b) { return a.first > b.first; });
    double best_gain = -1;
    int best = -1;
    for (size_t s = 0; s < k_short; ++s) {
      const int c = first[s].second;
      const Eigen::MatrixXd& l = factor[c].l;
      const Eigen::MatrixXd a = cov * l;
      Eigen::MatrixXd smat = l.transpose() * a;
      smat.diagonal().array() += 1.0;
      double gain;
      if (d_step) {
        gain = 2.0 * Eigen::LLT<Eigen::MatrixXd>(smat).matrixLLT().diagonal().array().log().sum();
      } else {
        gain = (Eigen::LLT<Eigen::MatrixXd>(smat).solve(a.transpose() * w * a)).trace();
      }
      if (gain > best_gain) {
        best_gain = gain;
        best = c;
      }
    }
    if (best < 0 || !(best_gain > 0)) break;
    chosen[best] = 1;
    order.push_back(best);
    ++per_zoom[pool.shots[best].pointing.zoom];
    m.noalias() += factor[best].l * factor[best].l.transpose();
    const Eigen::MatrixXd after = covariance(m, kRidge);
    result.criterion.push_back(no_goal ? -log_det(m) : phi_all(after));
    result.log_det.push_back(log_det(m));
  }
  if (!no_goal && !met) {
    bool left = false;
    unmet(exact(m), &goal_unmet, &cell_unmet);
    for (size_t k = 0; k < goals.size(); ++k) left = left || (goal_unmet[k] && goal_possible[k]);
    for (char c : cell_unmet) left = left || c;
    met = !left;
  }
  // Exchange pass: drop shots the goal does not need, cheapest first (the
  // first-order loss <P W P, I_c> of the goals).
  if (o.exchange && met && !no_goal) {
    bool removed = true;
    while (removed && order.size() > 1) {
      removed = false;
      const Eigen::MatrixXd cov = covariance(m, kRidge);
      std::vector<std::pair<double, size_t>> loss;
      Eigen::MatrixXd w = g_goals * g_goals.transpose();
      if (o.goal.projection_px > 0) w += g_cells * g_cells.transpose();
      const Eigen::MatrixXd pwp = cov * w * cov;
      for (size_t s = 0; s < order.size(); ++s) {
        const Eigen::MatrixXd& l = factor[order[s]].l;
        loss.push_back({(l.transpose() * pwp * l).trace(), s});
      }
      std::sort(loss.begin(), loss.end());
      for (size_t t = 0; t < std::min<size_t>(loss.size(), 8); ++t) {
        const int c = order[loss[t].second];
        if (per_zoom[pool.shots[c].pointing.zoom] <= min_per_zoom) continue;
        const Eigen::MatrixXd trial = m - factor[c].l * factor[c].l.transpose();
        std::vector<char> gu, cu;
        unmet(exact(trial), &gu, &cu);
        bool left = false;
        for (size_t k = 0; k < goals.size(); ++k) left = left || (gu[k] && goal_possible[k]);
        for (char x : cu) left = left || x;
        if (!left) {
          m = trial;
          chosen[c] = 0;
          --per_zoom[pool.shots[c].pointing.zoom];
          order.erase(order.begin() + static_cast<long>(loss[t].second));
          removed = true;
          break;
        }
      }
    }
  }

  // Prediction at the chosen set and of the fixed data alone: the
  // pseudo-inverse, as the fit's covariance.
  const Pseudo chosen_ps = exact(m);
  const Pseudo fixed_ps = exact(red_fixed);
  const Eigen::MatrixXd& cov = chosen_ps.cov;
  const Eigen::MatrixXd cov_all = covariance(reduce(info_all), 0.0);
  for (size_t k = 0; k < constants.size(); ++k) {
    PredictedConstant& pc = result.constants[constants[k].constant];
    const Eigen::VectorXd gk = g_consts.col(k);
    pc.determined = undetermined_fraction(constants[k].g) <= 1e-6;
    if (!pc.determined) continue;
    pc.sigma_all_candidates = std::sqrt(gk.dot(cov_all * gk));
    if (!in_null(chosen_ps, gk)) pc.sigma = std::sqrt(gk.dot(cov * gk));
    if (!in_null(fixed_ps, gk)) pc.sigma_fixed = std::sqrt(gk.dot(fixed_ps.cov * gk));
  }
  // Projection per zoom (cells already divided by the goal: multiply back).
  const double proj_unit = o.goal.projection_px > 0 ? o.goal.projection_px : 1.0;
  for (int z : zooms) {
    PredictedProjection pp;
    pp.zoom = z;
    pp.width = model.cams[z].width;
    pp.height = model.cams[z].height;
    pp.goal_px = o.goal.projection_px;
    double worst = 0;
    for (size_t k = 0; k + 1 < cells.size(); k += 2) {
      if (cells[k].zoom != z) continue;
      const Eigen::VectorXd pa = cov * g_cells.col(k), pb = cov * g_cells.col(k + 1);
      worst = std::max(worst, proj_unit * WorstSigma(g_cells.col(k).dot(pa), g_cells.col(k).dot(pb),
                                                     g_cells.col(k + 1).dot(pb)));
    }
    pp.worst_px = worst;
    result.projection.push_back(pp);
  }
  // What limits an unmet goal.
  result.goal_met = no_goal || met;
  for (const std::string& name : unreachable) {
    result.limits.push_back(
        name +
        ": these targets cannot determine it (no candidate photo or fixed observation "
        "depends on it); it needs other observations (e.g. EDM rows for an EDM effect)");
  }
  for (size_t k = 0; k < goals.size(); ++k) {
    const PredictedConstant& pc = result.constants[goals[k].constant];
    if (!goal_possible[k]) {
      result.goal_met = false;
      result.limits.push_back(
          pc.name +
          ": these targets cannot determine it (the information of every candidate photo is "
          "rank-deficient in its direction); it needs other targets, distances or faces");
    } else if (!(pc.sigma <= pc.goal)) {
      if (pc.sigma_all_candidates > pc.goal) {
        result.limits.push_back(pc.name + ": geometry: even all " + std::to_string(n_cand) +
                                " candidate photos give sigma " +
                                std::to_string(pc.sigma_all_candidates) + " " + pc.unit +
                                " > goal " + std::to_string(pc.goal));
      } else if (static_cast<int>(order.size()) < std::min(o.max_shots, n_cand)) {
        result.limits.push_back(pc.name + ": geometry: no further candidate photo lowers sigma " +
                                std::to_string(pc.sigma) + " " + pc.unit + " toward the goal " +
                                std::to_string(pc.goal) + " by a step of the greedy choice");
      } else {
        result.limits.push_back(pc.name + ": budget: max_shots " + std::to_string(o.max_shots) +
                                " gives sigma " + std::to_string(pc.sigma) + " " + pc.unit +
                                " > goal " + std::to_string(pc.goal));
      }
    }
  }
  if (o.goal.projection_px > 0) {
    for (const PredictedProjection& pp : result.projection) {
      if (pp.worst_px <= pp.goal_px) continue;
      result.limits.push_back(
          "projection zoom " + std::to_string(pp.zoom) + ": " +
          // Every candidate taken: more photos of these do not help.
          (static_cast<int>(order.size()) >= o.max_shots && static_cast<int>(order.size()) < n_cand
               ? "budget"
               : "geometry") +
          ": worst sigma " + std::to_string(pp.worst_px) + " px > goal " +
          std::to_string(pp.goal_px) + " px");
    }
  }
  if (!result.limits.empty()) result.goal_met = false;

  // What each chosen shot determines: the goal (or constant group) whose
  // variance it reduces most, relatively, given all the other chosen shots.
  std::vector<Functional> labels = goals;
  if (o.goal.projection_px > 0) {
    for (const Functional& f : cells) labels.push_back(f);
  }
  if (labels.empty()) labels = constants;
  const Eigen::MatrixXd g_labels = red(labels);
  for (int c : order) {
    PlanShot s = pool.shots[c];
    const Eigen::MatrixXd without = m - factor[c].l * factor[c].l.transpose();
    const Eigen::MatrixXd cw = covariance(without, kRidge);
    double best = -1;
    for (int k = 0; k < g_labels.cols(); ++k) {
      const double before = g_labels.col(k).dot(cw * g_labels.col(k));
      const double now = g_labels.col(k).dot(cov * g_labels.col(k));
      if (!(before > 0)) continue;
      const double drop = 1.0 - now / before;
      if (drop > best) {
        best = drop;
        s.determines = labels[k].name;
      }
    }
    for (const Functional& g : goals) {
      const Eigen::VectorXd gr = to_red * g.g;
      const double v = gr.dot(cw * gr);
      const PredictedConstant& pc = result.constants[g.constant];
      s.sigma_without.push_back({pc.name, v < 1.0 / kRidge * 1e-3 ? std::sqrt(v) * pc.goal : kNaN});
    }
    result.shots.push_back(s);
  }
  int index = 0;
  result.motor_travel_rad = OrderShots(session.scenes, &result.shots);
  for (PlanShot& s : result.shots) {
    s.pointing.name = "plan" + std::to_string(++index);
  }
  return result;
}

}  // namespace rtscalib

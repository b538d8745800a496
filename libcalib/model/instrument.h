// The instrument model: every physical thing owns one contiguous parameter
// block that Ceres optimises in place.
//
//   base        ref_from_base pose: quaternion (Eigen x,y,z,w) + translation  [m]
//   links[2]    DH link parameters {d, gamma_offset, alpha, a} (Klug Eq. 5)   [m, rad]
//               joint angle gamma_i = control_i* + gamma_offset_i
//   edm         flange_from_edm pose (EDM ray = +z of this frame)
//   cams[z]     per zoom: flange_from_cam pose, intrinsics[4], distortion[14],
//               focus[3] {kf [m], au [px m], av [px m]} (SPEC 4.1, focus.h)
//   effects[e]  one block per kinematic/EDM effect (effects.h), SI units
//   boards[b]   ref_from_board pose of a board of unknown pose (SPEC 7):
//               quaternion + translation [m]; scale fixed by its tag_size
//   points[p]   position of a fixed point of unknown position (SPEC 7) [m]
//   board_warps[w] {wx, wy} [m] of a board of unknown pose (the effect
//               board_warp, TagBoard::warp), one per board, shared by its poses
//
// Two kinematics share these blocks (kinematics.h has the formulas):
//   dh         Klug Sec. 3:   ref_from_flange = Base * Z1 X1 * Z2 X2
//   spherical  Klug Sec. 4.1 + SPEC 4: ref_from_flange = Base * Rz(-phi*) Ry(i) Rx(-theta*) Ry(c)
// and both end in ref_from_tool = ref_from_flange * flange_from_tool (Eq. 9).
// A third, `none` (SPEC 7.1), is the camera-only calibration: no chain at
// all. Base, links and tools stay at the identity and are never estimated,
// so that ref_from_cam = identity: the reference frame of a zoom's shots is
// that zoom's camera frame, and each board pose is cam_from_board. Only the
// intrinsics, the distortion and the boards are estimated.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "libcalib/camera/opencv_model.h"
#include "libcalib/geometry/rotation.h"
#include "libcalib/model/effects.h"
#include "libcalib/model/focus.h"
#include "libcalib/model/targets.h"

namespace rtscalib {

enum class Kinematics { kDh, kSpherical, kNone };
const char* KinematicsName(Kinematics k);

// A pose parameter block pair: rotation as a unit quaternion (Eigen storage
// order x, y, z, w) on a manifold, translation in metres.
struct PoseBlock {
  std::array<double, 4> q{0, 0, 0, 1};
  std::array<double, 3> t{0, 0, 0};

  Rigid3 ToRigid() const;
  static PoseBlock FromRigid(const Rigid3& r);
  // Euler angles [a, b, g] of Klug Eq. 83 (for reports and Tables 2/7).
  Eigen::Vector3d Euler() const;
};

enum DhIndex { kDhD = 0, kDhGamma = 1, kDhAlpha = 2, kDhA = 3 };
// Parameter names (model.yaml keys, column names of the fit) in DhIndex order.
inline constexpr const char* kDhParamNames[] = {"d", "gamma_offset", "alpha", "a"};
struct DhLink {
  std::array<double, 4> p{0, 0, 0, 0};  // d, gamma_offset, alpha, a
};

// Intrinsics names in storage order fx, fy, cx, cy (model.yaml keys, column names).
inline constexpr const char* kIntrinsicsParamNames[kNumIntrinsics] = {"fx", "fy", "cx", "cy"};

struct CameraTool {
  PoseBlock flange_from_cam;
  std::array<double, kNumIntrinsics> intrinsics{1000, 1000, 640, 480};
  std::array<double, kNumDistortion> distortion{};
  // true: coefficient i is held at its value by the fit although its
  // distortion group is enabled (the config's model.<group>.coefficients,
  // libcalib/fit/parameterization.h decides with it); written to model.yaml
  // as `distortion_held`, its sigma as `held`.
  std::array<bool, kNumDistortion> distortion_held{};
  // SPEC 4.1: how the intrinsics above (focused at infinity) change with the
  // focus distance D (libcalib/model/focus.h); used only when the model has
  // the `focus` effect.
  std::array<double, kNumFocus> focus{};
  int width = 1280;
  int height = 960;
  // False when the data held no rows of this zoom (outside the critical
  // regions): the values are the start's, not an estimate, have no
  // uncertainty, and nothing may be predicted with them.
  bool determined = true;
  // Where the calibration's image points of this zoom (pixels.csv rows and
  // cam records' u, v) fell: their convex hull [px] (geometry/convex_hull.h),
  // empty when unknown (no such rows, or a model.yaml without
  // `valid_region`). Outside it the distortion is extrapolated.
  std::vector<Eigen::Vector2d> valid_region;
};

// Standard deviations for every parameter, filled by the fit. Rotation
// sigmas are those of the fit's tangent coordinates (libcalib/fit/manifolds.h):
// for the base, the camera tools and the boards (Ceres's
// EigenQuaternionManifold, q -> exp(delta) q) HALF the rotation angle about
// the PARENT frame's x, y, z; for the EDM tool (no-roll manifold, q ->
// q exp(delta)) the rotation angle about its own x and y (z: 0, not fitted).
struct PoseSigma {
  std::array<double, 3> rotation{};  // rad, tangent coordinates (above)
  std::array<double, 3> euler{};     // rad, of [a, b, g]
  std::array<double, 3> t{};         // m
};
struct ModelSigmas {
  bool valid = false;
  PoseSigma base, edm;
  std::array<std::array<double, 4>, 2> links{};
  std::vector<PoseSigma> cam_tools;
  std::vector<std::array<double, kNumIntrinsics>> intrinsics;
  std::vector<std::array<double, kNumDistortion>> distortion;
  std::vector<std::array<double, kNumFocus>> focus;  // per zoom, when the model has `focus`
  std::array<std::array<double, 4>, kNumKinematicEffects> effect_cov{};  // 2x2 row major
  // The fit's full joint covariance of p in the tangent coordinates and order
  // of libcalib/fit/parameter_layout.h (held coordinates: zero rows); empty
  // when none was computed. Written beside model.yaml as covariance.yaml.
  Eigen::MatrixXd covariance;
};

// A board of unknown pose (SPEC 7), estimated with the instrument: its
// geometry (`board`, whose ref_from_board is kept equal to `pose` after a
// fit) and its ref_from_board pose block. Corner (target, corner) is
// ref_from_board * board.CornersInBoard(target - first_id)[corner].
// One board has one such pose per `placement` (SPEC 7.1: the board was moved
// between sets of shots; empty = the one placement of a session without
// placements). In a camera-only calibration (Kinematics::kNone) the pose is
// also per `zoom`: each zoom's camera frame is the reference of its own shots
// and no camera tool relates the zooms; otherwise `zoom` is -1 (every zoom).
struct EstimatedBoard {
  TagBoard board;
  std::string placement;
  int zoom = -1;
  PoseBlock pose;
  PoseSigma sigma;  // filled by the fit (zero when not estimated)

  // Does this pose hold target `id` seen in `placement` at `zoom`?
  bool Holds(int id, const std::string& at_placement, int at_zoom) const {
    return board.HasId(id) && placement == at_placement && (zoom < 0 || zoom == at_zoom);
  }
  // "board 0", "board 0 at placement p3", "board 0 at placement p3, zoom 1"
  // (reports, messages).
  std::string Name() const;
  // The parameter name stem "board[0]", "board[0@p3]", "board[0@p3/z1]"
  // (fit columns, covariance.yaml).
  std::string Key() const;
};
// The warp of a board of estimated pose (the catalogue effect board_warp,
// TagBoard::warp), one pair per board, identified by its first_id: a board
// bends alike wherever it is put, so every pose of it (placements, zooms)
// shares the pair. Fitted when the model has the effect; after a fit each
// EstimatedBoard of the board carries it in board.warp (SyncBoardWarps).
struct BoardWarp {
  int first_id = 0;
  std::array<double, kNumBoardWarp> w{0, 0};  // {wx, wy} [m]
  std::array<double, 4> cov{};                // 2 x 2 row major [m^2], filled by the fit
};
// A fixed point of unknown position named by records.csv's `point` column.
struct EstimatedPoint {
  std::string name;
  std::array<double, 3> x{0, 0, 0};      // reference frame [m]
  std::array<double, 3> sigma{0, 0, 0};  // [m], filled by the fit
};

struct InstrumentModel {
  Kinematics kinematics = Kinematics::kDh;
  EffectSet effects;
  PoseBlock base;
  std::array<DhLink, 2> links;
  PoseBlock edm;
  std::vector<CameraTool> cams;  // index = zoom level
  std::array<std::array<double, kMaxEffectParams>, kNumKinematicEffects> effect_values{};
  double edm_cyclic_unit_length = 1.5;  // U of edm_cyclic [m], an instrument constant
  // False when the data held no EDM rows (outside the critical regions): edm
  // is the start value, not an estimate (as CameraTool::determined).
  bool edm_determined = true;
  ModelSigmas sigmas;
  // SPEC 7: boards of unknown pose and points of unknown position, estimated
  // with everything else. Vectors (not maps) so that a same-sized copy keeps
  // the block addresses a fit holds.
  std::vector<EstimatedBoard> boards;
  std::vector<EstimatedPoint> points;
  // board_warp: one per board of `boards` (by first_id) when the model has the
  // effect; a vector for the same reason as above.
  std::vector<BoardWarp> board_warps;

  int NumZooms() const { return static_cast<int>(cams.size()); }
  std::array<double, 2>& EffectValue(Effect e) { return effect_values[static_cast<int>(e)]; }
  const std::array<double, 2>& EffectValue(Effect e) const {
    return effect_values[static_cast<int>(e)];
  }
  // The estimated board pose holding tag `id` in `placement` at `zoom`
  // (EstimatedBoard::Holds), or nullptr.
  const EstimatedBoard* BoardOf(int id, const std::string& placement, int zoom) const;
  EstimatedBoard* BoardOf(int id, const std::string& placement, int zoom);
  const EstimatedPoint* Point(const std::string& name) const;
  EstimatedPoint* Point(const std::string& name);
  // The warp of the board whose first tag is `first_id`, or nullptr.
  const BoardWarp* WarpOf(int first_id) const;
  BoardWarp* WarpOf(int first_id);
};

// board_warp: gives the model a warp for every board of `boards` it has none
// for (at zero) when it has the effect, and none at all without it; then
// copies each warp into the EstimatedBoards of its board (board.warp), zero
// without the effect.
void SyncBoardWarps(InstrumentModel* model);

// Which face a (phi, theta) reading belongs to: face 1 for theta in [0, pi],
// face 2 for theta in (pi, 2 pi).
int FaceOf(double theta);
// Face-2 reading of a face-1 pointing (SPEC 1).
inline void OtherFace(double phi, double theta, double* phi2, double* theta2) {
  double p = std::fmod(phi - M_PI, 2.0 * M_PI);
  if (p < 0) p += 2.0 * M_PI;
  *phi2 = p;
  *theta2 = 2.0 * M_PI - theta;
}
// Zenith angle of a reading: theta in face 1, 2 pi - theta in face 2.
inline double ZenithOf(double theta) { return theta <= M_PI ? theta : 2.0 * M_PI - theta; }

// The ideal instrument of Klug Eq. 90/91 in both kinematics (no effects, ideal
// tools, `num_zooms` identical ideal cameras): a starting point and a test fixture.
InstrumentModel IdealModel(Kinematics k, int num_zooms, const CameraTool& camera);

}  // namespace rtscalib

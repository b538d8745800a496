// The physical-effects catalogue (SPEC section 4, docs/effects.md).
//
// An effect is an optional, named model component with physical units. This
// header is the one place that knows every effect: `RTSCALIB_EFFECT_LIST`
// below is the one list from which the `Effect` enum, `kNumEffects`,
// `kNumKinematicEffects`, the catalogue rows (name, parameter count and order,
// report units and with them the SI -> report scale, kind, redundancy in `dh`,
// the data that determine it) and the distortion groups' coefficients are all
// derived. The fit switches effects on and off only through `EffectSet`; the
// formulas live in libcalib/model/kinematics.h (kinematic effects) and
// libcalib/camera/opencv_model.h (distortion groups).
//
// Parameterisation (chosen so that every effect is linear in its parameters at
// zero and well conditioned when the effect is absent):
//   collimation      [c]                                rad
//   tilting_axis     [i]                                rad
//   vertical_index   [v0]                               rad
//   hz_eccentricity  [e cos(phi_e), e sin(phi_e)]       rad
//                    e sin(phi - phi_e) = p0 sin(phi) - p1 cos(phi)
//   v_eccentricity   [e cos(theta_e), e sin(theta_e)]   rad; same form in theta
//   hz_scale         [s]                                ratio
//   v_scale          [s]                                ratio
//   axis_wobble      [w cos(phi_w), w sin(phi_w)]       rad
//   edm_offset       [k0]                               m
//   edm_scale        [m]                                ratio
//   edm_cyclic       [A cos(psi), A sin(psi)]           m
//                    A sin(2 pi d/U + psi) = p0 sin(.) + p1 cos(.)
//   distortion groups: coefficients of OpenCV's 14, per zoom
//                    (RTSCALIB_DISTORTION_COEFFICIENTS).
//   focus            per zoom [kf, au, av]                 m, px m, px m
//                    (SPEC 4.1, libcalib/model/focus.h: the camera constant and
//                    the principal point at focus distance D)
//   board_warp       per board of estimated pose [wx, wy]  m
//                    (libcalib/model/targets.h TagBoard::warp: the board's
//                    points leave its plane by wx (1 - xr^2) + wy (1 - yr^2))
#pragma once

#include <array>
#include <bitset>
#include <iterator>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "libcalib/camera/opencv_model.h"

namespace rtscalib {

// What data determine an effect (the diagnosis's advice when they are
// missing, libcalib/diagnose/coverage.cc). Bits, reported in this order.
enum DataNeed : unsigned {
  kNeedNone = 0,
  kNeedFullTurn = 1u << 0,       // pointings all around the horizon
  kNeedSteepSights = 1u << 1,    // zenith angles near the zenith or nadir
  kNeedWideZenith = 1u << 2,     // a wide range of zenith angles
  kNeedBothFaces = 1u << 3,      // face 2 readings of the same pointings
  kNeedEdm = 1u << 4,            // EDM records
  kNeedLongDistances = 1u << 5,  // EDM distances over a wide ratio
  kNeedFineDistances = 1u << 6,  // EDM distances finer than the cyclic unit
  kNeedImageCorners = 1u << 7,   // camera observations reaching the image corners
  kNeedNearAndFar = 1u << 8,     // camera targets at several distances, near and far
  kNeedManyPoses = 1u << 9,      // each board seen in many poses, tilted both ways
};
constexpr int kNumDataNeeds = 10;

// clang-format off
// THE effect list. One row per effect, kinematic and EDM effects first, then
// the per-zoom camera effects (the distortion groups, then focus), then the
// per-board effects:
//   X(enumerator, name, kind, num_params, param_names {p0, p1}, report_units {u0, u1},
//     redundant_in_dh, needs, definition, signature)
// Report units are "arcsec", "ppm" or "mm" for the (amplitude) parameter and
// "deg" for a phase; they also fix the SI -> report scale (`ReportScale`).
#define RTSCALIB_EFFECT_LIST(X)                                                                    \
  X(kCollimation, "collimation", kAxis, 1, "c", "", "arcsec", "", true,                            \
    kNeedSteepSights | kNeedBothFaces,                                                             \
    "line of sight turned by c about the telescope's y axis (after the tilt about the trunnion "   \
    "axis)",                                                                                       \
    "dHz = +c/sin(z) face 1, -c/sin(z) face 2")                                                    \
  X(kTiltingAxis, "tilting_axis", kAxis, 1, "i", "", "arcsec", "", true,                           \
    kNeedSteepSights | kNeedBothFaces,                                                             \
    "trunnion axis turned by i about the alidade's y axis (before the tilt)",                      \
    "dHz = +i*cot(z) face 1, opposite face 2")                                                     \
  X(kVerticalIndex, "vertical_index", kAngle, 1, "v0", "", "arcsec", "", true, kNeedBothFaces,     \
    "theta* = theta + v0", "constant dz, flips sign with face")                                    \
  X(kHzEccentricity, "hz_eccentricity", kAngle, 2, "e", "phi_e", "arcsec", "deg", false,           \
    kNeedFullTurn, "phi* = phi + e*sin(phi - phi_e)", "once per turn in phi")                      \
  X(kVEccentricity, "v_eccentricity", kAngle, 2, "e", "theta_e", "arcsec", "deg", false,           \
    kNeedWideZenith | kNeedBothFaces, "theta* = theta + e*sin(theta - theta_e)",                   \
    "once per turn in theta")                                                                      \
  X(kHzScale, "hz_scale", kAngle, 1, "s", "", "ppm", "", false, kNeedFullTurn,                     \
    "phi* = phi + s*phi", "grows with phi")                                                        \
  X(kVScale, "v_scale", kAngle, 1, "s", "", "ppm", "", false, kNeedWideZenith | kNeedBothFaces,    \
    "theta* = theta + s*theta", "grows with theta")                                                \
  X(kAxisWobble, "axis_wobble", kAxis, 2, "w", "phi_w", "arcsec", "deg", false,                    \
    kNeedFullTurn | kNeedSteepSights,                                                              \
    "vertical axis tilted by Rx(w cos(phi-phi_w)) Ry(w sin(phi-phi_w)) before the phi rotation",   \
    "once per turn tilt")                                                                          \
  X(kEdmOffset, "edm_offset", kEdm, 1, "k0", "", "mm", "", true, kNeedEdm, "d* = d + k0",          \
    "constant along the ray")                                                                      \
  X(kEdmScale, "edm_scale", kEdm, 1, "m", "", "ppm", "", false, kNeedEdm | kNeedLongDistances,     \
    "d* = d (1 + m)", "grows with d")                                                              \
  X(kEdmCyclic, "edm_cyclic", kEdm, 2, "A", "psi", "mm", "deg", false,                             \
    kNeedEdm | kNeedFineDistances, "d* = d + A sin(2 pi d / U + psi), U configured",               \
    "periodic in d")                                                                               \
  X(kRadialDistortion, "radial_distortion", kDistortion, 0, "", "", "", "", false,                 \
    kNeedImageCorners, "OpenCV k1 k2 k3", "radial in the image")                                   \
  X(kTangentialDistortion, "tangential_distortion", kDistortion, 0, "", "", "", "", false,         \
    kNeedImageCorners, "OpenCV p1 p2", "decentring")                                               \
  X(kRationalDistortion, "rational_distortion", kDistortion, 0, "", "", "", "", false,             \
    kNeedImageCorners, "OpenCV k4 k5 k6", "wide-angle radial")                                     \
  X(kThinPrism, "thin_prism", kDistortion, 0, "", "", "", "", false, kNeedImageCorners,            \
    "OpenCV s1..s4", "thin prism")                                                                 \
  X(kSensorTilt, "sensor_tilt", kDistortion, 0, "", "", "", "", false, kNeedImageCorners,          \
    "OpenCV taux tauy", "sensor tilt (Scheimpflug)")                                            \
  X(kFocus, "focus", kFocus, 0, "", "", "", "", false, kNeedNearAndFar,                           \
    "per zoom: fx* = fx (1 + kf/D), fy* = fy (1 + kf/D), cx* = cx + au/D, cy* = cy + av/D, "      \
    "D = the photo's focus distance",                                                              \
    "image scale and principal point that change with the target's distance")              \
  X(kBoardWarp, "board_warp", kBoard, 0, "wx", "wy", "mm", "mm", false, kNeedManyPoses,           \
    "per board of estimated pose: its points leave the board's plane along its z (out of its "   \
    "back) by wx (1 - xr^2) + wy (1 - yr^2), xr, yr in [-1, 1] across its points "              \
    "(mrcal's calobject_warp)",                                                                    \
    "residuals that follow the board's own coordinates as a bowl or a saddle, whatever its pose")

// OpenCV's 14 distortion coefficients, in DistortionIndex order, each
// with the effect (distortion group) that owns it: X(name, camera index, group).
#define RTSCALIB_DISTORTION_COEFFICIENTS(X)                                                        \
  X("k1", kK1, kRadialDistortion)                                                          \
  X("k2", kK2, kRadialDistortion)                                                          \
  X("p1", kP1, kTangentialDistortion)                                                      \
  X("p2", kP2, kTangentialDistortion)                                                      \
  X("k3", kK3, kRadialDistortion)                                                          \
  X("k4", kK4, kRationalDistortion)                                                        \
  X("k5", kK5, kRationalDistortion)                                                        \
  X("k6", kK6, kRationalDistortion)                                                        \
  X("s1", kS1, kThinPrism)                                                                 \
  X("s2", kS2, kThinPrism)                                                                 \
  X("s3", kS3, kThinPrism)                                                                 \
  X("s4", kS4, kThinPrism)                                                                 \
  X("taux", kTauX, kSensorTilt)                                                            \
  X("tauy", kTauY, kSensorTilt)
// clang-format on

enum class Effect : int {
#define RTSCALIB_EFFECT_ENUMERATOR(id, ...) id,
  RTSCALIB_EFFECT_LIST(RTSCALIB_EFFECT_ENUMERATOR)
#undef RTSCALIB_EFFECT_ENUMERATOR
};

// kAngle, kAxis, kEdm: one block of their own (InstrumentModel::effect_values);
// kDistortion: coefficients of each zoom's distortion block; kFocus: each
// zoom's focus block (CameraTool::focus, libcalib/model/focus.h); kBoard: one
// block per board of estimated pose (InstrumentModel::board_warps).
enum class EffectKind { kAngle, kAxis, kEdm, kDistortion, kFocus, kBoard };

// The list as a constexpr table (compile-time checks below; EffectInfo adds
// the derived distortion coefficients at run time).
struct EffectRow {
  Effect effect;
  const char* name;
  EffectKind kind;
  int num_params;
  std::array<const char*, 2> param_names;
  std::array<const char*, 2> report_units;
  bool redundant_in_dh;
  unsigned needs;  // DataNeed bits
  const char* definition;
  const char* signature;
};
inline constexpr EffectRow kEffectRows[] = {
#define RTSCALIB_EFFECT_ROW(id, name, kind, n, p0, p1, u0, u1, dh, needs, def, sig) \
  {Effect::id, name, EffectKind::kind, n, {p0, p1}, {u0, u1}, dh, needs, def, sig},
    RTSCALIB_EFFECT_LIST(RTSCALIB_EFFECT_ROW)
#undef RTSCALIB_EFFECT_ROW
};
constexpr int kNumEffects = static_cast<int>(std::size(kEffectRows));

struct DistortionCoefficient {
  const char* name;
  int index;     // DistortionIndex
  Effect group;  // the distortion effect that owns it
};
inline constexpr DistortionCoefficient kDistortionCoefficients[] = {
#define RTSCALIB_DISTORTION_ROW(name, index, group) {name, index, Effect::group},
    RTSCALIB_DISTORTION_COEFFICIENTS(RTSCALIB_DISTORTION_ROW)
#undef RTSCALIB_DISTORTION_ROW
};

// The coefficients' names ("k1" ... "tauy"), in DistortionIndex order.
inline constexpr const char* kDistortionCoefficientNames[] = {
#define RTSCALIB_DISTORTION_NAME(name, index, group) name,
    RTSCALIB_DISTORTION_COEFFICIENTS(RTSCALIB_DISTORTION_NAME)
#undef RTSCALIB_DISTORTION_NAME
};

namespace effects_internal {
constexpr bool KinematicKind(EffectKind kind) {
  return kind == EffectKind::kAngle || kind == EffectKind::kAxis || kind == EffectKind::kEdm;
}
constexpr int CountKinematic() {
  int n = 0;
  for (const EffectRow& r : kEffectRows) n += KinematicKind(r.kind);
  return n;
}
constexpr int CountKind(EffectKind kind) {
  int n = 0;
  for (const EffectRow& r : kEffectRows) n += r.kind == kind;
  return n;
}
constexpr bool Same(const char* a, const char* b) {
  while (*a && *a == *b) ++a, ++b;
  return *a == *b;
}
// Rows in enum order, kinematic effects first, then the distortion groups,
// then focus, then the per-board effects; parameter counts and report units
// consistent with the kind (per-zoom camera and per-board effects have no
// block in effect_values: num_params 0; a per-board effect's report units
// are millimetres).
constexpr bool RowsConsistent() {
  int stage = 0;  // 0 kinematic, 1 distortion, 2 focus, 3 board
  for (int i = 0; i < static_cast<int>(std::size(kEffectRows)); ++i) {
    const EffectRow& r = kEffectRows[i];
    if (static_cast<int>(r.effect) != i) return false;
    const int s = r.kind == EffectKind::kDistortion ? 1
                  : r.kind == EffectKind::kFocus    ? 2
                  : r.kind == EffectKind::kBoard    ? 3
                                                    : 0;
    if (s < stage) return false;
    stage = s;
    const bool distortion = s > 0;
    if (distortion != (r.num_params == 0)) return false;
    if (s == 3 && (!Same(r.report_units[0], "mm") || !Same(r.report_units[1], "mm"))) return false;
    if (!distortion && !Same(r.report_units[0], "arcsec") && !Same(r.report_units[0], "ppm") &&
        !Same(r.report_units[0], "mm"))
      return false;
    if (r.num_params == 2 && !Same(r.report_units[1], "deg")) return false;
    if (r.needs == kNeedNone || r.needs >= (1u << kNumDataNeeds)) return false;
  }
  return true;
}
constexpr bool CoefficientsConsistent() {
  for (int i = 0; i < static_cast<int>(std::size(kDistortionCoefficients)); ++i) {
    const DistortionCoefficient& c = kDistortionCoefficients[i];
    if (c.index != i) return false;
    if (kEffectRows[static_cast<int>(c.group)].kind != EffectKind::kDistortion) return false;
  }
  // Every distortion group owns at least one coefficient.
  for (const EffectRow& r : kEffectRows) {
    if (r.kind != EffectKind::kDistortion) continue;
    bool owns = false;
    for (const DistortionCoefficient& c : kDistortionCoefficients)
      owns = owns || c.group == r.effect;
    if (!owns) return false;
  }
  return true;
}
}  // namespace effects_internal

// Effects with a parameter block of their own (the rest live in the per-zoom
// camera blocks: distortion, focus; and in the per-board blocks: board_warp).
constexpr int kNumKinematicEffects = effects_internal::CountKinematic();
constexpr int kNumDistortionGroups = effects_internal::CountKind(EffectKind::kDistortion);
constexpr int kMaxEffectParams = 2;

static_assert(effects_internal::RowsConsistent(),
              "RTSCALIB_EFFECT_LIST: rows out of enum order, a distortion group before a "
              "kinematic effect, or parameter count / report units / needs not matching the kind");
static_assert(static_cast<int>(std::size(kDistortionCoefficients)) == kNumDistortion,
              "RTSCALIB_DISTORTION_COEFFICIENTS must name all of OpenCV's coefficients");
static_assert(effects_internal::CoefficientsConsistent(),
              "RTSCALIB_DISTORTION_COEFFICIENTS: out of DistortionIndex order, owned by a "
              "kinematic effect, or a distortion group owning no coefficient");

struct EffectInfo {
  Effect effect;
  const char* name;
  EffectKind kind;
  int num_params;  // kinematic effects: size of its block (0 for camera effects)
  std::array<const char*, 2> param_names;
  std::array<const char*, 2> report_units;  // after polar conversion (see below)
  const char* definition;
  const char* signature;
  // True when, in the `dh` kinematics, the DH links and free tool transforms
  // already contain this effect (SPEC section 4).
  bool redundant_in_dh;
  unsigned needs;  // DataNeed bits
  // Distortion coefficients this group owns (indices into
  // kDistortionCoefficients); empty for kinematic effects.
  std::vector<int> distortion_indices;
};

const std::vector<EffectInfo>& EffectCatalogue();
const EffectInfo& Info(Effect e);
std::optional<Effect> EffectFromName(std::string_view name);
inline bool IsKinematic(Effect e) { return static_cast<int>(e) < kNumKinematicEffects; }
// A group of OpenCV distortion coefficients (per zoom).
inline bool IsDistortion(Effect e) {
  return kEffectRows[static_cast<int>(e)].kind == EffectKind::kDistortion;
}
// An effect of each zoom's camera (distortion groups and focus): its
// parameters live in the cameras (CameraTool), not in effect_values.
inline bool IsCameraEffect(Effect e) {
  const EffectKind kind = kEffectRows[static_cast<int>(e)].kind;
  return kind == EffectKind::kDistortion || kind == EffectKind::kFocus;
}
// An effect of each board of estimated pose (board_warp): its parameters
// live in InstrumentModel::board_warps, one pair per board.
inline bool IsBoardEffect(Effect e) {
  return kEffectRows[static_cast<int>(e)].kind == EffectKind::kBoard;
}
// Number of parameters of a per-board effect per board.
constexpr int kNumBoardWarp = 2;

// The distortion group (effect) that owns coefficient `index`.
inline Effect DistortionGroupOf(int index) { return kDistortionCoefficients[index].group; }
// Scale from SI to report units of an effect's (amplitude) parameter: 206265
// arcsec/rad, 1e6 ppm, 1e3 mm/m, from its first report unit.
double ReportScale(Effect e);

// Parameters of one effect in report units (arcsec, mm, ppm, degrees), polar
// pairs converted to amplitude and phase.
struct EffectReportValue {
  std::array<double, 2> value{};
  std::array<double, 2> sigma{};
  int num = 0;
};
// `si` and `cov` are the effect's SI parameters and their 2x2 covariance (row
// major; only the leading num_params block is read).
EffectReportValue ToReportUnits(Effect e, const std::array<double, 2>& si,
                                const std::array<double, 4>& cov);
// Inverse of ToReportUnits for values read from a config (sigmas ignored).
std::array<double, 2> FromReportUnits(Effect e, const std::array<double, 2>& report);

class EffectSet {
 public:
  EffectSet() = default;
  bool Has(Effect e) const { return bits_[static_cast<int>(e)]; }
  void Add(Effect e) { bits_.set(static_cast<int>(e)); }
  void Remove(Effect e) { bits_.reset(static_cast<int>(e)); }
  bool Empty() const { return bits_.none(); }
  std::vector<Effect> List() const;
  std::vector<std::string> Names() const;
  bool operator==(const EffectSet& o) const { return bits_ == o.bits_; }

 private:
  std::bitset<kNumEffects> bits_;
};

}  // namespace rtscalib

// The physical-effects catalogue (SPEC section 4, docs/effects.md).
//
// An effect is an optional, named model component with physical units. This
// header is the one place that knows every effect: its name, its parameter
// count and order, the conversion from SI (radians, metres, ratios) to report
// units, and whether it is a kinematic, EDM or camera (distortion) effect.
// The fit switches effects on and off only through `EffectSet`.
//
// Parameterisation (chosen so that every effect is linear in its parameters at
// zero and well conditioned when the effect is absent):
//   collimation      [c]                     rad
//   tilting_axis     [i]                     rad
//   vertical_index   [v0]                    rad
//   hz_eccentricity  [e cos(phi_e), e sin(phi_e)]      rad; e sin(phi - phi_e) = p0 sin(phi) - p1
//   cos(phi) v_eccentricity   [e cos(theta_e), e sin(theta_e)]  rad; same form in theta hz_scale
//   [s]                     ratio v_scale          [s]                     ratio axis_wobble [w
//   cos(phi_w), w sin(phi_w)]      rad edm_offset       [k0]                    m edm_scale [m]
//   ratio edm_cyclic       [A cos(psi), A sin(psi)]           m; A sin(2 pi d/U + psi) = p0 sin(.)
//   + p1 cos(.) distortion groups: indices into OpenCV's 14 coefficients, per zoom.
#pragma once

#include <array>
#include <bitset>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace rtscalib {

enum class Effect : int {
  kCollimation = 0,
  kTiltingAxis,
  kVerticalIndex,
  kHzEccentricity,
  kVEccentricity,
  kHzScale,
  kVScale,
  kAxisWobble,
  kEdmOffset,
  kEdmScale,
  kEdmCyclic,
  kRadialDistortion,
  kTangentialDistortion,
  kRationalDistortion,
  kThinPrism,
  kSensorTilt,
};
constexpr int kNumEffects = 16;
// Effects with a parameter block of their own (the rest live in the per-zoom
// distortion block).
constexpr int kNumKinematicEffects = 11;
constexpr int kMaxEffectParams = 2;

enum class EffectKind { kAngle, kAxis, kEdm, kDistortion };

struct EffectInfo {
  Effect effect;
  const char* name;
  EffectKind kind;
  int num_params;  // kinematic effects: size of its block
  std::array<const char*, 2> param_names;
  std::array<const char*, 2> report_units;  // after polar conversion (see below)
  const char* definition;
  const char* signature;
  // True when, in the `dh` kinematics, the DH links and free tool transforms
  // already contain this effect (SPEC section 4).
  bool redundant_in_dh;
  // Distortion coefficients this group owns (indices into k1 k2 p1 p2 k3 k4 k5
  // k6 s1 s2 s3 s4 taux tauy); empty for kinematic effects.
  std::vector<int> distortion_indices;
};

const std::vector<EffectInfo>& EffectCatalogue();
const EffectInfo& Info(Effect e);
std::optional<Effect> EffectFromName(std::string_view name);
inline bool IsKinematic(Effect e) { return static_cast<int>(e) < kNumKinematicEffects; }
inline bool IsDistortion(Effect e) { return !IsKinematic(e); }

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

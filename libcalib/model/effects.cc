#include "libcalib/model/effects.h"

#include <cmath>
#include <stdexcept>

namespace rtscalib {
namespace {

constexpr double kArcsecPerRad = 180.0 * 3600.0 / M_PI;
constexpr double kDegPerRad = 180.0 / M_PI;

std::vector<EffectInfo> MakeCatalogue() {
  using K = EffectKind;
  return {
      {Effect::kCollimation,
       "collimation",
       K::kAxis,
       1,
       {"c", ""},
       {"arcsec", ""},
       "line of sight turned by c about the telescope's y axis (after the tilt about the trunnion "
       "axis)",
       "dHz = +c/sin(z) face 1, -c/sin(z) face 2",
       true,
       {}},
      {Effect::kTiltingAxis,
       "tilting_axis",
       K::kAxis,
       1,
       {"i", ""},
       {"arcsec", ""},
       "trunnion axis turned by i about the alidade's y axis (before the tilt)",
       "dHz = +i*cot(z) face 1, opposite face 2",
       true,
       {}},
      {Effect::kVerticalIndex,
       "vertical_index",
       K::kAngle,
       1,
       {"v0", ""},
       {"arcsec", ""},
       "theta* = theta + v0",
       "constant dz, flips sign with face",
       true,
       {}},
      {Effect::kHzEccentricity,
       "hz_eccentricity",
       K::kAngle,
       2,
       {"e", "phi_e"},
       {"arcsec", "deg"},
       "phi* = phi + e*sin(phi - phi_e)",
       "once per turn in phi",
       false,
       {}},
      {Effect::kVEccentricity,
       "v_eccentricity",
       K::kAngle,
       2,
       {"e", "theta_e"},
       {"arcsec", "deg"},
       "theta* = theta + e*sin(theta - theta_e)",
       "once per turn in theta",
       false,
       {}},
      {Effect::kHzScale,
       "hz_scale",
       K::kAngle,
       1,
       {"s", ""},
       {"ppm", ""},
       "phi* = phi + s*phi",
       "grows with phi",
       false,
       {}},
      {Effect::kVScale,
       "v_scale",
       K::kAngle,
       1,
       {"s", ""},
       {"ppm", ""},
       "theta* = theta + s*theta",
       "grows with theta",
       false,
       {}},
      {Effect::kAxisWobble,
       "axis_wobble",
       K::kAxis,
       2,
       {"w", "phi_w"},
       {"arcsec", "deg"},
       "vertical axis tilted by Rx(w cos(phi-phi_w)) Ry(w sin(phi-phi_w)) before the phi rotation",
       "once per turn tilt",
       false,
       {}},
      {Effect::kEdmOffset,
       "edm_offset",
       K::kEdm,
       1,
       {"k0", ""},
       {"mm", ""},
       "d* = d + k0",
       "constant along the ray",
       true,
       {}},
      {Effect::kEdmScale,
       "edm_scale",
       K::kEdm,
       1,
       {"m", ""},
       {"ppm", ""},
       "d* = d (1 + m)",
       "grows with d",
       false,
       {}},
      {Effect::kEdmCyclic,
       "edm_cyclic",
       K::kEdm,
       2,
       {"A", "psi"},
       {"mm", "deg"},
       "d* = d + A sin(2 pi d / U + psi), U configured",
       "periodic in d",
       false,
       {}},
      {Effect::kRadialDistortion,
       "radial_distortion",
       K::kDistortion,
       0,
       {"", ""},
       {"", ""},
       "OpenCV k1 k2 k3",
       "radial in the image",
       false,
       {0, 1, 4}},
      {Effect::kTangentialDistortion,
       "tangential_distortion",
       K::kDistortion,
       0,
       {"", ""},
       {"", ""},
       "OpenCV p1 p2",
       "decentring",
       false,
       {2, 3}},
      {Effect::kRationalDistortion,
       "rational_distortion",
       K::kDistortion,
       0,
       {"", ""},
       {"", ""},
       "OpenCV k4 k5 k6",
       "wide-angle radial",
       false,
       {5, 6, 7}},
      {Effect::kThinPrism,
       "thin_prism",
       K::kDistortion,
       0,
       {"", ""},
       {"", ""},
       "OpenCV s1..s4",
       "thin prism",
       false,
       {8, 9, 10, 11}},
      {Effect::kSensorTilt,
       "sensor_tilt",
       K::kDistortion,
       0,
       {"", ""},
       {"", ""},
       "OpenCV taux tauy",
       "sensor tilt (Scheimpflug)",
       false,
       {12, 13}},
  };
}

// Scale from SI to report units for a one-parameter effect or for the
// amplitude of a polar pair.
double ReportScale(Effect e) {
  switch (e) {
    case Effect::kHzScale:
    case Effect::kVScale:
    case Effect::kEdmScale:
      return 1e6;
    case Effect::kEdmOffset:
    case Effect::kEdmCyclic:
      return 1e3;
    default:
      return kArcsecPerRad;
  }
}

}  // namespace

const std::vector<EffectInfo>& EffectCatalogue() {
  static const std::vector<EffectInfo> catalogue = MakeCatalogue();
  return catalogue;
}

const EffectInfo& Info(Effect e) { return EffectCatalogue()[static_cast<int>(e)]; }

std::optional<Effect> EffectFromName(std::string_view name) {
  for (const EffectInfo& info : EffectCatalogue()) {
    if (name == info.name) return info.effect;
  }
  return std::nullopt;
}

EffectReportValue ToReportUnits(Effect e, const std::array<double, 2>& si,
                                const std::array<double, 4>& cov) {
  const EffectInfo& info = Info(e);
  EffectReportValue out;
  out.num = info.num_params;
  const double scale = ReportScale(e);
  if (info.num_params == 1) {
    out.value[0] = si[0] * scale;
    out.sigma[0] = std::sqrt(std::max(cov[0], 0.0)) * scale;
    return out;
  }
  // Polar pair (p0, p1) = (A cos(phase), A sin(phase)).
  const double a = std::hypot(si[0], si[1]);
  const double phase = std::atan2(si[1], si[0]);
  // Jacobian of (A, phase) wrt (p0, p1).
  double ja[2] = {0, 0}, jp[2] = {0, 0};
  if (a > 0) {
    ja[0] = si[0] / a;
    ja[1] = si[1] / a;
    jp[0] = -si[1] / (a * a);
    jp[1] = si[0] / (a * a);
  }
  auto quad = [&](const double* j) {
    return j[0] * j[0] * cov[0] + 2 * j[0] * j[1] * cov[1] + j[1] * j[1] * cov[3];
  };
  out.value[0] = a * scale;
  out.value[1] = phase * kDegPerRad;
  out.sigma[0] = std::sqrt(std::max(quad(ja), 0.0)) * scale;
  out.sigma[1] = a > 0 ? std::sqrt(std::max(quad(jp), 0.0)) * kDegPerRad : 180.0;
  return out;
}

std::array<double, 2> FromReportUnits(Effect e, const std::array<double, 2>& report) {
  const EffectInfo& info = Info(e);
  const double scale = ReportScale(e);
  if (info.num_params == 1) return {report[0] / scale, 0.0};
  const double a = report[0] / scale;
  const double phase = report[1] / kDegPerRad;
  return {a * std::cos(phase), a * std::sin(phase)};
}

std::vector<Effect> EffectSet::List() const {
  std::vector<Effect> out;
  for (int i = 0; i < kNumEffects; ++i) {
    if (bits_[i]) out.push_back(static_cast<Effect>(i));
  }
  return out;
}

std::vector<std::string> EffectSet::Names() const {
  std::vector<std::string> out;
  for (Effect e : List()) out.emplace_back(Info(e).name);
  return out;
}

}  // namespace rtscalib

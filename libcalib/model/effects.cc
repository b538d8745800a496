#include "libcalib/model/effects.h"

#include <cmath>
#include <stdexcept>

namespace rtscalib {
namespace {

constexpr double kArcsecPerRad = 180.0 * 3600.0 / M_PI;
constexpr double kDegPerRad = 180.0 / M_PI;

std::vector<EffectInfo> MakeCatalogue() {
  std::vector<EffectInfo> out;
  for (const EffectRow& r : kEffectRows) {
    EffectInfo info{r.effect,
                    r.name,
                    r.kind,
                    r.num_params,
                    r.param_names,
                    r.report_units,
                    r.definition,
                    r.signature,
                    r.redundant_in_dh,
                    r.needs,
                    {}};
    for (const DistortionCoefficient& c : kDistortionCoefficients) {
      if (c.group == r.effect) info.distortion_indices.push_back(c.index);
    }
    out.push_back(std::move(info));
  }
  return out;
}

}  // namespace

double ReportScale(Effect e) {
  const std::string_view unit = Info(e).report_units[0];
  if (unit == "ppm") return 1e6;
  if (unit == "mm") return 1e3;
  // arcsec, and distortion groups (which have no report value of their own).
  return kArcsecPerRad;
}

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

#include "libcalib/diagnose/wild_fit.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "libcalib/text/number_text.h"

namespace rtscalib {
namespace {

std::string ValueText(double value, double sigma, const std::string& unit = "") {
  std::string out = Fmt("%.3g", value);
  if (sigma > 0) out += " +- " + Fmt("%.2g", sigma);
  return out + (unit.empty() ? "" : " " + unit);
}

// Sigma of every base column of the camera's intrinsics and focus: the
// diagonal of (J^T J)^-1 for those columns (NaN when the normal matrix is
// singular), keyed by column.
std::map<int, double> CameraSigmas(const Linearization& lin) {
  std::map<int, double> out;
  std::vector<int> columns;
  for (size_t c = 0; c < lin.base_columns.size(); ++c) {
    const FreeColumn& col = lin.base_columns[c];
    if (col.zoom < 0) continue;
    const bool intrinsics = !col.effect && col.name.find(".rotation") == std::string::npos &&
                            col.name.find(".t[") == std::string::npos;
    const bool focus = col.effect && *col.effect == Effect::kFocus;
    if (intrinsics || focus) columns.push_back(static_cast<int>(c));
  }
  if (columns.empty()) return out;
  const Eigen::MatrixXd normal = lin.base.transpose() * lin.base;
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(normal);
  const bool ok = ldlt.info() == Eigen::Success && ldlt.rcond() > 1e-300;
  for (int c : columns) {
    double sigma = std::nan("");
    if (ok) {
      Eigen::VectorXd unit = Eigen::VectorXd::Zero(normal.rows());
      unit[c] = 1.0;
      const double v = ldlt.solve(unit)[c];
      if (std::isfinite(v)) sigma = std::sqrt(std::max(v, 0.0));
    }
    out[c] = sigma;
  }
  return out;
}

}  // namespace

std::vector<WildParameter> FindWildParameters(const Linearization& lin,
                                              const InstrumentModel& model,
                                              const DistortionTerms& terms,
                                              const std::map<int, double>& min_distance) {
  std::vector<WildParameter> out;
  for (const DistortionTerm& t : terms.terms) {
    if (!t.wild) continue;
    const CameraTool& cam = model.cams[t.zoom];
    const int size = std::max(cam.width, cam.height);
    WildParameter w;
    w.name = t.name + " of zoom " + std::to_string(t.zoom);
    w.zoom = t.zoom;
    w.value = ValueText(t.value, t.sigma);
    w.undetermined = t.corner_px > size;
    w.why = w.undetermined ? "its sigma alone moves the image corners by " +
                                 Fmt("%.3g", t.corner_px) + " px"
                           : "its value moves the image corners by " +
                                 Fmt("%.3g", t.corner_value_px) + " px";
    w.why += ", more than the image (" + std::to_string(size) + " px)";
    out.push_back(w);
  }

  const std::map<int, double> sigma = CameraSigmas(lin);
  auto sigma_of = [&](int zoom, const std::string& name) {
    for (const auto& [c, s] : sigma) {
      if (lin.base_columns[c].zoom == zoom && lin.base_columns[c].name == name) return s;
    }
    return 0.0;
  };
  for (int z = 0; z < model.NumZooms(); ++z) {
    const CameraTool& cam = model.cams[z];
    if (!cam.determined) continue;
    const std::string zs = "cam[" + std::to_string(z) + "].";
    const std::string of = " of zoom " + std::to_string(z);
    const int size = std::max(cam.width, cam.height);
    for (int i = 0; i < kNumIntrinsics; ++i) {
      const double v = cam.intrinsics[i];
      const double s = sigma_of(z, zs + kIntrinsicsParamNames[i]);
      WildParameter w;
      w.name = std::string(kIntrinsicsParamNames[i]) + of;
      w.zoom = z;
      w.value = ValueText(v, s, "px");
      if (s > size) {
        w.undetermined = true;
        w.why = "its sigma is more than the image (" + std::to_string(size) + " px)";
      } else if (i < 2 && !(v > 0)) {
        w.why = "a focal length must be positive";
      } else if (i == 1 && cam.intrinsics[0] > 0 &&
                 std::abs(v / cam.intrinsics[0] - 1.0) > kMaxAspect) {
        w.why = "fy / fx = " + Fmt("%.4g", v / cam.intrinsics[0]) +
                ": no sensor's pixels are that far from square";
      } else if (i >= 2 && (v < -0.5 || v > (i == 2 ? cam.width : cam.height) - 0.5)) {
        w.why = "the principal point lies outside the image";
      }
      if (!w.why.empty()) out.push_back(w);
    }
    if (model.effects.Has(Effect::kFocus)) {
      const auto it = min_distance.find(z);
      const double d = it != min_distance.end() ? it->second : 0.0;
      for (int i = 0; i < kNumFocus; ++i) {
        const double v = cam.focus[i];
        const double s = sigma_of(z, zs + kFocusParamNames[i]);
        WildParameter w;
        w.name = std::string("focus ") + kFocusParamNames[i] + of;
        w.zoom = z;
        w.value = ValueText(v * kFocusReportScale[i], s * kFocusReportScale[i],
                            kFocusReportUnits[i]);
        if (i == kFocusKf) {
          if (std::abs(v) > kMaxFocusKf) {
            w.why = "more than a telescope camera's focal length (" + Fmt("%g", kMaxFocusKf) +
                    " m)";
          } else if (d > 0 && s / d > 0.5) {
            w.undetermined = true;
            w.why = "its sigma changes the camera constant by more than half at the nearest "
                    "target (" + Fmt("%.3g", d) + " m)";
          } else if (d > 0 && v / d < -0.5) {
            w.why = "it halves the camera constant at the nearest target (" + Fmt("%.3g", d) +
                    " m)";
          }
        } else if (d > 0) {
          if (s / d > size) {
            w.undetermined = true;
            w.why = "its sigma moves the principal point by more than the image at the nearest "
                    "target (" + Fmt("%.3g", d) + " m)";
          } else if (std::abs(v) / d > size) {
            w.why = "it moves the principal point by more than the image at the nearest target (" +
                    Fmt("%.3g", d) + " m)";
          }
        }
        if (!w.why.empty()) out.push_back(w);
      }
    }
  }

  for (Effect e : model.effects.List()) {
    if (!IsKinematic(e)) continue;
    const EffectInfo& info = Info(e);
    const EffectReportValue v = ToReportUnits(e, model.EffectValue(e), {0, 0, 0, 0});
    const std::string unit = info.report_units[0];
    const double bound = unit == "arcsec" ? kMaxArcsec : unit == "ppm" ? kMaxPpm : kMaxMm;
    if (std::abs(v.value[0]) <= bound) continue;
    WildParameter w;
    w.name = info.name;
    w.value = ValueText(v.value[0], 0, unit);
    w.why = "beyond " + Fmt("%g", bound) + " " + unit + ": no working instrument is that far off";
    out.push_back(w);
  }
  return out;
}

}  // namespace rtscalib

#include "libcalib/diagnose/distortion_terms.h"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include "libcalib/camera/opencv_model.h"
#include "libcalib/fit/parameterization.h"
#include "libcalib/text/number_text.h"

namespace rtscalib {
namespace {

// Central-difference step of the corner derivative; the distortion is linear
// in every coefficient but k4..k6 and the tilt, where 1e-6 leaves a relative
// error of ~1e-12, far below the rule's factor of 1.
constexpr double kStep = 1e-6;

// Data that reach this fraction of the half-diagonal cover the image: the
// corners themselves are never observed (a board's corner points sit inside
// its border).
constexpr double kWholeImage = 0.95;

// The power of the normalised radius r that coefficient `index` multiplies
// in the distortion (k1 r^2, k2 r^4, k3 r^6, ...; the tilt: none). Among the
// coefficients of a zoom and group that qualify, the highest power is
// dropped first: data without the image corners cannot tell r^4 from r^6
// (k2 and k3 correlate), and the series is truncated from the top, as
// OpenCV's CALIB_FIX_K3 practice does.
int RadialPower(int index) {
  switch (index) {
    case kK1:
    case kK4:
    case kP1:
    case kP2:
    case kS1:
    case kS3:
      return 2;
    case kK2:
    case kK5:
    case kS2:
    case kS4:
      return 4;
    case kK3:
    case kK6:
      return 6;
    default:
      return 0;
  }
}

// max over the four image corners of |d pixel / d coefficient `index`| [px],
// at the rays that the camera now maps to the corners; with `fraction` < 1,
// at the points that far from the principal point towards each corner (the
// edge of data that reach that fraction of the half-diagonal).
double CornerDerivative(const CameraTool& cam, int index, double fraction = 1.0) {
  const double w = cam.width, h = cam.height;
  const double cx = cam.intrinsics[2], cy = cam.intrinsics[3];
  const double half = 0.5 * std::hypot(w, h);
  double corners[4][2] = {{-0.5, -0.5}, {w - 0.5, -0.5}, {-0.5, h - 0.5}, {w - 0.5, h - 0.5}};
  if (fraction < 1.0) {
    // Along the diagonals, at `fraction` of the half-diagonal from the
    // principal point (the reach Coverage::corner_fraction measures).
    for (auto& corner : corners) {
      const double du = corner[0] - cx, dv = corner[1] - cy, norm = std::hypot(du, dv);
      if (!(norm > 0)) continue;
      corner[0] = cx + du / norm * fraction * half;
      corner[1] = cy + dv / norm * fraction * half;
    }
  }
  double best = 0;
  for (const auto& corner : corners) {
    double x = 0, y = 0;
    if (!UndistortPixel(cam.intrinsics.data(), cam.distortion.data(), corner, &x, &y)) {
      // Beyond the trusted region: the ray of the undistorted corner.
      x = (corner[0] - cam.intrinsics[2]) / cam.intrinsics[0];
      y = (corner[1] - cam.intrinsics[3]) / cam.intrinsics[1];
    }
    const double point[3] = {x, y, 1.0};
    std::array<double, kNumDistortion> plus = cam.distortion, minus = cam.distortion;
    plus[index] += kStep;
    minus[index] -= kStep;
    double p[2], m[2];
    if (!ProjectToPixel(cam.intrinsics.data(), plus.data(), point, p) ||
        !ProjectToPixel(cam.intrinsics.data(), minus.data(), point, m)) {
      continue;
    }
    best = std::max(best, std::hypot(p[0] - m[0], p[1] - m[1]) / (2 * kStep));
  }
  return best;
}

std::string List(const std::vector<int>& indices) {
  std::string out = "[";
  for (size_t i = 0; i < indices.size(); ++i) {
    out += (i ? ", " : "") + std::string(kDistortionCoefficientNames[indices[i]]);
  }
  return out + "]";
}

// The group's config line with `drops` (zoom, index) held as well.
std::string ConfigLine(const InstrumentModel& model, Effect group,
                       const std::set<std::pair<int, int>>& drops) {
  std::vector<std::vector<int>> fitted(model.NumZooms());
  for (int z = 0; z < model.NumZooms(); ++z) {
    for (int index : Info(group).distortion_indices) {
      if (DistortionIsFree(model, z, index) && !drops.count({z, index})) {
        fitted[z].push_back(index);
      }
    }
  }
  // The list most zooms share (the lowest zoom's on a tie) is `coefficients`.
  std::map<std::vector<int>, int> count;
  for (const std::vector<int>& f : fitted) ++count[f];
  std::vector<int> common = fitted.empty() ? std::vector<int>() : fitted[0];
  for (const std::vector<int>& f : fitted) {
    if (count[f] > count[common]) common = f;
  }
  std::string line = std::string("model.") + Info(group).name + ": {coefficients: " + List(common);
  std::string zooms;
  for (int z = 0; z < model.NumZooms(); ++z) {
    if (fitted[z] == common) continue;
    zooms += (zooms.empty() ? "" : ", ") + std::to_string(z) + ": " + List(fitted[z]);
  }
  if (!zooms.empty()) line += ", zooms: {" + zooms + "}";
  return line + "}";
}

}  // namespace

std::vector<const DistortionTerm*> DistortionTerms::Drops() const {
  std::vector<const DistortionTerm*> out;
  for (const DistortionTerm& t : terms) {
    if (t.drop) out.push_back(&t);
  }
  return out;
}

std::string DistortionConfigLine(const InstrumentModel& model, Effect group, int drop_zoom,
                                 int drop_index) {
  std::set<std::pair<int, int>> drops;
  if (drop_zoom >= 0) drops.insert({drop_zoom, drop_index});
  return ConfigLine(model, group, drops);
}

DistortionTerms AssessDistortionTerms(const Linearization& lin, const InstrumentModel& model,
                                      const std::vector<double>& reach,
                                      const DistortionTermRules& rules) {
  DistortionTerms out;
  out.pixel_sigma = lin.sigma[static_cast<int>(ObsGroup::kPixel)];
  std::vector<int> columns;  // base columns of distortion coefficients
  for (size_t c = 0; c < lin.base_columns.size(); ++c) {
    const FreeColumn& col = lin.base_columns[c];
    if (col.effect && IsDistortion(*col.effect) && col.zoom >= 0) {
      columns.push_back(static_cast<int>(c));
    }
  }
  if (columns.empty()) return out;
  // C = (J^T J)^-1 on the distortion columns: solve N X = E for their unit
  // vectors. The fit's gauges are held, so N is regular; a singular N
  // (coefficients the data do not see at all) gives no assessment.
  const Eigen::MatrixXd normal = lin.base.transpose() * lin.base;
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(normal);
  if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > 1e-300)) return out;
  Eigen::MatrixXd unit = Eigen::MatrixXd::Zero(normal.rows(), columns.size());
  for (size_t k = 0; k < columns.size(); ++k) unit(columns[k], k) = 1.0;
  const Eigen::MatrixXd solved = ldlt.solve(unit);
  Eigen::MatrixXd cov(columns.size(), columns.size());
  for (size_t a = 0; a < columns.size(); ++a) {
    for (size_t b = 0; b < columns.size(); ++b) cov(a, b) = solved(columns[a], b);
  }
  if (!cov.allFinite()) return out;

  for (size_t a = 0; a < columns.size(); ++a) {
    const FreeColumn& col = lin.base_columns[columns[a]];
    DistortionTerm t;
    t.zoom = col.zoom;
    t.index = col.index;
    t.name = kDistortionCoefficientNames[col.index];
    t.group = *col.effect;
    t.value = model.cams[col.zoom].distortion[col.index];
    t.sigma = std::sqrt(std::max(cov(a, a), 0.0));
    const CameraTool& cam = model.cams[col.zoom];
    const double derivative = CornerDerivative(cam, col.index);
    t.corner_px = t.sigma * derivative;
    t.corner_value_px = std::fabs(t.value) * derivative;
    t.reach = col.zoom < static_cast<int>(reach.size()) && reach[col.zoom] > 0
                  ? std::min(reach[col.zoom], 1.0)
                  : 1.0;
    t.data_px = t.sigma * CornerDerivative(cam, col.index, t.reach);
    const double size = std::max(cam.width, cam.height);
    t.wild = t.corner_px > size || t.corner_value_px > size;
    for (size_t b = 0; b < columns.size(); ++b) {
      const FreeColumn& other = lin.base_columns[columns[b]];
      if (b == a || other.zoom != col.zoom) continue;
      const double s = std::sqrt(std::max(cov(a, a), 0.0) * std::max(cov(b, b), 0.0));
      const double rho = s > 0 ? cov(a, b) / s : 0.0;
      if (std::fabs(rho) > std::fabs(t.rho)) {
        t.rho = rho;
        t.partner = kDistortionCoefficientNames[other.index];
      }
    }
    out.terms.push_back(t);
  }

  // The rule, then the weakest candidate per zoom and group.
  std::map<std::pair<int, Effect>, DistortionTerm*> weakest;
  for (DistortionTerm& t : out.terms) {
    const double tvalue = t.sigma > 0 ? std::fabs(t.value) / t.sigma : 0.0;
    const bool zero = tvalue < rules.max_t;
    const bool corner = t.data_px > rules.max_corner_sigmas * out.pixel_sigma;
    const bool collinear = std::fabs(t.rho) > rules.max_rho;
    if (t.wild || !zero || !(corner || collinear)) continue;
    t.reason = t.name + " = " + Fmt("%.3g", t.value) + " +- " + Fmt("%.2g", t.sigma) +
               " is not distinguishable from 0 (|value| < " + Fmt("%g", rules.max_t) + " sigma)";
    if (corner) {
      t.reason += "; its sigma alone moves the points at the edge of the data by " +
                  Fmt("%.3g", t.data_px) + " px (pixel sigma " + Fmt("%.2g", out.pixel_sigma) +
                  " px; the observed points reach " + Fmt("%.0f", 100 * t.reach) +
                  " % of the image's half-diagonal" +
                  (t.reach < kWholeImage ? ", beyond which the distortion is extrapolated)"
                                         : ")");
    }
    if (collinear) t.reason += "; correlation with " + t.partner + " " + Fmt("%+.4f", t.rho);
    // The highest power first, then the smallest |v| / s.
    DistortionTerm*& w = weakest[{t.zoom, t.group}];
    const double wt = w && w->sigma > 0 ? std::fabs(w->value) / w->sigma : 0.0;
    if (!w || RadialPower(t.index) > RadialPower(w->index) ||
        (RadialPower(t.index) == RadialPower(w->index) && tvalue < wt)) {
      w = &t;
    }
  }
  std::map<Effect, std::set<std::pair<int, int>>> drops;
  for (auto& [key, t] : weakest) {
    t->drop = true;
    drops[t->group].insert({t->zoom, t->index});
  }
  for (DistortionTerm& t : out.terms) {
    if (t.drop) {
      t.config_line = ConfigLine(model, t.group, drops[t.group]);
    } else {
      t.reason.clear();
    }
  }
  return out;
}

}  // namespace rtscalib

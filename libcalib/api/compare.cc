#include "libcalib/api/compare.h"

#include <ceres/manifold.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "libcalib/camera/opencv_model.h"
#include "libcalib/fit/manifolds.h"
#include "libcalib/fit/parameter_layout.h"
#include "libcalib/geometry/convex_hull.h"
#include "libcalib/model/gauge.h"

namespace rtscalib {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

bool SameCamera(const CameraTool& a, const CameraTool& b) {
  return a.intrinsics == b.intrinsics && a.distortion == b.distortion;
}

// Unit ray of pixel (u, v) in the camera frame.
bool UnitRay(const CameraTool& cam, double u, double v, Eigen::Vector3d* ray) {
  const double pixel[2] = {u, v};
  double r[3];
  if (!PixelToRay(cam.intrinsics.data(), cam.distortion.data(), pixel, r)) return false;
  *ray = Eigen::Vector3d(r[0], r[1], r[2]).normalized();
  return ray->allFinite();
}

bool Project(const CameraTool& cam, const Eigen::Vector3d& x, Eigen::Vector2d* uv) {
  if (!(x.z() > 0) || !(x.head<2>().norm() / x.z() < MaxTrustedRadius(cam.distortion.data())))
    return false;
  return ProjectToPixel(cam.intrinsics.data(), cam.distortion.data(), x.data(), uv->data()) &&
         uv->allFinite();
}

// The rotation R minimising sum |R a_i - b_i|^2 (unit vectors, no centroid).
Eigen::Matrix3d BestRotation(const std::vector<Eigen::Vector3d>& a,
                             const std::vector<Eigen::Vector3d>& b) {
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < a.size(); ++i) h += a[i] * b[i].transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1 : 1;
  return svd.matrixV() * d * svd.matrixU().transpose();
}

double Rms(const std::vector<double>& v) {
  if (v.empty()) return kNan;
  double s = 0;
  for (double x : v) s += x * x;
  return std::sqrt(s / v.size());
}
double Max(const std::vector<double>& v) {
  if (v.empty()) return kNan;
  double m = 0;
  for (double x : v) m = std::max(m, x);
  return m;
}

ZoomDifference CompareZoom(const CameraTool& ca, const CameraTool& cb, int zoom,
                           const CompareOptions& o) {
  ZoomDifference z;
  z.zoom = zoom;
  z.cols = o.cols;
  z.rows = o.rows;
  z.width = ca.width;
  z.height = ca.height;
  z.diff_px.assign(o.cols * o.rows, kNan);
  z.inside.assign(o.cols * o.rows, 0);
  if (!ca.determined || !cb.determined) return z;
  z.compared = true;
  std::vector<Eigen::Vector3d> ra(o.cols * o.rows), rb(o.cols * o.rows);
  std::vector<char> ok(o.cols * o.rows, 0);
  std::vector<Eigen::Vector3d> fit_a, fit_b, all_a, all_b;
  for (int r = 0; r < o.rows; ++r) {
    for (int c = 0; c < o.cols; ++c) {
      const int k = r * o.cols + c;
      const Eigen::Vector2d q(z.CellU(c), z.CellV(r));
      z.inside[k] = InsideConvexHull(ca.valid_region, q) && InsideConvexHull(cb.valid_region, q);
      if (!UnitRay(ca, q.x(), q.y(), &ra[k]) || !UnitRay(cb, q.x(), q.y(), &rb[k])) continue;
      ok[k] = 1;
      all_a.push_back(ra[k]);
      all_b.push_back(rb[k]);
      if (z.inside[k]) {
        fit_a.push_back(ra[k]);
        fit_b.push_back(rb[k]);
      }
    }
  }
  if (fit_a.size() < 3) {
    fit_a = all_a;
    fit_b = all_b;
  }
  z.fit_cells = static_cast<int>(fit_a.size());
  const Eigen::Matrix3d rot = SameCamera(ca, cb) || fit_a.size() < 3 ? Eigen::Matrix3d::Identity()
                                                                     : BestRotation(fit_a, fit_b);
  z.rotation_rad = Eigen::AngleAxisd(rot).angle();
  std::vector<double> all, inside;
  for (int k = 0; k < o.cols * o.rows; ++k) {
    if (!ok[k]) continue;
    Eigen::Vector2d pa, pb;
    if (!Project(ca, ra[k], &pa) || !Project(cb, rot * ra[k], &pb)) continue;
    const double d = (pb - pa).norm();
    z.diff_px[k] = d;
    all.push_back(d);
    if (z.inside[k]) inside.push_back(d);
  }
  z.rms_px = Rms(all);
  z.max_px = Max(all);
  z.inside_rms_px = Rms(inside);
  z.inside_max_px = Max(inside);
  return z;
}

// b - a of one block in its tangent coordinates.
Eigen::VectorXd BlockDifference(const LayoutBlock& la, const InstrumentModel& a,
                                const LayoutBlock& lb, const InstrumentModel& b) {
  const double* x = la.const_data(a);
  const double* y = lb.const_data(b);
  Eigen::VectorXd d = Eigen::VectorXd::Zero(la.size);
  if (std::equal(x, x + la.ambient, y)) return d;  // exactly 0, not Minus's rounding
  // q and -q are one rotation: take the b nearer to a, or Minus would
  // report the other way round (an angle near 2 pi).
  double yq[4] = {0, 0, 0, 0};
  if (la.tangent != LayoutTangent::kEuclidean) {
    const double dot = x[0] * y[0] + x[1] * y[1] + x[2] * y[2] + x[3] * y[3];
    for (int i = 0; i < 4; ++i) yq[i] = dot < 0 ? -y[i] : y[i];
    y = yq;
  }
  switch (la.tangent) {
    case LayoutTangent::kEuclidean:
      for (int i = 0; i < la.size; ++i) d[i] = y[i] - x[i];
      break;
    case LayoutTangent::kQuaternion:
      // The inverse of the fit's Plus: q_b = exp(d) q_a.
      ceres::EigenQuaternionManifold().Minus(y, x, d.data());
      break;
    case LayoutTangent::kNoRoll:
      // q_b = q_a exp([d0, d1, 0]) (roll is not a parameter).
      QuaternionNoRollManifold().Minus(y, x, d.data());
      break;
  }
  return d;
}

// Both models put into one gauge before their parameters are compared: a
// gauge a fit held moves what depends on it, so the same instrument fitted
// in two gauges would show as differences far beyond the sigmas. The
// re-expressions are libcalib/model/gauge.h's (the same instrument, other
// parameter values); each model's covariance follows them (J P J^T).
struct Gauged {
  InstrumentModel model;
  Eigen::MatrixXd cov;  // ParameterLayout order; empty without one
  std::vector<LayoutBlock> layout;
  const LayoutBlock* Block(const std::string& name) const {
    for (const LayoutBlock& b : layout) {
      if (b.name == name) return &b;
    }
    return nullptr;
  }
  // Held by the fit: every coordinate `index` of block `name` has variance 0
  // (false without a covariance: nothing is known to be held).
  bool Held(const std::string& name, std::initializer_list<int> index = {}) const {
    const LayoutBlock* b = Block(name);
    if (!b || cov.rows() == 0) return false;
    std::vector<int> idx(index);
    if (idx.empty()) {
      for (int i = 0; i < b->size; ++i) idx.push_back(i);
    }
    for (int i : idx) {
      if (cov(b->offset + i, b->offset + i) != 0) return false;
    }
    return true;
  }
  // cov <- J cov J^T for J = identity but `r` on the rows of block `name`.
  void Transform(const std::string& name, const Eigen::MatrixXd& r) {
    const LayoutBlock* b = Block(name);
    if (!b || cov.rows() == 0) return;
    cov.middleRows(b->offset, b->size) = r * cov.middleRows(b->offset, b->size);
    cov.middleCols(b->offset, b->size) = cov.middleCols(b->offset, b->size) * r.transpose();
  }
  void Hold(const std::string& name) { Transform(name, Eigen::MatrixXd::Zero(3, 3)); }
};

Gauged MakeGauged(const CalibratedInstrument& x) {
  Gauged g{x.Model(), x.HasParameterCovariance() ? x.ParameterCovariance() : Eigen::MatrixXd(),
           ParameterLayout(x.Model())};
  return g;
}

// Reference frames. A fit with no known position holds the base at the
// instrument's ideal base frame (SPEC 7); one with known positions fits the
// base in their frame. When only one of the two holds its base, the other
// is re-expressed in its own ideal base frame (ToIdealBaseFrame): there the
// base is the gauge (its rows held) and everything else is frame-free, but
// for axis_wobble's phase, which turns with the frame about z
// (gauge.h; its 2 x 2 block turns with it).
void ToIdealBaseFrameOf(Gauged* g) {
  const Rigid3 new_from_old = ToIdealBaseFrame(&g->model);
  g->Hold("base.rotation");
  g->Hold("base.t");
  g->Transform(Info(Effect::kAxisWobble).name, AxisWobbleMap(new_from_old));
}

// dh link 2 is held at its start (the tools absorb it); two fits that
// started from different values hold different link 2s and their tools
// differ by M = M2_a^-1 M2_b (gauge.h, SetSecondLink). b's tools are
// re-expressed with a's link 2: tool' = M tool, so the tangents of the
// camera rotations (q -> exp(delta) q: delta' = R_M delta) and the tool
// translations (t' = R_M t + t_M) turn by R_M; the EDM's no-roll tangent
// (q -> q exp(delta)) is unchanged.
void SetSecondLinkOf(const DhLink& link, Gauged* g) {
  const InstrumentModel before = g->model;
  SetSecondLink(link, &g->model);
  const Eigen::Matrix3d r =
      g->model.edm.ToRigid().rotation * before.edm.ToRigid().rotation.transpose();
  g->Transform("edm.t", r);
  for (int z = 0; z < g->model.NumZooms(); ++z) {
    g->Transform("cam[" + std::to_string(z) + "].rotation", r);
    g->Transform("cam[" + std::to_string(z) + "].t", r);
  }
}

std::vector<std::string> IntoOneGauge(Gauged* a, Gauged* b) {
  std::vector<std::string> notes;
  const bool ideal_a = a->Held("base.rotation") && a->Held("base.t");
  const bool ideal_b = b->Held("base.rotation") && b->Held("base.t");
  if (ideal_a != ideal_b) {
    ToIdealBaseFrameOf(ideal_a ? b : a);
    notes.push_back(std::string("the ") + (ideal_a ? "first" : "second") +
                    " fit knew no position, so its reference frame is the instrument's ideal "
                    "base frame (SPEC 7); the " +
                    (ideal_a ? "second" : "first") +
                    " was re-expressed in its own ideal base frame before the parameters were "
                    "compared, and the base (the frame itself) is not compared");
  }
  // The first joint's zero offset and height (link1's gamma_offset and d)
  // are gauges of a dh model the fit holds at their starting values; they go
  // into the base (gamma = d = 0, SetFirstJointOffsets). The base's
  // covariance is unchanged: its rotation tangent is global (q -> exp(delta)
  // q), unaffected by a constant right factor, and its translation moves by
  // R (0, 0, d) with d's variance 0.
  const std::initializer_list<int> offsets = {kDhD, kDhGamma};
  if (a->model.kinematics == Kinematics::kDh && b->model.kinematics == Kinematics::kDh &&
      a->Held("link1", offsets) && b->Held("link1", offsets)) {
    SetFirstJointOffsets(0, 0, &a->model);
    SetFirstJointOffsets(0, 0, &b->model);
    notes.push_back(
        "link1's d and gamma_offset are gauges both fits held at their starting values: they "
        "were moved into the base frame (base Rz(gamma) Tz(d)) before the parameters were "
        "compared");
  }
  if (a->model.kinematics == Kinematics::kDh && b->model.kinematics == Kinematics::kDh &&
      a->Held("link2") && b->Held("link2") && a->model.links[1].p != b->model.links[1].p) {
    SetSecondLinkOf(a->model.links[1], b);
    notes.push_back(
        "link2 is a gauge both fits held, at different values: the second model's tools were "
        "re-expressed with the first's link2 before the parameters were compared");
  }
  return notes;
}

}  // namespace

std::string CompareOptions::Check() const {
  if (cols < 1 || rows < 1 || cols > 1000 || rows > 1000) return "cells must be 1..1000 each";
  return "";
}

Comparison CompareInstruments(const CalibratedInstrument& a, const CalibratedInstrument& b,
                              const CompareOptions& o) {
  const std::string msg = o.Check();
  if (!msg.empty()) throw std::invalid_argument("compare: " + msg);
  const InstrumentModel& ma = a.Model();
  const InstrumentModel& mb = b.Model();
  if (ma.NumZooms() != mb.NumZooms()) {
    throw std::invalid_argument("zoom levels 0.." + std::to_string(ma.NumZooms() - 1) +
                                " as the first model's, got " + std::to_string(mb.NumZooms()) +
                                " zoom level(s)");
  }
  for (int z = 0; z < ma.NumZooms(); ++z) {
    if (ma.cams[z].width != mb.cams[z].width || ma.cams[z].height != mb.cams[z].height) {
      throw std::invalid_argument(
          "zoom " + std::to_string(z) + "'s image size " + std::to_string(ma.cams[z].width) + "x" +
          std::to_string(ma.cams[z].height) + " as the first model's, got " +
          std::to_string(mb.cams[z].width) + "x" + std::to_string(mb.cams[z].height));
    }
  }
  Comparison out;
  out.full_covariance = a.HasFullParameterCovariance() && b.HasFullParameterCovariance();
  Gauged ga = MakeGauged(a), gb = MakeGauged(b);
  for (const std::string& note : IntoOneGauge(&ga, &gb)) out.notes.push_back(note);
  const InstrumentModel& gauge_a = ga.model;
  const InstrumentModel& gauge_b = gb.model;
  for (int z = 0; z < ma.NumZooms(); ++z) {
    out.zooms.push_back(CompareZoom(ma.cams[z], mb.cams[z], z, o));
  }
  const std::vector<LayoutBlock> la = ParameterLayout(ma), lb = ParameterLayout(mb);
  const bool sa = ga.cov.rows() > 0, sb = gb.cov.rows() > 0;
  double sum = 0;
  std::vector<std::pair<int, int>> compared;  // offsets in a's and b's covariance
  for (const LayoutBlock& ba : la) {
    const LayoutBlock* bb = nullptr;
    for (const LayoutBlock& x : lb) {
      if (x.name == ba.name && x.size == ba.size) bb = &x;
    }
    if (!bb) {
      out.notes.push_back("'" + ba.name + "' is only in the first model");
      continue;
    }
    const Eigen::VectorXd d = BlockDifference(ba, gauge_a, *bb, gauge_b);
    const double* xa = ba.const_data(gauge_a);
    const double* xb = bb->const_data(gauge_b);
    for (int i = 0; i < ba.size; ++i) {
      ParameterDifference p;
      p.block = ba.name;
      p.index = i;
      p.unit = ba.unit;
      const bool euclid = ba.tangent == LayoutTangent::kEuclidean;
      p.a = euclid ? xa[i] : 0.0;
      p.b = euclid ? xb[i] : d[i];
      p.difference = d[i];
      const double va = sa ? ga.cov(ba.offset + i, ba.offset + i) : 0.0;
      const double vb = sb ? gb.cov(bb->offset + i, bb->offset + i) : 0.0;
      p.sigma = std::sqrt(std::max(va, 0.0) + std::max(vb, 0.0));
      p.has_sigma = p.sigma > 0 && std::isfinite(p.sigma);
      p.normalised = p.has_sigma ? p.difference / p.sigma : 0.0;
      if (p.has_sigma) {
        sum += p.normalised * p.normalised;
        ++out.num_normalised;
        compared.push_back({ba.offset + i, bb->offset + i});
      }
      out.parameters.push_back(p);
    }
  }
  for (const LayoutBlock& x : lb) {
    bool found = false;
    for (const LayoutBlock& y : la) found = found || (y.name == x.name && y.size == x.size);
    if (!found) out.notes.push_back("'" + x.name + "' is only in the second model");
  }
  out.mean_square_normalised = out.num_normalised ? sum / out.num_normalised : 0.0;
  if (sa && sb && !compared.empty()) {
    const int p = static_cast<int>(compared.size());
    Eigen::MatrixXd c(p, p);
    for (int i = 0; i < p; ++i) {
      for (int j = 0; j < p; ++j) {
        c(i, j) = ga.cov(compared[i].first, compared[j].first) +
                  gb.cov(compared[i].second, compared[j].second);
      }
    }
    double rho2 = 0;
    for (int i = 0; i < p; ++i) {
      for (int j = 0; j < p; ++j) {
        const double d = c(i, i) * c(j, j);
        rho2 += d > 0 ? c(i, j) * c(i, j) / d : (i == j ? 1.0 : 0.0);
      }
    }
    out.effective_parameters = static_cast<double>(p) * p / rho2;
  }
  return out;
}

}  // namespace rtscalib

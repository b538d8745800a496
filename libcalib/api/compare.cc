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
bool Ray(const CameraTool& cam, double u, double v, Eigen::Vector3d* ray) {
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
      if (!Ray(ca, q.x(), q.y(), &ra[k]) || !Ray(cb, q.x(), q.y(), &rb[k])) continue;
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

// The first joint's zero offset and height (link1's gamma_offset and d) are
// gauges of a dh model: they rotate and lift the base frame about its z axis
// and nothing else (kinematics.h: Rz(joint + gamma) with t_z = d, and Rz, t_z
// commute with the joint), so the fit holds them at their starting values,
// which differ between two fits. base * [Rz(gamma), (0, 0, d)] with gamma =
// d = 0 is the same instrument; both models are put into that gauge before
// their parameters are compared. The base's covariance is unchanged: its
// rotation tangent is global (q -> exp(delta) q), unaffected by a constant
// right factor, and its translation moves by R (0, 0, d) with d's variance 0.
// Only when the model holds them (no variance in its covariance).
bool FirstJointOffsetsHeld(const CalibratedInstrument& instrument) {
  const InstrumentModel& m = instrument.Model();
  if (m.kinematics != Kinematics::kDh || !instrument.HasParameterCovariance()) return false;
  const Eigen::MatrixXd& c = instrument.ParameterCovariance();
  for (const LayoutBlock& b : ParameterLayout(m)) {
    if (b.name != "link1") continue;
    return c(b.offset + kDhD, b.offset + kDhD) == 0 &&
           c(b.offset + kDhGamma, b.offset + kDhGamma) == 0;
  }
  return false;
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
  InstrumentModel gauge_a = ma, gauge_b = mb;
  if (FirstJointOffsetsHeld(a) && FirstJointOffsetsHeld(b)) {
    SetFirstJointOffsets(0, 0, &gauge_a);
    SetFirstJointOffsets(0, 0, &gauge_b);
    out.notes.push_back(
        "link1's d and gamma_offset are gauges both fits held at their starting values: they "
        "were moved into the base frame (base Rz(gamma) Tz(d)) before the parameters were "
        "compared");
  }
  for (int z = 0; z < ma.NumZooms(); ++z) {
    out.zooms.push_back(CompareZoom(ma.cams[z], mb.cams[z], z, o));
  }
  const std::vector<LayoutBlock> la = ParameterLayout(ma), lb = ParameterLayout(mb);
  const bool sa = a.HasParameterCovariance(), sb = b.HasParameterCovariance();
  double sum = 0;
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
      const double va = sa ? a.ParameterCovariance()(ba.offset + i, ba.offset + i) : 0.0;
      const double vb = sb ? b.ParameterCovariance()(bb->offset + i, bb->offset + i) : 0.0;
      p.sigma = std::sqrt(std::max(va, 0.0) + std::max(vb, 0.0));
      p.has_sigma = p.sigma > 0 && std::isfinite(p.sigma);
      p.normalised = p.has_sigma ? p.difference / p.sigma : 0.0;
      if (p.has_sigma) {
        sum += p.normalised * p.normalised;
        ++out.num_normalised;
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
  return out;
}

}  // namespace rtscalib

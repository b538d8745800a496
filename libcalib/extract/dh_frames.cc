#include "libcalib/extract/dh_frames.h"

#include <cmath>

namespace rtscalib {

Eigen::Matrix3d LinkFrame::Rotation() const {
  Eigen::Matrix3d r;
  r.col(0) = x;
  r.col(1) = y;
  r.col(2) = z;
  return r;
}

LinkFrame FirstFrame(const Line3& axis) {
  LinkFrame f;
  f.o = axis.point;                   // Eq. 44
  f.z = axis.direction.normalized();  // Eq. 43
  const Eigen::Vector3d x0 = Eigen::Vector3d::UnitX();
  const Eigen::Vector3d px = x0 - x0.dot(f.z) * f.z;  // Eq. 45
  if (px.norm() >= kMinReferenceProjection) {
    f.x = px.normalized();
    f.y = f.z.cross(f.x);
  } else {
    const Eigen::Vector3d y0 = Eigen::Vector3d::UnitY();
    f.y = (y0 - y0.dot(f.z) * f.z).normalized();
    f.x = f.y.cross(f.z);
  }
  return f;
}

LinkFrame NextFrame(const LinkFrame& frame, const Line3& next_axis,
                    const LineTolerances& tolerances, ClosestPoints* closest) {
  const Line3 current{frame.o, frame.z};
  const ClosestPoints cp = ClosestPointsOfLines(current, next_axis, tolerances);
  if (closest) *closest = cp;
  LinkFrame f;
  f.z = next_axis.direction.normalized();  // Eq. 46
  f.o = cp.q_t;
  const Eigen::Vector3d cross = frame.z.cross(f.z);
  switch (cp.constellation) {  // Eq. 47
    case LineConstellation::kIntersecting:
      f.x = cross.normalized();
      break;
    case LineConstellation::kSkewed:
      f.x = (cp.q_t - cp.q_s).dot(cross) >= 0.0 ? cross.normalized()
                                                : Eigen::Vector3d(-cross.normalized());
      break;
    case LineConstellation::kParallel: {
      const Eigen::Vector3d v = cp.q_t - cp.q_s;
      f.x = (v - v.dot(frame.z) * frame.z).normalized();
      break;
    }
    case LineConstellation::kIdentical:
      f.x = frame.x;
      break;
  }
  f.y = f.z.cross(f.x).normalized();  // Eq. 48
  return f;
}

std::array<double, 4> DhParametersBetween(const LinkFrame& from, const LinkFrame& to) {
  const Eigen::Vector3d delta = to.o - from.o;
  std::array<double, 4> p{};
  p[kDhD] = delta.dot(from.z);
  p[kDhGamma] = std::atan2(from.x.cross(to.x).dot(from.z), from.x.dot(to.x));
  p[kDhA] = delta.dot(to.x);  // Eq. 49 prints x_i; x_{i+1} is consistent with Eq. 8
  p[kDhAlpha] = std::atan2(from.z.cross(to.z).dot(to.x), from.z.dot(to.z));
  return p;
}

}  // namespace rtscalib

#include "libcalib/geometry/lines.h"

#include <cmath>
#include <string>

namespace rtscalib {

const char* LineConstellationName(LineConstellation c) {
  switch (c) {
    case LineConstellation::kParallel:
      return "parallel";
    case LineConstellation::kSkewed:
      return "skewed";
    case LineConstellation::kIntersecting:
      return "intersecting";
    case LineConstellation::kIdentical:
      return "identical";
  }
  return "?";
}

std::string LineTolerances::Check() const {
  if (!(parallel_sin >= 0.0 && parallel_sin < 1.0)) {
    return "parallel_sin must be in [0, 1), got " + std::to_string(parallel_sin);
  }
  if (!(distance_m >= 0.0 && std::isfinite(distance_m))) {
    return "distance_m must be finite and >= 0, got " + std::to_string(distance_m);
  }
  return "";
}

ClosestPoints ClosestPointsOfLines(const Line3& l0, const Line3& l1,
                                   const LineTolerances& tolerances) {
  const Eigen::Vector3d& q0 = l0.point;
  const Eigen::Vector3d& q1 = l1.point;
  const Eigen::Vector3d& d0 = l0.direction;
  const Eigen::Vector3d& d1 = l1.direction;
  // Eq. 38, 39
  const double a = d0.squaredNorm();
  const double b = d0.dot(d1);
  const double c = d1.squaredNorm();
  const double d = d0.dot(q0 - q1);
  const double e = d1.dot(q0 - q1);
  const double det = a * c - b * b;

  ClosestPoints out;
  // |d0 x d1|^2 = a c - b^2 exactly; the cross product avoids the
  // cancellation of the difference for nearly parallel lines.
  out.sin_angle = d0.cross(d1).norm() / std::sqrt(a * c);
  const bool parallel = out.sin_angle <= tolerances.parallel_sin;
  if (parallel) {
    // Eq. 41: both forms give the foot of q_0 on L_1 (d0 = lambda d1 makes
    // d / b = e / c); the larger divisor is the better conditioned one.
    out.s = 0.0;
    out.t = b >= c ? d / b : e / c;
  } else {
    out.s = (b * e - c * d) / det;  // Eq. 37
    out.t = (a * e - b * d) / det;
  }
  out.q_s = q0 + out.s * d0;  // Eq. 42
  out.q_t = q1 + out.t * d1;
  out.distance = (out.q_s - out.q_t).norm();
  const bool touching = out.distance <= tolerances.distance_m;
  if (parallel) {
    out.constellation = touching ? LineConstellation::kIdentical : LineConstellation::kParallel;
  } else {
    out.constellation = touching ? LineConstellation::kIntersecting : LineConstellation::kSkewed;
  }
  return out;
}

}  // namespace rtscalib

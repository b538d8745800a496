// Closest points of two 3D lines and their constellation (Klug et al.
// Sec. 3.1.5, Eq. 33-42).
//
//   L_0(s) = q_0 + s d_0,  L_1(t) = q_1 + t d_1                          (Eq. 33)
//   a = |d_0|^2, b = d_0^T d_1, c = |d_1|^2,
//   d = d_0^T (q_0 - q_1), e = d_1^T (q_0 - q_1)                          (Eq. 38, 39)
//   not parallel: s = (b e - c d) / (a c - b^2), t = (a e - b d) / (a c - b^2)   (Eq. 37)
//   parallel:     s = 0, t = d / b if b >= c else e / c                   (Eq. 41)
//   q_s = L_0(s), q_t = L_1(t), distance = |q_s - q_t|                    (Eq. 34, 42)
//
// Constellation (Eq. 40 extended by the two special cases Eq. 47 needs):
//   parallel      sin(angle(d_0, d_1)) <= tol.parallel_sin, distance > tol.distance_m
//   identical     sin(angle) <= tol.parallel_sin, distance <= tol.distance_m
//   intersecting  sin(angle) >  tol.parallel_sin, distance <= tol.distance_m
//   skewed        sin(angle) >  tol.parallel_sin, distance >  tol.distance_m
// sin(angle)^2 = (a c - b^2) / (a c), so the parallel test is the paper's
// "ac - b^2 = 0" made scale free. The default tolerances (1e-9 for both) are a
// few thousand times double-precision round-off of unit-scale lines: they
// classify exact geometry and nothing else. Measured axes need tolerances of
// the order of the measurement noise (ExtractOptions sets its own).
// Units: metres (or whatever the points are in); angles as sines.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>

namespace rtscalib {

enum class LineConstellation { kParallel, kSkewed, kIntersecting, kIdentical };
const char* LineConstellationName(LineConstellation c);

struct Line3 {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();       // q
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();  // d, need not be unit; must be nonzero
};

struct LineTolerances {
  double parallel_sin = 1e-9;  // |sin| of the angle between the lines
  double distance_m = 1e-9;    // closest distance counted as touching
  std::string Check() const;   // empty if valid
};

struct ClosestPoints {
  double s = 0.0, t = 0.0;                        // s_c, t_c (Eq. 41)
  Eigen::Vector3d q_s = Eigen::Vector3d::Zero();  // on line 0 (Eq. 42)
  Eigen::Vector3d q_t = Eigen::Vector3d::Zero();  // on line 1 (Eq. 42)
  double distance = 0.0;                          // |q_s - q_t|
  double sin_angle = 0.0;                         // |sin| of the angle between the directions
  LineConstellation constellation = LineConstellation::kSkewed;
};

ClosestPoints ClosestPointsOfLines(const Line3& l0, const Line3& l1,
                                   const LineTolerances& tolerances = LineTolerances());

}  // namespace rtscalib

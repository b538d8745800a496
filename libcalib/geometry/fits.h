// Fits of planes, circles and lines to 3D point sets: the circular features of
// Klug et al. Sec. 3.1.3/3.1.4, and a line fit for prismatic (linear)
// trajectories.
//
// Plane (Eq. 13-20):
//   x_bar = mean(x_i)                                                (Eq. 14)
//   A_bar = [x_1 - x_bar ... x_N - x_bar],  A~ = A_bar / k,
//   k = max |a_ij| of A_bar                                          (Eq. 17, 18)
//   SVD(A~) = U S V^T, normal n = u_3 (smallest singular value)      (Eq. 15)
//   B = diag(1, 1, det U) U = [b_1 b_2 b_3], n = b_3  (right-handed) (Eq. 19, 20)
// The normalisation by k leaves U unchanged in exact arithmetic; it keeps the
// SVD's input at unit scale whatever the units and extent of the points.
//
// Circle in the plane (Eq. 21-30):
//   [u_i v_i]^T = [b_1 b_2]^T (x_i - x_bar) / k                      (Eq. 21)
//   2 u_i c_1 + 2 v_i c_2 + k_3 = u_i^2 + v_i^2                      (Eq. 23-26)
//   solved with the SVD pseudo-inverse                               (Eq. 27-29)
//   c = x_bar + k B [c_1 c_2 0]^T,  r = k sqrt(k_3 + c_1^2 + c_2^2)  (Eq. 30)
// Eq. 30 as printed has no factor k because the paper's Eq. 21 projects the
// unnormalised A_bar; projecting A~ and scaling back by k is the same circle.
//
// Sign of the normal (Eq. 31, 32): with x_1 recorded at a smaller control
// value than x_2 (and less than pi apart, footnote 6),
//   n~ = sign(((x_1 - c) x (x_2 - c))^T n) n,  sign(0) = +1,
// so that increasing the control is a positive rotation about n~.
//
// Units: whatever the points are in (metres in rtscalib); RMS values are in
// the same unit. Valid for N >= 3 points (plane, circle) and N >= 2 (line).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

namespace rtscalib {

struct PlaneFit {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();   // x_bar (Eq. 14)
  Eigen::Matrix3d basis = Eigen::Matrix3d::Identity();  // B = [b_1 b_2 b_3], det +1 (Eq. 19)
  double scale = 1.0;                                   // k (Eq. 18)
  // Singular values of A~ (Eq. 15), descending; they are scaled by 1/k.
  Eigen::Vector3d singular_values = Eigen::Vector3d::Zero();
  double rms = 0.0;  // RMS of the point-to-plane distances

  Eigen::Vector3d Normal() const { return basis.col(2); }  // n = b_3 (Eq. 20)
};

struct CircleFit {
  PlaneFit plane;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();   // c (Eq. 30)
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // plane normal, sign as fitted
  double radius = 0.0;                                // r (Eq. 30)
  // RMS of the points' 3D distances to the circle:
  // sqrt(mean(h_i^2 + (rho_i - r)^2)), h = out-of-plane, rho = in-plane distance to c.
  double rms = 0.0;
  // False when the in-plane system (Eq. 25) is rank deficient (collinear or
  // coincident points); centre, radius and rms are then +infinity.
  bool valid = false;
};

struct LineFit {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();       // the centroid, a point on the line
  Eigen::Vector3d direction = Eigen::Vector3d::UnitX();  // unit, sign as fitted
  double rms = 0.0;                                      // RMS of the perpendicular distances
  double extent = 0.0;  // max - min of the points' positions along the line
};

// Throws std::invalid_argument for fewer than 3 points.
PlaneFit FitPlane(const std::vector<Eigen::Vector3d>& points);
// Throws std::invalid_argument for fewer than 3 points.
CircleFit FitCircle(const std::vector<Eigen::Vector3d>& points);
// Total-least-squares line (first singular vector of A~). Throws
// std::invalid_argument for fewer than 2 points.
LineFit FitLine(const std::vector<Eigen::Vector3d>& points);

// Klug Eq. 31/32: `normal` turned so that going from x_first to x_second
// (recorded at increasing control values, less than pi apart) is a positive
// rotation about it around `center`.
Eigen::Vector3d CorrectNormalSign(const Eigen::Vector3d& normal, const Eigen::Vector3d& center,
                                  const Eigen::Vector3d& x_first, const Eigen::Vector3d& x_second);
// The prismatic counterpart: `direction` turned so that x_second - x_first
// (increasing control) points along it; sign(0) = +1 as in Eq. 32.
Eigen::Vector3d CorrectDirectionSign(const Eigen::Vector3d& direction,
                                     const Eigen::Vector3d& x_first,
                                     const Eigen::Vector3d& x_second);

}  // namespace rtscalib

// Elementary rotations, Euler angles and rigid transforms, templated so that
// Ceres can differentiate through them.
//
// Conventions (SPEC section 1, Klug et al. Eq. 6, 7, 83, 89):
//   Rx(a) = [1 0 0; 0 ca -sa; 0 sa ca]      (Eq. 6)
//   Ry(b) = [cb 0 sb; 0 1 0; -sb 0 cb]      (Eq. 89)
//   Rz(g) = [cg -sg 0; sg cg 0; 0 0 1]      (Eq. 7)
//   Euler: R = Rz(g) Ry(b) Rx(a), stored as [a, b, g]   (Eq. 83)
// A rotation matrix's columns are the rotated frame's axes in the outer frame,
// so `a_from_b` maps coordinates in frame b to coordinates in frame a.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace rtscalib {

template <typename T>
using Vec3 = Eigen::Matrix<T, 3, 1>;
template <typename T>
using Mat3 = Eigen::Matrix<T, 3, 3>;
template <typename T>
using Mat4 = Eigen::Matrix<T, 4, 4>;

template <typename T>
Mat3<T> Rx(const T& a) {
  using std::cos;
  using std::sin;
  const T c = cos(a), s = sin(a);
  Mat3<T> r;
  r << T(1), T(0), T(0), T(0), c, -s, T(0), s, c;
  return r;
}

template <typename T>
Mat3<T> Ry(const T& b) {
  using std::cos;
  using std::sin;
  const T c = cos(b), s = sin(b);
  Mat3<T> r;
  r << c, T(0), s, T(0), T(1), T(0), -s, T(0), c;
  return r;
}

template <typename T>
Mat3<T> Rz(const T& g) {
  using std::cos;
  using std::sin;
  const T c = cos(g), s = sin(g);
  Mat3<T> r;
  r << c, -s, T(0), s, c, T(0), T(0), T(0), T(1);
  return r;
}

// Klug et al. Eq. 83: R = Rz(g) Ry(b) Rx(a), euler = [a, b, g].
template <typename T>
Mat3<T> RotationFromEuler(const Vec3<T>& euler) {
  return Rz(euler[2]) * Ry(euler[1]) * Rx(euler[0]);
}

// Inverse of RotationFromEuler. Returns [a, b, g] with b in [-pi/2, pi/2]. At
// gimbal lock (|b| = pi/2) a is set to 0 and g carries the whole rotation
// about the common axis.
inline Eigen::Vector3d EulerFromRotation(const Eigen::Matrix3d& r) {
  const double sb = -r(2, 0);
  const double cb = std::hypot(r(0, 0), r(1, 0));
  const double b = std::atan2(sb, cb);
  if (cb > 1e-12) {
    return {std::atan2(r(2, 1), r(2, 2)), b, std::atan2(r(1, 0), r(0, 0))};
  }
  return {0.0, b, std::atan2(-r(0, 1), r(1, 1))};
}

// Wraps an angle to (-pi, pi].
inline double WrapAngle(double a) {
  a = std::fmod(a + M_PI, 2.0 * M_PI);
  if (a <= 0.0) a += 2.0 * M_PI;
  return a - M_PI;
}

// A rigid transform a_from_b: x_a = rotation * x_b + translation.
struct Rigid3 {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Eigen::Vector3d operator*(const Eigen::Vector3d& x) const { return rotation * x + translation; }
  Rigid3 operator*(const Rigid3& o) const {
    return {rotation * o.rotation, rotation * o.translation + translation};
  }
  Rigid3 Inverse() const { return {rotation.transpose(), -(rotation.transpose() * translation)}; }
  Eigen::Matrix4d Matrix() const {
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    m.topLeftCorner<3, 3>() = rotation;
    m.topRightCorner<3, 1>() = translation;
    return m;
  }
  static Rigid3 FromEuler(const Eigen::Vector3d& euler, const Eigen::Vector3d& t) {
    return {RotationFromEuler<double>(euler), t};
  }
};

}  // namespace rtscalib

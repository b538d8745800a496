// DH link frames from joint axes and the DH parameters between them (Klug et
// al. Sec. 3.1.5-3.1.8, Eq. 43-50).
//
// First frame (Eq. 43-45): z_1 = n~_1, o_1 = c_1,
//   x_1 = (x_0 - (x_0^T z_1) z_1) / |.|, y_1 = z_1 x x_1,
// with x_0 = reference x; when that projection is shorter than 1e-3 (the
// axis is within 0.06 deg of x_0: "plane p_1 parallel to the yz plane") the
// reference y is projected instead, y_1 = (y_0 - (y_0^T z_1) z_1) / |.|,
// x_1 = y_1 x z_1.
//
// Next frame (Eq. 46-48), from frame i and the axis L_{i+1} = (q, z_{i+1}):
//   (q_s, q_t) = closest points of L_i = (o_i, z_i) and L_{i+1}    (Eq. 33-42)
//   o_{i+1} = q_t,  z_{i+1} = unit direction of L_{i+1}
//   x_{i+1} = z_i x z_{i+1} / |.|          intersecting
//           = (q_t - q_s) / |q_t - q_s|    skewed or parallel
//           = x_i                          identical
//   y_{i+1} = z_{i+1} x x_{i+1} / |.|
// For skewed axes q_t - q_s is parallel to z_i x z_{i+1}; the code takes the
// cross product with the sign of q_t - q_s, which is the same unit vector
// without the cancellation in q_t - q_s. For parallel axes x_{i+1} is made
// exactly perpendicular to z_i (the DH convention needs it; the axes are
// parallel only to the tolerance).
// Last frame (Eq. 50): the frame after the last joint equals the last joint's
// frame, i.e. NextFrame with L_{i+1} = L_i (identical).
//
// DH parameters of M_{i,i+1} = Tz(d) Rz(gamma) Tx(a) Rx(alpha) (Eq. 8, 49):
//   d     = (o_{i+1} - o_i)^T z_i
//   gamma = atan2((x_i x x_{i+1})^T z_i, x_i^T x_{i+1})
//   a     = (o_{i+1} - o_i)^T x_{i+1}
//   alpha = atan2((z_i x z_{i+1})^T x_{i+1}, z_i^T z_{i+1})
// Deviation from the paper: Eq. 49 prints a_i = (o_{i+1} - o_i)^T x_i. With
// Eq. 8, o_{i+1} - o_i = d z_i + a x_{i+1} (the translation of M_{i,i+1} is
// [a cos(gamma), a sin(gamma), d] in frame i), so a is the component along
// x_{i+1}; the printed form is right only for gamma = 0.
// Units: metres and radians; all vectors in the reference frame.
#pragma once

#include <Eigen/Core>
#include <array>

#include "libcalib/geometry/lines.h"
#include "libcalib/model/instrument.h"

namespace rtscalib {

// A reference axis whose projection onto the plane normal to an axis is
// shorter than this falls back to the next reference axis (Eq. 45 and the
// camera tools' Eq. 79 with footnote 8): the axis is then within 0.06 deg of it.
constexpr double kMinReferenceProjection = 1e-3;

struct LinkFrame {
  Eigen::Vector3d o = Eigen::Vector3d::Zero();
  Eigen::Vector3d x = Eigen::Vector3d::UnitX();
  Eigen::Vector3d y = Eigen::Vector3d::UnitY();
  Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  Eigen::Matrix3d Rotation() const;  // [x y z]
  Rigid3 RefFromFrame() const { return {Rotation(), o}; }
};

// Eq. 43-45. `axis` is the joint-1 axis (point c_1, direction n~_1).
LinkFrame FirstFrame(const Line3& axis);

// Eq. 46-48 (and Eq. 50 with next_axis = the current axis). `closest`, if not
// null, receives the closest points and the constellation.
LinkFrame NextFrame(const LinkFrame& frame, const Line3& next_axis,
                    const LineTolerances& tolerances, ClosestPoints* closest = nullptr);

// Eq. 49 (corrected a, see above): {d, gamma, alpha, a} in DhLink order
// (kDhD, kDhGamma, kDhAlpha, kDhA), gamma being the full joint angle at the
// frames' configuration.
std::array<double, 4> DhParametersBetween(const LinkFrame& from, const LinkFrame& to);

}  // namespace rtscalib

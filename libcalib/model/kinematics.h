// Forward kinematics of both model families, templated for autodiff.
//
// Readings phi, theta, d become true values by the enabled effects (SPEC 4):
//   phi*   = phi + e_h sin(phi - phi_e) + s_h phi
//   theta* = theta + v0 + e_v sin(theta - theta_e) + s_v theta
//   d*     = d + k0 + m d + A sin(2 pi d / U + psi)
// Chain (SPEC 4; wobble rotates about the base origin in reference axes):
//   dh:        ref_from_flange = T(t_B) W(phi) R_B * Z1(phi*) X1 * Z2(theta*) X2        (Klug Eq.
//   2-9)
//              Z_i = Tz(d_i) Rz(q_i + gamma_i), X_i = Tx(a_i) Rx(alpha_i)              (Eq. 3, 4)
//   spherical: ref_from_flange = T(t_B) W(phi) R_B * Rz(-phi*) Ry(i) Rx(-theta*) Ry(c)  (Eq. 84-91)
//   none:      ref_from_flange = T(t_B) R_B, held at the identity: a camera-only
//              calibration (SPEC 7.1) has no chain; readings are not used
//   W(phi) = Rx(w cos(phi - phi_w)) Ry(w sin(phi - phi_w))
// In `dh`, collimation, tilting_axis, vertical_index and edm_offset are part of
// the links and tools; the fit never enables them there (reported redundant).
//
// Tools (Klug Eq. 9-12, 74-76, 96; SPEC 2):
//   F_EDM(phi, theta, d)       = ref_from_flange * flange_from_edm * [0 0 d* 1]
//   F_CAM(phi, theta, u, v, d) = ref_from_flange * flange_from_cam * (d * ray(u, v))
//   pixel of X                 = project(cam_from_ref * X)
// With the `focus` effect (SPEC 4.1, focus.h) the intrinsics are those at the
// focus distance D: D = d for F_CAM, the photo's D for a pixel.
#pragma once

#include <Eigen/Geometry>
#include <cmath>

#include "libcalib/camera/opencv_model.h"
#include "libcalib/geometry/rotation.h"
#include "libcalib/model/effects.h"
#include "libcalib/model/focus.h"
#include "libcalib/model/instrument.h"

namespace rtscalib {

// Pointers to the parameter blocks one evaluation needs. Effect pointers are
// null when the effect is off.
template <typename T>
struct ModelView {
  Kinematics kinematics = Kinematics::kDh;
  const T* base_q = nullptr;
  const T* base_t = nullptr;
  const T* link[2] = {nullptr, nullptr};
  const T* effect[kNumKinematicEffects] = {};
  double edm_cyclic_unit_length = 1.5;

  const T* E(Effect e) const { return effect[static_cast<int>(e)]; }
};

// A rigid transform with templated scalar.
template <typename T>
struct RigidT {
  Mat3<T> R = Mat3<T>::Identity();
  Vec3<T> t = Vec3<T>::Zero();
  Vec3<T> operator*(const Vec3<T>& x) const { return R * x + t; }
  RigidT operator*(const RigidT& o) const { return {R * o.R, R * o.t + t}; }
  Vec3<T> InverseApply(const Vec3<T>& x) const { return R.transpose() * (x - t); }
};

template <typename T>
RigidT<T> PoseFromBlocks(const T* q, const T* t) {
  RigidT<T> out;
  Eigen::Map<const Eigen::Quaternion<T>> quat(q);
  out.R = quat.toRotationMatrix();
  out.t = Vec3<T>(t[0], t[1], t[2]);
  return out;
}

template <typename T>
void TrueAngles(const ModelView<T>& m, const T& phi, const T& theta, T* phi_s, T* theta_s) {
  using std::cos;
  using std::sin;
  T p = phi, q = theta;
  if (const T* e = m.E(Effect::kHzEccentricity)) p += e[0] * sin(phi) - e[1] * cos(phi);
  if (const T* e = m.E(Effect::kHzScale)) p += e[0] * phi;
  if (const T* e = m.E(Effect::kVerticalIndex)) q += e[0];
  if (const T* e = m.E(Effect::kVEccentricity)) q += e[0] * sin(theta) - e[1] * cos(theta);
  if (const T* e = m.E(Effect::kVScale)) q += e[0] * theta;
  *phi_s = p;
  *theta_s = q;
}

template <typename T>
T TrueDistance(const ModelView<T>& m, const T& d) {
  using std::cos;
  using std::sin;
  T out = d;
  if (const T* e = m.E(Effect::kEdmOffset)) out += e[0];
  if (const T* e = m.E(Effect::kEdmScale)) out += e[0] * d;
  if (const T* e = m.E(Effect::kEdmCyclic)) {
    const T arg = T(2.0 * M_PI / m.edm_cyclic_unit_length) * d;
    out += e[0] * sin(arg) + e[1] * cos(arg);
  }
  return out;
}

// Klug Eq. 8: M_{i,i+1} = Tz(d) Rz(gamma) Tx(a) Rx(alpha).
template <typename T>
RigidT<T> DhLinkTransform(const T* link, const T& joint) {
  using std::cos;
  using std::sin;
  const T g = joint + link[kDhGamma];
  const T cg = cos(g), sg = sin(g);
  RigidT<T> out;
  out.R = Rz(g) * Rx(link[kDhAlpha]);
  out.t = Vec3<T>(link[kDhA] * cg, link[kDhA] * sg, link[kDhD]);
  return out;
}

template <typename T>
RigidT<T> RefFromFlange(const ModelView<T>& m, const T& phi, const T& theta) {
  using std::cos;
  using std::sin;
  RigidT<T> base = PoseFromBlocks(m.base_q, m.base_t);
  if (m.kinematics == Kinematics::kNone) return base;
  T phi_s, theta_s;
  TrueAngles(m, phi, theta, &phi_s, &theta_s);
  if (const T* w = m.E(Effect::kAxisWobble)) {
    const T wx = w[0] * cos(phi) + w[1] * sin(phi);  // w cos(phi - phi_w)
    const T wy = w[0] * sin(phi) - w[1] * cos(phi);  // w sin(phi - phi_w)
    base.R = Rx(wx) * Ry(wy) * base.R;
  }
  if (m.kinematics == Kinematics::kDh) {
    return base * DhLinkTransform(m.link[0], phi_s) * DhLinkTransform(m.link[1], theta_s);
  }
  Mat3<T> r = Rz(T(-phi_s));
  if (const T* i = m.E(Effect::kTiltingAxis)) r = r * Ry(i[0]);
  r = r * Rx(T(-theta_s));
  if (const T* c = m.E(Effect::kCollimation)) r = r * Ry(c[0]);
  base.R = base.R * r;
  return base;
}

// Klug Eq. 11/74-76: the EDM point in the reference frame.
template <typename T>
Vec3<T> EdmPoint(const ModelView<T>& m, const T* edm_q, const T* edm_t, const T& phi,
                 const T& theta, const T& d) {
  const RigidT<T> flange = RefFromFlange(m, phi, theta);
  const RigidT<T> tool = PoseFromBlocks(edm_q, edm_t);
  return flange * (tool * Vec3<T>(T(0), T(0), TrueDistance(m, d)));
}

// Klug Eq. 12/96 with SPEC 2: the point at ray length d through pixel (u, v);
// `focus` null without the focus effect, else the camera is focused at D = d.
template <typename T>
bool CamPoint(const ModelView<T>& m, const T* cam_q, const T* cam_t, const T* intrinsics,
              const T* distortion, const T* focus, const T& phi, const T& theta, const T* pixel,
              const T& d, Vec3<T>* out) {
  T k[4];
  if (!FocusedIntrinsics(intrinsics, focus, d, k)) return false;
  T ray[3];
  if (!PixelToRay(k, distortion, pixel, ray)) return false;
  const RigidT<T> flange = RefFromFlange(m, phi, theta);
  const RigidT<T> tool = PoseFromBlocks(cam_q, cam_t);
  *out = flange * (tool * Vec3<T>(d * ray[0], d * ray[1], d * ray[2]));
  return true;
}

// Klug Eq. 62: the pixel at which a reference-frame point is seen; `focus`
// null without the focus effect, else the camera is focused at
// `focus_distance`, or at the point's own distance when that is <= 0.
template <typename T>
bool ProjectPoint(const ModelView<T>& m, const T* cam_q, const T* cam_t, const T* intrinsics,
                  const T* distortion, const T* focus, const T& focus_distance, const T& phi,
                  const T& theta, const Vec3<T>& x_ref, T* pixel) {
  const RigidT<T> ref_from_cam = RefFromFlange(m, phi, theta) * PoseFromBlocks(cam_q, cam_t);
  const Vec3<T> x_cam = ref_from_cam.InverseApply(x_ref);
  T k[4];
  const T distance = focus_distance > T(0) ? focus_distance : T(x_cam.norm());
  if (!FocusedIntrinsics(intrinsics, focus, distance, k)) return false;
  return ProjectToPixel(k, distortion, x_cam.data(), pixel);
}

// ---------------------------------------------------------------------------
// Double-precision convenience on a whole InstrumentModel.
ModelView<double> ViewOf(const InstrumentModel& model);
Rigid3 RefFromFlange(const InstrumentModel& model, double phi, double theta);
Rigid3 RefFromEdm(const InstrumentModel& model, double phi, double theta);
Rigid3 RefFromCam(const InstrumentModel& model, int zoom, double phi, double theta);
Eigen::Vector3d PredictEdm(const InstrumentModel& model, double phi, double theta, double d);
// Throws std::runtime_error when the pixel cannot be undistorted. With the
// focus effect the camera is focused at D = d (SPEC 4.1).
Eigen::Vector3d PredictCam(const InstrumentModel& model, int zoom, double phi, double theta,
                           double u, double v, double d);
// Returns false for points behind the camera. With the focus effect the
// camera is focused at `focus_distance` [m] (a photo's D, PhotoFocusDistances
// in focus.h), or at the point's own distance when it is <= 0.
bool PredictPixel(const InstrumentModel& model, int zoom, double phi, double theta,
                  const Eigen::Vector3d& x_ref, Eigen::Vector2d* pixel,
                  double focus_distance = 0.0);
// The focus block of zoom `zoom` when the model has the focus effect, else null.
const double* FocusOf(const InstrumentModel& model, int zoom);

}  // namespace rtscalib

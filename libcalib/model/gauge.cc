#include "libcalib/model/gauge.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace rtscalib {
namespace {

// Klug Eq. 8 at joint angle 0: Tz(d) Rz(gamma) Tx(a) Rx(alpha).
Rigid3 LinkAtZero(const DhLink& link) {
  const double g = link.p[kDhGamma];
  return {Rz(g) * Rx(link.p[kDhAlpha]),
          Eigen::Vector3d(link.p[kDhA] * std::cos(g), link.p[kDhA] * std::sin(g), link.p[kDhD])};
}

Rigid3 FirstJointOffsets(double d, double gamma) {
  return {Rz(gamma), Eigen::Vector3d(0, 0, d)};
}

}  // namespace

Eigen::Matrix2d AxisWobbleMap(const Rigid3& new_from_old) {
  const Eigen::Matrix3d& r = new_from_old.rotation;
  const double psi = std::atan2(r(1, 0) - r(0, 1), r(0, 0) + r(1, 1));
  Eigen::Matrix2d map;
  map << std::cos(psi), std::sin(psi), -std::sin(psi), std::cos(psi);
  return map;
}

void ChangeReferenceFrame(const Rigid3& new_from_old, InstrumentModel* m) {
  if (m->effects.Has(Effect::kAxisWobble)) {
    const Eigen::Matrix3d& r = new_from_old.rotation;
    if (r(2, 2) < 0) {
      throw std::invalid_argument(
          "axis_wobble turns about the reference frame's x and y axes; the new frame's z axis is " +
          std::to_string(std::acos(std::max(-1.0, r(2, 2))) * 180.0 / M_PI) +
          " degrees from the old one's, which would reverse the wobble's sense");
    }
    std::array<double, 2>& w = m->EffectValue(Effect::kAxisWobble);
    const Eigen::Vector2d turned = AxisWobbleMap(new_from_old) * Eigen::Vector2d(w[0], w[1]);
    w = {turned.x(), turned.y()};
  }
  m->base = PoseBlock::FromRigid(new_from_old * m->base.ToRigid());
  for (EstimatedBoard& b : m->boards) {
    b.board.ref_from_board = new_from_old * b.pose.ToRigid();
    b.pose = PoseBlock::FromRigid(b.board.ref_from_board);
  }
  for (EstimatedPoint& p : m->points) {
    const Eigen::Vector3d x = new_from_old * Eigen::Vector3d(p.x[0], p.x[1], p.x[2]);
    p.x = {x.x(), x.y(), x.z()};
  }
}

void SetFirstJointOffsets(double d, double gamma_offset, InstrumentModel* m) {
  if (m->kinematics != Kinematics::kDh) return;
  std::array<double, 4>& link = m->links[0].p;
  m->base = PoseBlock::FromRigid(m->base.ToRigid() * FirstJointOffsets(link[kDhD], link[kDhGamma]) *
                                 FirstJointOffsets(d, gamma_offset).Inverse());
  link[kDhD] = d;
  link[kDhGamma] = gamma_offset;
}

void SetSecondLink(const DhLink& link, InstrumentModel* m) {
  if (m->kinematics != Kinematics::kDh) return;
  const Rigid3 new_from_old = LinkAtZero(link).Inverse() * LinkAtZero(m->links[1]);
  m->edm = PoseBlock::FromRigid(new_from_old * m->edm.ToRigid());
  for (CameraTool& c : m->cams) {
    c.flange_from_cam = PoseBlock::FromRigid(new_from_old * c.flange_from_cam.ToRigid());
  }
  m->links[1] = link;
}

Rigid3 ToIdealBaseFrame(InstrumentModel* m) {
  const InstrumentModel ideal = IdealModel(m->kinematics, 0, CameraTool());
  SetFirstJointOffsets(ideal.links[0].p[kDhD], ideal.links[0].p[kDhGamma], m);
  const Rigid3 new_from_old = ideal.base.ToRigid() * m->base.ToRigid().Inverse();
  ChangeReferenceFrame(new_from_old, m);
  m->base = ideal.base;  // exactly, not up to rounding
  return new_from_old;
}

}  // namespace rtscalib

#include "libcalib/fit/start_models.h"

#include "libcalib/model/kinematics.h"

namespace rtscalib {

InstrumentModel SphericalFromDh(const InstrumentModel& dh) {
  InstrumentModel s = dh;
  s.kinematics = Kinematics::kSpherical;
  const double phi = 0.0, theta = M_PI / 2;
  const Rigid3 ref_from_edm = RefFromEdm(dh, phi, theta);
  const Rigid3 ideal{Rz(-phi) * Rx(-theta), Eigen::Vector3d::Zero()};
  // Base rotation from the EDM direction, position from the flange origin.
  Rigid3 base;
  base.rotation = ref_from_edm.rotation * ideal.rotation.transpose();
  base.translation = RefFromFlange(dh, phi, theta).translation;
  s.base = PoseBlock::FromRigid(base);
  s.links = {};
  // EDM: ideal rotation; the dh EDM origin seen from the spherical flange.
  const Rigid3 ref_from_flange_s = base * ideal;
  const Eigen::Vector3d edm_origin = ref_from_flange_s.Inverse() * ref_from_edm.translation;
  s.edm = PoseBlock();
  s.edm.t = {edm_origin.x(), edm_origin.y(), 0.0};
  for (int z = 0; z < dh.NumZooms(); ++z) {
    const Rigid3 ref_from_cam = RefFromCam(dh, z, phi, theta);
    s.cams[z].flange_from_cam = PoseBlock::FromRigid(ref_from_flange_s.Inverse() * ref_from_cam);
  }
  return s;
}

void EnableEffects(const EffectSet& effects, InstrumentModel* model) {
  for (Effect e : effects.List()) {
    if (model->kinematics == Kinematics::kDh && Info(e).redundant_in_dh) continue;
    model->effects.Add(e);
  }
}

}  // namespace rtscalib

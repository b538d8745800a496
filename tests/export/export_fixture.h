// Random, non-trivial instrument models for the export tests: every pose
// block turned and shifted, DH links off their snapped values, the given
// effects at a few tens of arcseconds (or ppm, mm), every distortion
// coefficient of two zoom levels set.
#pragma once

#include <random>
#include <vector>

#include "libcalib/model/instrument.h"

namespace rtscalib {

inline Rigid3 RandomPose(std::mt19937& rng, double max_angle, double max_shift) {
  std::uniform_real_distribution<double> a(-max_angle, max_angle), t(-max_shift, max_shift);
  return {RotationFromEuler<double>(Eigen::Vector3d(a(rng), a(rng), a(rng))),
          Eigen::Vector3d(t(rng), t(rng), t(rng))};
}

inline InstrumentModel RandomModel(Kinematics k, std::mt19937& rng,
                                   const std::vector<Effect>& effects) {
  CameraTool cam;
  cam.intrinsics = {1500, 1490, 640.5, 479.5};
  cam.width = 1280;
  cam.height = 960;
  InstrumentModel m = IdealModel(k, 2, cam);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  // The base: any orientation, anywhere near the origin.
  m.base = PoseBlock::FromRigid(RandomPose(rng, M_PI, 0.5) * m.base.ToRigid());
  if (k == Kinematics::kDh) {
    for (auto& link : m.links) {
      for (int j : {kDhD, kDhA}) link.p[j] += 0.01 * u(rng);
      for (int j : {kDhGamma, kDhAlpha}) link.p[j] += 0.05 * u(rng);
    }
  }
  m.edm = PoseBlock::FromRigid(m.edm.ToRigid() * RandomPose(rng, 0.01, 0.02));
  // Zoom 0 keeps the ideal tool rotation (exactly at pitch pi/2 in dh, where
  // rpy is degenerate); zoom 1 is turned far from it.
  m.cams[0].flange_from_cam =
      PoseBlock::FromRigid(m.cams[0].flange_from_cam.ToRigid() * RandomPose(rng, 0.0, 0.05));
  m.cams[1].flange_from_cam =
      PoseBlock::FromRigid(m.cams[1].flange_from_cam.ToRigid() * RandomPose(rng, 1.0, 0.05));
  const double dist_scale[kNumDistortion] = {0.1,   0.05, 1e-3, 1e-3, 0.01, 0.01, 0.005,
                                             0.001, 1e-3, 1e-4, 1e-3, 1e-4, 0.01, 0.01};
  for (CameraTool& c : m.cams) {
    for (int i = 0; i < kNumDistortion; ++i) c.distortion[i] = dist_scale[i] * u(rng);
  }
  constexpr double kArcsec = M_PI / 180.0 / 3600.0;
  for (Effect e : effects) {
    m.effects.Add(e);
    if (!IsKinematic(e)) continue;
    double scale = 30 * kArcsec;
    if (e == Effect::kHzScale || e == Effect::kVScale || e == Effect::kEdmScale) scale = 50e-6;
    if (e == Effect::kEdmOffset || e == Effect::kEdmCyclic) scale = 2e-3;
    m.EffectValue(e) = {scale * u(rng), scale * u(rng)};
    if (Info(e).num_params == 1) m.EffectValue(e)[1] = 0.0;
  }
  return m;
}

}  // namespace rtscalib

#include "libcalib/model/instrument.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "libcalib/model/kinematics.h"

namespace rtscalib {
namespace {

// Products of a few unit-magnitude rotation entries and metre-scale
// translations: double round-off (~1e-16 per operation); 1e-12 is generous.
constexpr double kRoundOff = 1e-12;

Eigen::Vector3d IdealEdmPoint(double phi, double theta, double d) {
  // SPEC 1: the ideal EDM point d [sin(phi) sin(theta), cos(phi) sin(theta), cos(theta)].
  return d * Eigen::Vector3d(std::sin(phi) * std::sin(theta), std::cos(phi) * std::sin(theta),
                             std::cos(theta));
}

TEST(Instrument, KinematicsNames) {
  // The config and report names of SPEC 5 (`model.kinematics: dh | spherical`).
  EXPECT_STREQ(KinematicsName(Kinematics::kDh), "dh");
  EXPECT_STREQ(KinematicsName(Kinematics::kSpherical), "spherical");
}

TEST(Instrument, PoseBlockStoresQuaternionXYZW) {
  // A 90 degree turn about z: Eigen quaternion (x, y, z, w) = (0, 0, s, s), s = sqrt(1/2).
  const Rigid3 r{Rz(M_PI / 2), Eigen::Vector3d(1, 2, 3)};
  const PoseBlock p = PoseBlock::FromRigid(r);
  const double s = std::sqrt(0.5);
  EXPECT_NEAR(p.q[0], 0.0, kRoundOff);
  EXPECT_NEAR(p.q[1], 0.0, kRoundOff);
  EXPECT_NEAR(p.q[2], s, kRoundOff);
  EXPECT_NEAR(p.q[3], s, kRoundOff);
  EXPECT_EQ(p.t[0], 1.0);
  EXPECT_EQ(p.t[1], 2.0);
  EXPECT_EQ(p.t[2], 3.0);
  // Default: identity.
  const PoseBlock id;
  EXPECT_LT((id.ToRigid().rotation - Eigen::Matrix3d::Identity()).norm(), kRoundOff);
  EXPECT_EQ(id.ToRigid().translation, Eigen::Vector3d::Zero());
}

TEST(Instrument, PoseBlockRoundTripsAndPicksNonNegativeW) {
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Quaterniond q = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized();
    const Rigid3 r{q.toRotationMatrix(), Eigen::Vector3d(n(rng), n(rng), n(rng))};
    const PoseBlock p = PoseBlock::FromRigid(r);
    // q and -q are the same rotation; the block keeps the w >= 0 one.
    EXPECT_GE(p.q[3], 0.0);
    EXPECT_NEAR(std::sqrt(p.q[0] * p.q[0] + p.q[1] * p.q[1] + p.q[2] * p.q[2] + p.q[3] * p.q[3]),
                1.0, kRoundOff);
    const Rigid3 back = p.ToRigid();
    EXPECT_LT((back.rotation - r.rotation).cwiseAbs().maxCoeff(), kRoundOff);
    EXPECT_LT((back.translation - r.translation).norm(), kRoundOff);
  }
}

TEST(Instrument, PoseBlockToRigidNormalisesTheQuaternion) {
  // Ceres keeps the block on the unit sphere, but a hand-edited model file
  // may not: the rotation must still be orthonormal.
  PoseBlock p;
  p.q = {0.0, 0.0, 2.0, 2.0};  // |q| = 2 sqrt(2): Rz(pi/2) once normalised
  const Eigen::Matrix3d r = p.ToRigid().rotation;
  EXPECT_LT((r - Rz(M_PI / 2)).cwiseAbs().maxCoeff(), kRoundOff);
}

TEST(Instrument, PoseBlockEulerFollowsEq83) {
  const Eigen::Vector3d e(0.2, -0.4, 1.3);
  const PoseBlock p = PoseBlock::FromRigid(Rigid3::FromEuler(e, Eigen::Vector3d::Zero()));
  // Quaternion round trip then atan2: round-off only, b far from +-pi/2.
  EXPECT_LT((p.Euler() - e).cwiseAbs().maxCoeff(), kRoundOff);
  EXPECT_LT((p.ToRigid().rotation - Rz(1.3) * Ry(-0.4) * Rx(0.2)).cwiseAbs().maxCoeff(), kRoundOff);
}

TEST(Instrument, FaceOfAndZenithOf) {
  // SPEC 1: face 1 for theta in [0, pi], face 2 for theta in (pi, 2 pi).
  EXPECT_EQ(FaceOf(0.0), 1);
  EXPECT_EQ(FaceOf(M_PI / 2), 1);
  EXPECT_EQ(FaceOf(M_PI), 1);
  EXPECT_EQ(FaceOf(M_PI + 1e-9), 2);
  EXPECT_EQ(FaceOf(3 * M_PI / 2), 2);
  EXPECT_EQ(FaceOf(2 * M_PI - 1e-9), 2);
  // Readings outside [0, 2 pi) are taken modulo 2 pi.
  EXPECT_EQ(FaceOf(-M_PI / 2), 2);
  EXPECT_EQ(FaceOf(2 * M_PI + 0.5), 1);
  EXPECT_DOUBLE_EQ(ZenithOf(1.0), 1.0);
  EXPECT_DOUBLE_EQ(ZenithOf(M_PI), M_PI);
  EXPECT_NEAR(ZenithOf(2 * M_PI - 1.0), 1.0, kRoundOff);
}

TEST(Instrument, OtherFaceFollowsSpec1) {
  // SPEC 1: face 2 of (phi, theta) is (phi - pi mod 2 pi, 2 pi - theta).
  struct Case {
    double phi, theta, phi2, theta2;
  };
  for (const Case& c :
       {Case{0.0, M_PI / 2, M_PI, 3 * M_PI / 2}, Case{0.5, 1.0, 0.5 + M_PI, 2 * M_PI - 1.0},
        Case{4.0, 0.3, 4.0 - M_PI, 2 * M_PI - 0.3}, Case{M_PI, 2.0, 0.0, 2 * M_PI - 2.0}}) {
    double p2, t2;
    OtherFace(c.phi, c.theta, &p2, &t2);
    EXPECT_NEAR(p2, c.phi2, kRoundOff) << c.phi;
    EXPECT_NEAR(t2, c.theta2, kRoundOff) << c.theta;
    EXPECT_GE(p2, 0.0);
    EXPECT_LT(p2, 2 * M_PI);
    EXPECT_EQ(FaceOf(t2), c.theta > 0 && c.theta < M_PI ? 2 : 1);
    EXPECT_NEAR(ZenithOf(t2), c.theta, kRoundOff);
  }
}

TEST(Instrument, IdealModelsFollowSpec1InBothFaces) {
  // SPEC 1 / Klug Eq. 90/91: the line-of-sight frame is Rz(-phi) Rx(-theta)
  // and an EDM point is d [sin phi sin theta, cos phi sin theta, cos theta];
  // face 2 sees the same direction with the image turned by 180 degrees.
  CameraTool cam;
  cam.intrinsics = {1200, 1190, 630, 470};
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> phi_dist(0, 2 * M_PI), theta_dist(0.05, M_PI - 0.05);
  for (Kinematics k : {Kinematics::kDh, Kinematics::kSpherical}) {
    const InstrumentModel m = IdealModel(k, 3, cam);
    EXPECT_EQ(m.kinematics, k);
    ASSERT_EQ(m.NumZooms(), 3);
    EXPECT_TRUE(m.effects.Empty());
    for (int z = 0; z < 3; ++z) {
      EXPECT_EQ(m.cams[z].intrinsics, cam.intrinsics) << "intrinsics are copied per zoom";
      EXPECT_EQ(m.cams[z].width, cam.width);
    }
    for (int i = 0; i < 30; ++i) {
      const double phi = phi_dist(rng), theta = theta_dist(rng), d = 0.5 + 10.0 * i / 29;
      const Rigid3 edm1 = RefFromEdm(m, phi, theta);
      EXPECT_LT((edm1.rotation - Rz(-phi) * Rx(-theta)).cwiseAbs().maxCoeff(), kRoundOff);
      EXPECT_LT(edm1.translation.norm(), kRoundOff);
      EXPECT_LT((PredictEdm(m, phi, theta, d) - IdealEdmPoint(phi, theta, d)).norm(),
                kRoundOff * d);
      // Every zoom's camera frame is the line-of-sight frame (coaxial ideal camera).
      for (int z = 0; z < 3; ++z) {
        EXPECT_LT((RefFromCam(m, z, phi, theta).rotation - edm1.rotation).cwiseAbs().maxCoeff(),
                  kRoundOff);
      }
      double phi2, theta2;
      OtherFace(phi, theta, &phi2, &theta2);
      const Rigid3 edm2 = RefFromEdm(m, phi2, theta2);
      EXPECT_LT((edm2.rotation.col(2) - edm1.rotation.col(2)).norm(), kRoundOff);
      EXPECT_LT((edm2.rotation.col(0) + edm1.rotation.col(0)).norm(), kRoundOff);
      EXPECT_LT((edm2.rotation.col(1) + edm1.rotation.col(1)).norm(), kRoundOff);
      EXPECT_LT((PredictEdm(m, phi2, theta2, d) - IdealEdmPoint(phi, theta, d)).norm(),
                kRoundOff * d);
    }
  }
}

TEST(Instrument, IdealModelDirectionsOfSpec1) {
  // phi = 0 looks north (+y), phi = pi/2 east (+x, clockwise from above),
  // theta = 0 straight up.
  const InstrumentModel m = IdealModel(Kinematics::kDh, 1, CameraTool{});
  EXPECT_LT((PredictEdm(m, 0.0, M_PI / 2, 1.0) - Eigen::Vector3d(0, 1, 0)).norm(), kRoundOff);
  EXPECT_LT((PredictEdm(m, M_PI / 2, M_PI / 2, 1.0) - Eigen::Vector3d(1, 0, 0)).norm(), kRoundOff);
  EXPECT_LT((PredictEdm(m, 1.0, 0.0, 1.0) - Eigen::Vector3d(0, 0, 1)).norm(), kRoundOff);
}

TEST(Instrument, EffectValueAccessorsShareStorage) {
  InstrumentModel m = IdealModel(Kinematics::kSpherical, 1, CameraTool{});
  m.EffectValue(Effect::kHzEccentricity) = {1e-5, -2e-5};
  EXPECT_EQ(m.effect_values[static_cast<int>(Effect::kHzEccentricity)][0], 1e-5);
  EXPECT_EQ(m.effect_values[static_cast<int>(Effect::kHzEccentricity)][1], -2e-5);
  const InstrumentModel& cm = m;
  EXPECT_EQ(cm.EffectValue(Effect::kHzEccentricity)[1], -2e-5);
  EXPECT_EQ(cm.EffectValue(Effect::kCollimation)[0], 0.0);
}

TEST(Instrument, UnknownZoomLevelThrows) {
  const InstrumentModel m = IdealModel(Kinematics::kDh, 2, CameraTool{});
  EXPECT_NO_THROW(RefFromCam(m, 1, 0.0, 1.0));
  EXPECT_THROW(RefFromCam(m, 2, 0.0, 1.0), std::out_of_range);
  EXPECT_THROW(RefFromCam(m, -1, 0.0, 1.0), std::out_of_range);
}

}  // namespace
}  // namespace rtscalib

#include "libcalib/fit/two_face.h"

#include <gtest/gtest.h>

#include <cmath>

#include "libcalib/model/kinematics.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib {
namespace {

constexpr double kArcsec = M_PI / (180.0 * 3600.0);
// two_face.h: first order in c, i, v0; the neglected terms are products of
// two of them. The values below are <= 30" = 1.5e-4 rad, so the products are
// <= 2.1e-8 rad; 0.01" = 4.8e-8 rad bounds them with a factor 2 to spare.
constexpr double kFirstOrder = 0.01 * kArcsec;

// A simulated spherical truth like the diagnosis fixtures' (tests/diagnose):
// a station away from the origin and turned about the vertical, a camera
// slightly off the EDM, and the given classical axis errors (SI, SPEC 4).
InstrumentModel SphericalTruth(double c, double i, double v0) {
  InstrumentModel m = IdealModel(Kinematics::kSpherical, 1, PaperTruth(1).cams[0]);
  m.base = PoseBlock::FromRigid(Rigid3::FromEuler({0.0, 0.0, 0.3}, {1.0, 2.0, 0.5}));
  m.edm.t = {2e-4, -1e-4, 0.0};
  m.cams[0].flange_from_cam = PoseBlock::FromRigid(Rigid3::FromEuler({0, 0, 0}, {1e-4, -2e-4, 0}));
  m.effects.Add(Effect::kCollimation);
  m.effects.Add(Effect::kTiltingAxis);
  m.effects.Add(Effect::kVerticalIndex);
  m.EffectValue(Effect::kCollimation)[0] = c;
  m.EffectValue(Effect::kTiltingAxis)[0] = i;
  m.EffectValue(Effect::kVerticalIndex)[0] = v0;
  return m;
}

TEST(TwoFaceCheck, IdealInstrumentHasNoDifferences) {
  const InstrumentModel m = IdealModel(Kinematics::kSpherical, 1, CameraTool{});
  const TwoFaceDifferences d = TwoFaceCheck(m, m);
  // Exactly the same ray in both faces: round-off of atan2/acos, ~1e-15 rad.
  EXPECT_NEAR(d.collimation, 0.0, 1e-12);
  EXPECT_NEAR(d.tilting_axis, 0.0, 1e-12);
  EXPECT_NEAR(d.vertical_index, 0.0, 1e-12);
  EXPECT_LT(d.rms_hz, 1e-12);
  EXPECT_LT(d.rms_z, 1e-12);
  // The header's grid: phi every 30 degrees (12 values) times some zenith rows.
  EXPECT_GE(d.num_pointings, 24);
  EXPECT_EQ(d.num_pointings % 12, 0);
}

TEST(TwoFaceCheck, EachClassicalErrorAloneIsRecoveredWithItsSpecSign) {
  // SPEC 4 signatures: collimation dHz = +c / sin z in face 1, -c / sin z in
  // face 2; tilting axis +i cot z, opposite in face 2; vertical index
  // theta* = theta + v0, flipping with the face.
  struct Case {
    double c, i, v0;
  };
  for (const Case& k :
       {Case{25 * kArcsec, 0, 0}, Case{-25 * kArcsec, 0, 0}, Case{0, 18 * kArcsec, 0},
        Case{0, -18 * kArcsec, 0}, Case{0, 0, 12 * kArcsec}, Case{0, 0, -12 * kArcsec}}) {
    const InstrumentModel m = SphericalTruth(k.c, k.i, k.v0);
    const TwoFaceDifferences d = TwoFaceCheck(m, m);
    EXPECT_NEAR(d.collimation, k.c, kFirstOrder) << k.c / kArcsec << "\"";
    EXPECT_NEAR(d.tilting_axis, k.i, kFirstOrder) << k.i / kArcsec << "\"";
    EXPECT_NEAR(d.vertical_index, k.v0, kFirstOrder) << k.v0 / kArcsec << "\"";
    EXPECT_LT(d.rms_hz, kFirstOrder);
    EXPECT_LT(d.rms_z, kFirstOrder);
  }
}

TEST(TwoFaceCheck, AllThreeTogetherAndFromTheSimulatedData) {
  // c, i, v0 at once; and the face-1 / face-2 EDM records the simulator makes
  // from this truth really differ by the SPEC 1 two-face signature: a point
  // measured in face 2 at the face-2 reading of a face-1 pointing lies
  // d * 2 c / sin z off horizontally at z = 90 deg.
  const double c = 30 * kArcsec, i = -20 * kArcsec, v0 = 10 * kArcsec;
  const InstrumentModel truth = SphericalTruth(c, i, v0);
  const TwoFaceDifferences d = TwoFaceCheck(truth, truth);
  EXPECT_NEAR(d.collimation, c, kFirstOrder);
  EXPECT_NEAR(d.tilting_axis, i, kFirstOrder);
  EXPECT_NEAR(d.vertical_index, v0, kFirstOrder);

  SimulationOptions o;
  o.truth = truth;
  o.plan.faces = {1, 2};
  const SimulatedData data = Simulate(o);
  const size_t half = data.obs.records.size() / 2;
  // First sweep1 pose (phi 0, theta pi/2), EDM at 1 m: face 1 row 0, face 2 row `half`.
  const Record& f1 = data.obs.records[0];
  const Record& f2 = data.obs.records[half];
  ASSERT_EQ(f1.tool, Tool::kEdm);
  ASSERT_EQ(f2.tool, Tool::kEdm);
  ASSERT_EQ(f2.face, 2);
  ASSERT_EQ(f1.d, f2.d);
  const Eigen::Vector3d origin = RefFromEdm(truth, 0.0, M_PI / 2).translation;
  const Eigen::Vector3d r1 = f1.x - origin,
                        r2 = f2.x - RefFromEdm(truth, f2.phi, f2.theta).translation;
  const double hz1 = std::atan2(r1.x(), r1.y()), hz2 = std::atan2(r2.x(), r2.y());
  // At z = 90 deg: hz1 - hz2 = 2 c (cot z = 0), to first order (c^2 ~ 2e-8).
  EXPECT_NEAR(WrapAngle(hz1 - hz2), 2 * c, 2 * kFirstOrder);
}

TEST(TwoFaceCheck, ReadsTheCameraAxisWhenAskedForAZoom) {
  // A camera tool turned about the telescope's y axis by delta adds to the
  // collimation of the camera's line of sight (SPEC 4 chain: ... Ry(c) * tool),
  // not to the EDM's; turned about x by eps it acts as a vertical index of
  // -eps (Rx(-theta) Rx(eps) = Rx(-(theta - eps))).
  const double c = 15 * kArcsec, delta = 8 * kArcsec, eps = 5 * kArcsec;
  InstrumentModel m = SphericalTruth(c, 0, 0);
  m.cams[0].flange_from_cam =
      PoseBlock::FromRigid(Rigid3{Ry(delta) * Rx(eps), Eigen::Vector3d(1e-4, -2e-4, 0)});
  const TwoFaceDifferences edm = TwoFaceCheck(m, m, -1);
  EXPECT_NEAR(edm.collimation, c, kFirstOrder);
  EXPECT_NEAR(edm.vertical_index, 0.0, kFirstOrder);
  const TwoFaceDifferences cam = TwoFaceCheck(m, m, 0);
  EXPECT_NEAR(cam.collimation, c + delta, kFirstOrder);
  EXPECT_NEAR(cam.tilting_axis, 0.0, kFirstOrder);
  EXPECT_NEAR(cam.vertical_index, -eps, kFirstOrder);
}

TEST(TwoFaceCheck, SeparateFaceModelsAndUnexplainedStructure) {
  // Face models that differ only in their vertical index by 2 v: the check
  // reads the mean (v1 + v2) / 2 of face 1's v1 and face 2's v2, because
  // z1 - z2 = v1 + v2 (face 2 zenith = 2 pi - theta*).
  const double v1 = 10 * kArcsec, v2 = 4 * kArcsec;
  const TwoFaceDifferences d = TwoFaceCheck(SphericalTruth(0, 0, v1), SphericalTruth(0, 0, v2));
  EXPECT_NEAR(d.vertical_index, (v1 + v2) / 2, kFirstOrder);
  EXPECT_NEAR(d.collimation, 0.0, kFirstOrder);

  // Horizontal-circle eccentricity flips sign between faces (phi differs by
  // pi): hz1 - hz2 = 2 e sin(phi - phi_e), which neither c nor i explains
  // (zero mean over the 12 phi values at every zenith); it stays in rms_hz,
  // whose value over equally spaced phi is sqrt(mean(4 e^2 sin^2)) = sqrt(2) e.
  InstrumentModel ecc = SphericalTruth(0, 0, 0);
  const double e = 20 * kArcsec, phi_e = 0.7;
  ecc.effects.Add(Effect::kHzEccentricity);
  ecc.EffectValue(Effect::kHzEccentricity) = {e * std::cos(phi_e), e * std::sin(phi_e)};
  const TwoFaceDifferences h = TwoFaceCheck(ecc, ecc);
  EXPECT_NEAR(h.collimation, 0.0, kFirstOrder);
  EXPECT_NEAR(h.tilting_axis, 0.0, kFirstOrder);
  EXPECT_NEAR(h.rms_hz, std::sqrt(2.0) * e, 0.01 * e) << "1%: second-order terms are ~e = 1e-4";
  EXPECT_LT(h.rms_z, kFirstOrder);
}

}  // namespace
}  // namespace rtscalib

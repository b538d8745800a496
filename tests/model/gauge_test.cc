#include "libcalib/model/gauge.h"

#include <gtest/gtest.h>

#include <random>

#include "libcalib/model/kinematics.h"

namespace rtscalib {
namespace {

// Tolerances: the re-expressions are exact in exact arithmetic; in double
// precision a few products of unit-size rotations and metre-size
// translations give ~1e-15 relative, so 1e-10 m at 10 m and 1e-7 px at
// f = 3000 px (1e-10 rad) for a point in view. axis_wobble is re-expressed
// to first order (gauge.h): Rx(a) Ry(b) turned by Rz(psi) differs from
// Rx(a') Ry(b') by ~a*b; with w = 5" that is 6e-10 rad, 7e-9 m at 12 m,
// 2e-6 px at 3000 px: those checks use 1e-8 m and 1e-5 px.
constexpr double kExactM = 1e-10, kExactPx = 1e-7, kWobbleM = 1e-8, kWobblePx = 1e-5;

Rigid3 RandomPose(std::mt19937* rng, double angle, double dist) {
  std::uniform_real_distribution<double> a(-angle, angle), t(-dist, dist);
  return Rigid3::FromEuler({a(*rng), a(*rng), a(*rng)}, {t(*rng), t(*rng), t(*rng)});
}

// A dh or spherical instrument far from ideal, with effects, two cameras,
// one estimated board and one estimated point.
InstrumentModel ArbitraryModel(Kinematics k, bool wobble, std::mt19937* rng) {
  CameraTool cam;
  cam.intrinsics = {3000, 3001, 641, 479};
  cam.distortion[kK1] = -0.05;
  InstrumentModel m = IdealModel(k, 2, cam);
  m.base = PoseBlock::FromRigid(RandomPose(rng, 0.3, 5.0) * m.base.ToRigid());
  m.links[0].p = {0.012, -1.52, M_PI / 2 + 2e-4, 3e-4};
  m.links[1].p = {7e-5, -4e-4, 2e-4, -1.1e-4};
  m.edm = PoseBlock::FromRigid(m.edm.ToRigid() * RandomPose(rng, 2e-3, 1e-3));
  for (CameraTool& c : m.cams) {
    c.flange_from_cam = PoseBlock::FromRigid(c.flange_from_cam.ToRigid() * RandomPose(rng, 2e-3, 0.05));
  }
  m.effects.Add(Effect::kHzEccentricity);
  m.EffectValue(Effect::kHzEccentricity) = {8.0 / 206264.8, 0.7};
  if (k == Kinematics::kSpherical) {
    m.effects.Add(Effect::kCollimation);
    m.EffectValue(Effect::kCollimation) = {15.0 / 206264.8, 0};
  }
  if (wobble) {
    m.effects.Add(Effect::kAxisWobble);
    m.EffectValue(Effect::kAxisWobble) = {3.0 / 206264.8, 4.0 / 206264.8};  // w = 5"
  }
  EstimatedBoard b;
  b.board.first_id = 0;
  b.board.rows = 2;
  b.board.cols = 3;
  b.board.pose_known = false;
  b.board.ref_from_board = RandomPose(rng, 3.0, 10.0);
  b.pose = PoseBlock::FromRigid(b.board.ref_from_board);
  m.boards.push_back(b);
  m.points.push_back({"prism", {4.0, -7.0, 1.5}, {}});
  return m;
}

// Every prediction of `b` equals `b_from_a` applied to `a`'s, at random
// readings in both faces: EDM points, camera points, the pixel of a point in
// view (pixels far outside the image are not compared: the distortion
// polynomial blows their rounding up), and the boards' corners and the
// points (positions in the reference frame).
void ExpectSameInstrument(const InstrumentModel& a, const InstrumentModel& b,
                          const Rigid3& b_from_a, double tol_m, double tol_px) {
  for (const Eigen::Vector3d& c : a.boards[0].board.CornersInBoard(4)) {
    EXPECT_LT((b.boards[0].pose.ToRigid() * c - b_from_a * (a.boards[0].pose.ToRigid() * c)).norm(),
              kExactM);
  }
  EXPECT_LT((Eigen::Map<const Eigen::Vector3d>(b.points[0].x.data()) -
             b_from_a * Eigen::Map<const Eigen::Vector3d>(a.points[0].x.data()))
                .norm(),
            kExactM);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> phi(0, 2 * M_PI), theta(0.3, 2.6);
  for (int i = 0; i < 40; ++i) {
    const double p = phi(rng), t = i % 2 ? theta(rng) : 2 * M_PI - theta(rng);
    EXPECT_LT((PredictEdm(b, p, t, 12.0) - b_from_a * PredictEdm(a, p, t, 12.0)).norm(), tol_m);
    for (int z = 0; z < a.NumZooms(); ++z) {
      EXPECT_LT((PredictCam(b, z, p, t, 100, 800, 10.0) -
                 b_from_a * PredictCam(a, z, p, t, 100, 800, 10.0))
                    .norm(),
                tol_m);
      const Eigen::Vector3d x = PredictCam(a, z, p, t, 300, 200, 8.0);
      Eigen::Vector2d ua, ub;
      ASSERT_TRUE(PredictPixel(a, z, p, t, x, &ua));
      ASSERT_TRUE(PredictPixel(b, z, p, t, b_from_a * x, &ub));
      EXPECT_LT((ua - Eigen::Vector2d(300, 200)).norm(), 1e-6);  // the round trip itself
      EXPECT_LT((ua - ub).norm(), tol_px) << "zoom " << z << " phi " << p << " theta " << t;
    }
  }
}

TEST(Gauge, FirstJointOffsetsTradeExactlyWithTheBase) {
  std::mt19937 rng(1);
  const InstrumentModel a = ArbitraryModel(Kinematics::kDh, false, &rng);
  InstrumentModel b = a;
  SetFirstJointOffsets(-0.4, 2.1, &b);
  EXPECT_EQ(b.links[0].p[kDhD], -0.4);
  EXPECT_EQ(b.links[0].p[kDhGamma], 2.1);
  EXPECT_EQ(b.links[0].p[kDhAlpha], a.links[0].p[kDhAlpha]);
  ExpectSameInstrument(a, b, Rigid3{}, kExactM, kExactPx);
}

TEST(Gauge, SecondLinkTradesExactlyWithTheTools) {
  std::mt19937 rng(2);
  const InstrumentModel a = ArbitraryModel(Kinematics::kDh, false, &rng);
  InstrumentModel b = a;
  SetSecondLink(DhLink{{0.03, 0.2, -0.1, 0.02}}, &b);
  EXPECT_EQ(b.links[1].p[kDhA], 0.02);
  EXPECT_GT((b.cams[0].flange_from_cam.ToRigid().translation -
             a.cams[0].flange_from_cam.ToRigid().translation)
                .norm(),
            0.01);
  ExpectSameInstrument(a, b, Rigid3{}, kExactM, kExactPx);
}

TEST(Gauge, ReferenceFrameChangeMovesBaseBoardsAndPoints) {
  std::mt19937 rng(3);
  for (Kinematics k : {Kinematics::kDh, Kinematics::kSpherical}) {
    const InstrumentModel a = ArbitraryModel(k, false, &rng);
    InstrumentModel b = a;
    const Rigid3 new_from_old = RandomPose(&rng, 1.0, 20.0);
    ChangeReferenceFrame(new_from_old, &b);
    ExpectSameInstrument(a, b, new_from_old, kExactM, kExactPx);
    // The board's geometry follows its pose block.
    EXPECT_LT((b.boards[0].board.ref_from_board.Matrix() - b.boards[0].pose.ToRigid().Matrix())
                  .norm(),
              1e-14);
  }
}

TEST(Gauge, AxisWobblePhaseFollowsATurnAboutZ) {
  std::mt19937 rng(4);
  const InstrumentModel a = ArbitraryModel(Kinematics::kDh, true, &rng);
  InstrumentModel b = a;
  const Rigid3 new_from_old{Rz(0.8), Eigen::Vector3d(1, 2, 3)};
  ChangeReferenceFrame(new_from_old, &b);
  // phi_w' = phi_w - 0.8 (gauge.h), w unchanged.
  const auto& wa = a.EffectValue(Effect::kAxisWobble);
  const auto& wb = b.EffectValue(Effect::kAxisWobble);
  EXPECT_NEAR(std::hypot(wb[0], wb[1]), std::hypot(wa[0], wa[1]), 1e-18);
  EXPECT_NEAR(WrapAngle(std::atan2(wb[1], wb[0]) - std::atan2(wa[1], wa[0])), -0.8, 1e-9);
  ExpectSameInstrument(a, b, new_from_old, kWobbleM, kWobblePx);

  // A frame tilted by 2 mrad as well: the tilt's part of the wobble is left
  // out (gauge.h), an error of w * tilt = 2.4e-5 * 2e-3 = 5e-8 rad: 6e-7 m
  // at 12 m, 1.5e-4 px at 3000 px; bounds twice that.
  InstrumentModel c = a;
  const Rigid3 tilted{Rz(0.8) * Rx(2e-3), Eigen::Vector3d(1, 2, 3)};
  ChangeReferenceFrame(tilted, &c);
  ExpectSameInstrument(a, c, tilted, 1.2e-6, 3e-4);

  // A frame upside down would reverse the wobble's sense: refused.
  InstrumentModel d = a;
  EXPECT_THROW(ChangeReferenceFrame(Rigid3{Rx(M_PI), Eigen::Vector3d::Zero()}, &d),
               std::invalid_argument);
}

// SPEC 7: the ideal base frame has its origin on the vertical axis, z along
// it (up), phi = 0 towards +y. An ideal instrument in any frame becomes
// Eq. 90 exactly; a real one keeps its predictions.
TEST(Gauge, IdealBaseFrameIsTheInstrumentsOwn) {
  std::mt19937 rng(5);
  for (Kinematics k : {Kinematics::kDh, Kinematics::kSpherical}) {
    InstrumentModel ideal = IdealModel(k, 1, CameraTool{});
    ideal.base = PoseBlock::FromRigid(RandomPose(&rng, 0.5, 3.0) * ideal.base.ToRigid());
    ToIdealBaseFrame(&ideal);
    for (double phi : {0.0, 0.4, 2.5}) {
      for (double theta : {0.7, 1.6}) {
        const Rigid3 r = RefFromEdm(ideal, phi, theta);
        EXPECT_LT((r.rotation - Rz(-phi) * Rx(-theta)).norm(), 1e-12);
        EXPECT_LT(r.translation.norm(), 1e-12);
      }
    }

    const InstrumentModel a = ArbitraryModel(k, false, &rng);
    InstrumentModel b = a;
    const Rigid3 new_from_old = ToIdealBaseFrame(&b);
    const InstrumentModel reference = IdealModel(k, 0, CameraTool{});
    EXPECT_EQ(b.base.q, reference.base.q);
    EXPECT_EQ(b.base.t, reference.base.t);
    if (k == Kinematics::kDh) {
      EXPECT_EQ(b.links[0].p[kDhD], reference.links[0].p[kDhD]);
      EXPECT_EQ(b.links[0].p[kDhGamma], reference.links[0].p[kDhGamma]);
    }
    ExpectSameInstrument(a, b, new_from_old, kExactM, kExactPx);
    // Turning phi alone turns the flange about the z axis through the origin.
    const Rigid3 turn = RefFromFlange(b, 1.1, 1.4) * RefFromFlange(b, 0.2, 1.4).Inverse();
    const Eigen::AngleAxisd aa(turn.rotation);
    EXPECT_NEAR(std::abs(aa.axis().z()), 1.0, 1e-12);
    EXPECT_LT(turn.translation.norm(), 1e-12);
  }
}

}  // namespace
}  // namespace rtscalib

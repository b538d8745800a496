#include "libcalib/geometry/rotation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace rtscalib {
namespace {

// Rotations of unit vectors and products of a few 3x3 matrices built from
// sin/cos of O(1) angles: round-off only, a few ulps per product
// (~1e-16 each); 1e-13 leaves room for the longest chain below.
constexpr double kRoundOff = 1e-13;

Eigen::Matrix3d AxisAngle(double angle, const Eigen::Vector3d& axis) {
  return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

// Largest absolute entry difference.
double MaxDiff(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return (a - b).cwiseAbs().maxCoeff();
}

TEST(Rotation, ElementaryRotationsMatchTheHeaderMatrices) {
  // Klug Eq. 6, 89, 7 written out entry by entry for one angle.
  const double t = 0.37, c = std::cos(t), s = std::sin(t);
  Eigen::Matrix3d rx, ry, rz;
  rx << 1, 0, 0, 0, c, -s, 0, s, c;
  ry << c, 0, s, 0, 1, 0, -s, 0, c;
  rz << c, -s, 0, s, c, 0, 0, 0, 1;
  EXPECT_LT(MaxDiff(Rx(t), rx), kRoundOff);
  EXPECT_LT(MaxDiff(Ry(t), ry), kRoundOff);
  EXPECT_LT(MaxDiff(Rz(t), rz), kRoundOff);
}

TEST(Rotation, ElementaryRotationsAreRightHanded) {
  // Right-handed positive rotations by 90 degrees (SPEC 1: right-handed frame):
  // Rx: y -> z, Ry: z -> x, Rz: x -> y.
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY(),
                        z = Eigen::Vector3d::UnitZ();
  EXPECT_LT((Rx(M_PI / 2) * y - z).norm(), kRoundOff);
  EXPECT_LT((Ry(M_PI / 2) * z - x).norm(), kRoundOff);
  EXPECT_LT((Rz(M_PI / 2) * x - y).norm(), kRoundOff);
  // And they agree with Eigen's angle-axis for any angle.
  for (double a : {-2.9, -0.4, 0.0, 1e-7, 1.2, 3.1}) {
    EXPECT_LT(MaxDiff(Rx(a), AxisAngle(a, x)), kRoundOff) << a;
    EXPECT_LT(MaxDiff(Ry(a), AxisAngle(a, y)), kRoundOff) << a;
    EXPECT_LT(MaxDiff(Rz(a), AxisAngle(a, z)), kRoundOff) << a;
  }
}

TEST(Rotation, EulerIsRzRyRxStoredAsABG) {
  // SPEC 1 / Klug Eq. 83: R = Rz(g) Ry(b) Rx(a), stored as [a, b, g]. Built
  // here from Eigen's angle-axis so that the order is checked independently.
  const double a = 0.3, b = -0.7, g = 2.1;
  const Eigen::Matrix3d expected = AxisAngle(g, Eigen::Vector3d::UnitZ()) *
                                   AxisAngle(b, Eigen::Vector3d::UnitY()) *
                                   AxisAngle(a, Eigen::Vector3d::UnitX());
  EXPECT_LT(MaxDiff(RotationFromEuler<double>(Eigen::Vector3d(a, b, g)), expected), kRoundOff);
  // A different order (Rx Ry Rz) gives a different matrix for these angles,
  // so the check above can tell the orders apart.
  const Eigen::Matrix3d other = Rx(a) * Ry(b) * Rz(g);
  EXPECT_GT(MaxDiff(other, expected), 0.1);
}

TEST(Rotation, RotationFromEulerIsTemplated) {
  // The same formula in long double agrees with double to double round-off.
  const Eigen::Matrix<long double, 3, 1> e(0.3L, -0.7L, 2.1L);
  const Mat3<long double> rl = RotationFromEuler<long double>(e);
  const Eigen::Matrix3d rd = RotationFromEuler<double>(Eigen::Vector3d(0.3, -0.7, 2.1));
  EXPECT_LT(MaxDiff(rl.cast<double>(), rd), kRoundOff);
}

TEST(Rotation, EulerRoundTripAwayFromGimbalLock) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> ang(-M_PI + 1e-3, M_PI - 1e-3);
  std::uniform_real_distribution<double> beta(-M_PI / 2 + 0.01, M_PI / 2 - 0.01);
  for (int i = 0; i < 500; ++i) {
    const Eigen::Vector3d e(ang(rng), beta(rng), ang(rng));
    const Eigen::Vector3d back = EulerFromRotation(RotationFromEuler<double>(e));
    // |cos b| >= sin(0.01): atan2 of entries with round-off 1e-16 recovers
    // each angle to ~1e-16 / 1e-2; 1e-12 is generous.
    EXPECT_LT((back - e).cwiseAbs().maxCoeff(), 1e-12) << e.transpose();
  }
}

TEST(Rotation, EulerFromRotationRangeOfB) {
  // b is returned in [-pi/2, pi/2]: an input with |b| > pi/2 comes back as
  // the equivalent triple (a + pi, pi - b, g + pi), same matrix.
  const Eigen::Vector3d e(0.2, 2.0, -0.5);
  const Eigen::Matrix3d r = RotationFromEuler<double>(e);
  const Eigen::Vector3d back = EulerFromRotation(r);
  EXPECT_LE(std::abs(back[1]), M_PI / 2);
  EXPECT_NEAR(back[1], M_PI - 2.0, kRoundOff);
  EXPECT_NEAR(WrapAngle(back[0] - (0.2 + M_PI)), 0.0, kRoundOff);
  EXPECT_NEAR(WrapAngle(back[2] - (-0.5 + M_PI)), 0.0, kRoundOff);
  EXPECT_LT(MaxDiff(RotationFromEuler<double>(back), r), kRoundOff);
}

TEST(Rotation, EulerRoundTripNearAndAtGimbalLock) {
  // Near |b| = pi/2 only g - a (b = +pi/2) or g + a (b = -pi/2) is
  // determined; the matrix must survive the round trip anyway, and exactly at
  // the lock a is 0 and g carries the whole rotation (header contract).
  for (double sign : {1.0, -1.0}) {
    for (double off : {1e-3, 1e-6, 1e-9, 1e-13, 0.0}) {
      const Eigen::Vector3d e(0.4, sign * (M_PI / 2 - off), -1.1);
      const Eigen::Matrix3d r = RotationFromEuler<double>(e);
      const Eigen::Vector3d back = EulerFromRotation(r);
      // Matrix entries are exact to round-off whatever branch is taken.
      EXPECT_LT(MaxDiff(RotationFromEuler<double>(back), r), 1e-12)
          << "sign " << sign << " off " << off;
      EXPECT_LE(std::abs(back[1]), M_PI / 2);
      // The combination that is determined: g - sign * a.
      EXPECT_NEAR(WrapAngle((back[2] - sign * back[0]) - (e[2] - sign * e[0])), 0.0, 1e-9)
          << "sign " << sign << " off " << off;
    }
  }
  // Exactly at the lock (the matrix built by hand, cos b = 0 exactly).
  const double a = 0.4, g = -1.1;
  Eigen::Matrix3d ry;
  ry << 0, 0, 1, 0, 1, 0, -1, 0, 0;  // Ry(pi/2) without cos(pi/2) round-off
  const Eigen::Matrix3d r = Rz(g) * ry * Rx(a);
  const Eigen::Vector3d back = EulerFromRotation(r);
  EXPECT_EQ(back[0], 0.0);
  EXPECT_NEAR(back[1], M_PI / 2, kRoundOff);
  EXPECT_NEAR(WrapAngle(back[2] - (g - a)), 0.0, kRoundOff);
  EXPECT_LT(MaxDiff(RotationFromEuler<double>(back), r), kRoundOff);
}

TEST(Rotation, WrapAngleRangeIsMinusPiExclusiveToPiInclusive) {
  EXPECT_NEAR(WrapAngle(0.0), 0.0, kRoundOff);
  EXPECT_NEAR(WrapAngle(0.5), 0.5, kRoundOff);
  EXPECT_NEAR(WrapAngle(-0.5), -0.5, kRoundOff);
  EXPECT_NEAR(WrapAngle(2 * M_PI + 0.5), 0.5, kRoundOff);
  EXPECT_NEAR(WrapAngle(-2 * M_PI - 0.5), -0.5, kRoundOff);
  EXPECT_NEAR(WrapAngle(7 * M_PI / 2), -M_PI / 2, 1e-12);
  // pi is in the range and -pi maps to +pi (the half-open interval).
  EXPECT_NEAR(WrapAngle(M_PI), M_PI, kRoundOff);
  EXPECT_NEAR(WrapAngle(-M_PI), M_PI, kRoundOff);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  for (int i = 0; i < 1000; ++i) {
    const double a = u(rng), w = WrapAngle(a);
    EXPECT_GT(w, -M_PI);
    EXPECT_LE(w, M_PI);
    // Same direction: differs by a multiple of 2 pi (|a| <= 50, so the
    // multiple is recovered with round-off ~1e-14).
    const double k = (a - w) / (2 * M_PI);
    EXPECT_NEAR(k, std::round(k), 1e-12) << a;
  }
}

TEST(Rotation, Rigid3ActsComposesAndInverts) {
  const Rigid3 a_from_b = Rigid3::FromEuler({0.1, -0.2, 0.3}, {1.0, -2.0, 0.5});
  const Rigid3 b_from_c = Rigid3::FromEuler({-0.4, 0.5, 2.0}, {0.2, 0.3, -0.7});
  const Eigen::Vector3d x_c(0.3, -1.2, 4.0);
  // x_a = R x_b + t.
  const Eigen::Vector3d x_b = b_from_c.rotation * x_c + b_from_c.translation;
  EXPECT_LT((b_from_c * x_c - x_b).norm(), kRoundOff);
  // Composition a_from_c = a_from_b * b_from_c acts as the two in turn.
  const Rigid3 a_from_c = a_from_b * b_from_c;
  EXPECT_LT((a_from_c * x_c - a_from_b * (b_from_c * x_c)).norm(), kRoundOff);
  // Inverse undoes it, both ways.
  EXPECT_LT((a_from_c.Inverse() * (a_from_c * x_c) - x_c).norm(), kRoundOff);
  const Rigid3 id = a_from_b * a_from_b.Inverse();
  EXPECT_LT(MaxDiff(id.rotation, Eigen::Matrix3d::Identity()), kRoundOff);
  EXPECT_LT(id.translation.norm(), kRoundOff);
  // The homogeneous matrix acts the same way.
  const Eigen::Vector4d h = a_from_c.Matrix() * x_c.homogeneous();
  EXPECT_LT((h.head<3>() - a_from_c * x_c).norm(), kRoundOff);
  EXPECT_EQ(h[3], 1.0);
  EXPECT_EQ(a_from_c.Matrix().row(3), Eigen::RowVector4d(0, 0, 0, 1));
  // FromEuler uses the SPEC 1 Euler convention.
  EXPECT_LT(MaxDiff(a_from_b.rotation, Rz(0.3) * Ry(-0.2) * Rx(0.1)), kRoundOff);
  EXPECT_EQ(a_from_b.translation, Eigen::Vector3d(1.0, -2.0, 0.5));
  // Columns are the rotated frame's axes in the outer frame.
  EXPECT_LT((a_from_b.rotation * Eigen::Vector3d::UnitX() - a_from_b.rotation.col(0)).norm(),
            kRoundOff);
}

TEST(Rotation, DefaultRigid3IsIdentity) {
  const Rigid3 id;
  const Eigen::Vector3d x(1.5, -2.5, 3.5);
  EXPECT_EQ(id * x, x);
  EXPECT_EQ(id.Matrix(), Eigen::Matrix4d::Identity());
}

}  // namespace
}  // namespace rtscalib

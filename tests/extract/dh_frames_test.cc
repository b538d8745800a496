#include "libcalib/extract/dh_frames.h"

#include <gtest/gtest.h>

#include <random>

#include "libcalib/model/kinematics.h"

namespace rtscalib {
namespace {

// Exact unit-scale geometry: round-off of a few products and one closest-
// point solve with a c - b^2 = sin^2(alpha) >= 0.25; 1e-12 is generous.
constexpr double kExact = 1e-12;

LinkFrame FrameFrom(const Rigid3& ref_from_frame) {
  LinkFrame f;
  f.o = ref_from_frame.translation;
  f.x = ref_from_frame.rotation.col(0);
  f.y = ref_from_frame.rotation.col(1);
  f.z = ref_from_frame.rotation.col(2);
  return f;
}

Rigid3 RandomPose(std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  return {Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix(),
          Eigen::Vector3d(g(rng), g(rng), g(rng))};
}

Rigid3 Link(const std::array<double, 4>& p, double joint) {
  const RigidT<double> m = DhLinkTransform(p.data(), joint);
  return {m.R, m.t};
}

void ExpectSameFrame(const LinkFrame& a, const LinkFrame& b, double tol) {
  EXPECT_LT((a.o - b.o).norm(), tol);
  EXPECT_LT((a.x - b.x).norm(), tol);
  EXPECT_LT((a.y - b.y).norm(), tol);
  EXPECT_LT((a.z - b.z).norm(), tol);
}

// Frame i+1 = frame i * Tz(d) Rz(gamma) Tx(a) Rx(alpha) (Eq. 8); the axis of
// frame i+1 given by any point on it and any positive multiple of z_{i+1}.
// NextFrame must find frame i+1 and DhParametersBetween the parameters. With
// a > 0 and alpha in (0, pi) Eq. 47's x_{i+1} (from axis i towards axis i+1)
// is the DH x_{i+1}, so the frames agree exactly.
TEST(DhFrames, NextFrameAndEq49InvertEq8) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 100; ++trial) {
    const LinkFrame fi = FrameFrom(RandomPose(rng));
    const std::array<double, 4> p{u(rng) - 0.5, (2 * u(rng) - 1) * M_PI, 0.5 + 2.1 * u(rng),
                                  0.05 + u(rng)};  // {d, gamma, alpha, a}
    const LinkFrame next = FrameFrom(fi.RefFromFrame() * Link(p, 0.0));
    const Line3 axis{next.o + (u(rng) - 0.5) * 4 * next.z, next.z * (0.5 + u(rng))};
    ClosestPoints cp;
    const LinkFrame found = NextFrame(fi, axis, LineTolerances(), &cp);
    EXPECT_EQ(cp.constellation, LineConstellation::kSkewed);
    ExpectSameFrame(found, next, kExact);
    const std::array<double, 4> q = DhParametersBetween(fi, found);
    for (int k = 0; k < 4; ++k) EXPECT_NEAR(q[k], p[k], kExact) << k;
  }
}

// Eq. 49 as printed, a = (o_{i+1} - o_i)^T x_i, is a cos(gamma): right only
// for gamma = 0. The corrected form uses x_{i+1}.
TEST(DhFrames, PrintedEq49AIsOnlyRightForZeroGamma) {
  const LinkFrame fi;
  const std::array<double, 4> p{0.1, 0.7, 1.2, 0.3};
  const LinkFrame next = FrameFrom(fi.RefFromFrame() * Link(p, 0.0));
  EXPECT_NEAR(DhParametersBetween(fi, next)[kDhA], 0.3, kExact);
  EXPECT_NEAR((next.o - fi.o).dot(fi.x), 0.3 * std::cos(0.7), kExact);
}

// Intersecting axes (a = 0): x_{i+1} = z_i x z_{i+1} / |.| (Eq. 47), which is
// the DH x_{i+1} for alpha in (0, pi).
TEST(DhFrames, IntersectingAxes) {
  std::mt19937 rng(2);
  const LinkFrame fi = FrameFrom(RandomPose(rng));
  const std::array<double, 4> p{0.2, -1.1, M_PI / 2, 0.0};
  const LinkFrame next = FrameFrom(fi.RefFromFrame() * Link(p, 0.0));
  ClosestPoints cp;
  const LinkFrame found = NextFrame(fi, Line3{next.o + 0.3 * next.z, 2.0 * next.z}, {}, &cp);
  EXPECT_EQ(cp.constellation, LineConstellation::kIntersecting);
  ExpectSameFrame(found, next, kExact);
  const auto q = DhParametersBetween(fi, found);
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(q[k], p[k], kExact) << k;
}

// Parallel axes: x_{i+1} points from o_i to axis i+1; d = 0, alpha = 0 (or pi
// when antiparallel), a = the distance.
TEST(DhFrames, ParallelAndIdenticalAxes) {
  LinkFrame fi;
  fi.o = Eigen::Vector3d(1, 2, 3);
  ClosestPoints cp;
  const LinkFrame par = NextFrame(fi, Line3{{1, 2.5, 7}, {0, 0, -3}}, {}, &cp);
  EXPECT_EQ(cp.constellation, LineConstellation::kParallel);
  EXPECT_LT((par.x - Eigen::Vector3d(0, 1, 0)).norm(), kExact);
  EXPECT_LT((par.o - Eigen::Vector3d(1, 2.5, 3)).norm(), kExact);
  const auto q = DhParametersBetween(fi, par);
  EXPECT_NEAR(q[kDhD], 0.0, kExact);
  EXPECT_NEAR(q[kDhA], 0.5, kExact);
  EXPECT_NEAR(q[kDhGamma], M_PI / 2, kExact);
  EXPECT_NEAR(std::abs(q[kDhAlpha]), M_PI, kExact);

  // Eq. 50: the last frame is the previous one.
  const LinkFrame last = NextFrame(par, Line3{par.o, par.z}, {}, &cp);
  EXPECT_EQ(cp.constellation, LineConstellation::kIdentical);
  ExpectSameFrame(last, par, kExact);
  for (double v : DhParametersBetween(par, last)) EXPECT_NEAR(v, 0.0, kExact);
}

// Eq. 45: x_1 is the reference x projected onto the plane of joint 1; the
// fallback projects y when the axis is (nearly) along x.
TEST(DhFrames, FirstFrameAlignsWithReferenceX) {
  const Eigen::Vector3d n = Eigen::Vector3d(0.1, -0.2, -1).normalized();
  const LinkFrame f = FirstFrame(Line3{{0.5, 0.5, 0.5}, 3.0 * n});
  EXPECT_LT((f.z - n).norm(), kExact);
  EXPECT_NEAR(f.x.dot(n), 0.0, kExact);
  // x_1 is the normalised projection of x_0: no component along z_1 and
  // x_0 - x_1 (x_0 . x_1) parallel to z_1.
  const Eigen::Vector3d x0 = Eigen::Vector3d::UnitX();
  EXPECT_LT((x0 - x0.dot(n) * n).normalized().cross(f.x).norm(), kExact);
  EXPECT_GT(f.x.x(), 0.0);
  EXPECT_NEAR(f.Rotation().determinant(), 1.0, kExact);
  EXPECT_LT((f.o - Eigen::Vector3d(0.5, 0.5, 0.5)).norm(), kExact);

  const LinkFrame g = FirstFrame(Line3{{0, 0, 0}, {-1, 0, 1e-5}});  // plane ~ parallel to yz
  EXPECT_NEAR(g.y.dot(Eigen::Vector3d::UnitY()), 1.0, 1e-9);
  EXPECT_NEAR(g.Rotation().determinant(), 1.0, kExact);
  EXPECT_NEAR(g.x.dot(g.z), 0.0, kExact);
}

// A whole two-joint chain: base, link 1 at joint angle q1, link 2; the frames
// from the two axes with frame 2 at q1 reproduce the chain (Eq. 9).
TEST(DhFrames, TwoJointChainFromAxes) {
  std::mt19937 rng(3);
  const Rigid3 base = RandomPose(rng);
  const std::array<double, 4> link1{0.01, 0.3, 1.4, 0.02};
  const double q1 = 0.8;
  const LinkFrame f1 = FrameFrom(base);
  const LinkFrame f2 = FrameFrom(base * Link(link1, q1));
  // The extraction sees only the axes; frame 1's x is its own convention, so
  // compare the DH parameters with frame 1 taken as given.
  const LinkFrame found2 = NextFrame(f1, Line3{f2.o - 0.7 * f2.z, f2.z}, {});
  const auto q = DhParametersBetween(f1, found2);
  EXPECT_NEAR(q[kDhGamma], link1[kDhGamma] + q1, kExact);
  EXPECT_NEAR(q[kDhD], link1[kDhD], kExact);
  EXPECT_NEAR(q[kDhA], link1[kDhA], kExact);
  EXPECT_NEAR(q[kDhAlpha], link1[kDhAlpha], kExact);
}

}  // namespace
}  // namespace rtscalib

#include "libcalib/geometry/lines.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace rtscalib {
namespace {

// Unit-scale exact geometry: Eq. 37 divides by a c - b^2 ~ sin^2 = O(1), so
// round-off stays within a few 1e-16; 1e-12 is a generous bound.
constexpr double kLinesExact = 1e-12;

TEST(ClosestPointsOfLines, SkewedLinesMeetTheCommonNormal) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 50; ++trial) {
    // Directions of length 0.5 .. 1.5 at 30 .. 150 deg to each other, so
    // that a c - b^2 = O(1) (well-conditioned Eq. 37).
    const Eigen::Vector3d dir0 = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    const Line3 l0{{u(rng), u(rng), u(rng)}, dir0 * (1.0 + 0.5 * u(rng))};
    // Build line 1 from a known common normal of length `dist`.
    const Eigen::Vector3d d0 = l0.direction;
    const Eigen::Vector3d normal = d0.unitOrthogonal();
    const double dist = 0.5 + 0.4 * u(rng);
    const double s_true = u(rng) * 3, t_true = u(rng) * 3;
    // Direction of line 1: perpendicular to the common normal, not parallel to d0.
    const double angle = M_PI / 2 + M_PI / 3 * u(rng);
    const Eigen::Vector3d d1 =
        (std::cos(angle) * d0.normalized() + std::sin(angle) * normal.cross(d0).normalized()) *
        (1.0 + u(rng) * 0.5);
    const Eigen::Vector3d q_s = l0.point + s_true * d0;
    const Eigen::Vector3d q_t = q_s + dist * normal;
    const Line3 l1{q_t - t_true * d1, d1};
    const ClosestPoints cp = ClosestPointsOfLines(l0, l1);
    EXPECT_EQ(cp.constellation, LineConstellation::kSkewed);
    EXPECT_NEAR(cp.s, s_true, kLinesExact * 10);
    EXPECT_NEAR(cp.t, t_true, kLinesExact * 10);
    EXPECT_LT((cp.q_s - q_s).norm(), kLinesExact * 10);
    EXPECT_LT((cp.q_t - q_t).norm(), kLinesExact * 10);
    EXPECT_NEAR(cp.distance, dist, kLinesExact * 10);
    // Eq. 36: v is perpendicular to both directions.
    EXPECT_NEAR(d0.dot(cp.q_s - cp.q_t), 0.0, kLinesExact * 10);
    EXPECT_NEAR(d1.dot(cp.q_s - cp.q_t), 0.0, kLinesExact * 10);
  }
}

TEST(ClosestPointsOfLines, IntersectingLines) {
  const Eigen::Vector3d x(0.3, -1.0, 2.0);
  const Line3 l0{x + 2.0 * Eigen::Vector3d(1, 0, 0), {1, 0, 0}};
  const Line3 l1{x - 0.7 * Eigen::Vector3d(1, 1, 1), {2, 2, 2}};
  const ClosestPoints cp = ClosestPointsOfLines(l0, l1);
  EXPECT_EQ(cp.constellation, LineConstellation::kIntersecting);
  EXPECT_LT((cp.q_s - x).norm(), kLinesExact);
  EXPECT_LT((cp.q_t - x).norm(), kLinesExact);
  EXPECT_NEAR(cp.s, -2.0, kLinesExact);
  EXPECT_NEAR(cp.t, 0.35, kLinesExact);
}

TEST(ClosestPointsOfLines, ParallelLinesUseTheFootOfQ0) {
  const Line3 l0{{1, 2, 3}, {0, 0, 1}};
  for (double scale : {-3.0, 0.5, 2.0}) {  // both Eq. 41 branches (b >= c and b < c)
    const Line3 l1{{1, 2.5, -4}, {0, 0, scale}};
    const ClosestPoints cp = ClosestPointsOfLines(l0, l1);
    EXPECT_EQ(cp.constellation, LineConstellation::kParallel) << scale;
    EXPECT_EQ(cp.s, 0.0);
    EXPECT_LT((cp.q_s - l0.point).norm(), kLinesExact);
    EXPECT_LT((cp.q_t - Eigen::Vector3d(1, 2.5, 3)).norm(), kLinesExact) << scale;
    EXPECT_NEAR(cp.distance, 0.5, kLinesExact);
  }
}

TEST(ClosestPointsOfLines, IdenticalLines) {
  const Line3 l0{{1, 2, 3}, {1, 1, 0}};
  const Line3 l1{{3, 4, 3}, {-2, -2, 0}};  // same line, other point, antiparallel
  const ClosestPoints cp = ClosestPointsOfLines(l0, l1);
  EXPECT_EQ(cp.constellation, LineConstellation::kIdentical);
  EXPECT_LT(cp.distance, kLinesExact);
  EXPECT_LT((cp.q_t - l0.point).norm(), kLinesExact);
}

// The tolerances decide borderline cases: a 1e-6 offset and a 1e-7 rad tilt
// are "skewed"/"parallel" at the exact defaults, "intersecting"/"identical"
// with looser ones.
TEST(ClosestPointsOfLines, TolerancesDecideBorderlineCases) {
  const Line3 l0{{0, 0, 0}, {1, 0, 0}};
  const Line3 skew{{0, 0, 1e-6}, {0, 1, 0}};
  EXPECT_EQ(ClosestPointsOfLines(l0, skew).constellation, LineConstellation::kSkewed);
  EXPECT_EQ(ClosestPointsOfLines(l0, skew, {1e-9, 1e-5}).constellation,
            LineConstellation::kIntersecting);

  const Line3 tilted{{0, 0, 1e-6}, {1, 1e-7, 0}};
  EXPECT_EQ(ClosestPointsOfLines(l0, tilted).constellation, LineConstellation::kSkewed);
  EXPECT_EQ(ClosestPointsOfLines(l0, tilted, {1e-6, 1e-9}).constellation,
            LineConstellation::kParallel);
  EXPECT_EQ(ClosestPointsOfLines(l0, tilted, {1e-6, 1e-5}).constellation,
            LineConstellation::kIdentical);

  EXPECT_EQ(LineTolerances().Check(), "");
  EXPECT_NE(LineTolerances({-1.0, 0.0}).Check(), "");
  EXPECT_STREQ(LineConstellationName(LineConstellation::kIdentical), "identical");
}

}  // namespace
}  // namespace rtscalib

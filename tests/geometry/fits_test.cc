#include "libcalib/geometry/fits.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "libcalib/geometry/rotation.h"

namespace rtscalib {
namespace {

// Points on the circle (center, normal, radius) at the given angles; the
// in-plane axes are any right-handed pair, so angles increase counter-clockwise
// about `normal`.
std::vector<Eigen::Vector3d> CirclePoints(const Eigen::Vector3d& center,
                                          const Eigen::Vector3d& normal, double radius,
                                          const std::vector<double>& angles) {
  const Eigen::Vector3d n = normal.normalized();
  Eigen::Vector3d e1 = n.unitOrthogonal();
  Eigen::Vector3d e2 = n.cross(e1);
  std::vector<Eigen::Vector3d> out;
  for (double a : angles) out.push_back(center + radius * (std::cos(a) * e1 + std::sin(a) * e2));
  return out;
}

std::vector<double> Angles(int n, double from, double to) {
  std::vector<double> a;
  for (int i = 0; i < n; ++i) a.push_back(from + (to - from) * i / n);
  return a;
}

double AxisAngle(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), std::abs(a.dot(b)));  // up to sign
}

// Exact data: the only error is double round-off in the SVDs of unit-scale
// matrices (Eq. 18 normalises), a few 1e-16 times a condition number of order
// 10 for 15 points spread over an arc; 1e-12 (relative to the radius) leaves
// a wide margin and still fails for any real mistake.
constexpr double kExact = 1e-12;

TEST(FitCircle, ExactCirclesOfManyScalesAndArcs) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (double scale : {1e-3, 1.0, 1e3}) {
    for (double arc : {2 * M_PI, M_PI, 0.5 * M_PI}) {
      for (int trial = 0; trial < 5; ++trial) {
        const Eigen::Vector3d center = scale * Eigen::Vector3d(u(rng), u(rng), u(rng)) * 10.0;
        const Eigen::Vector3d normal = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
        const double radius = scale * (1.0 + u(rng) * 0.5);
        const auto pts = CirclePoints(center, normal, radius, Angles(15, 0.0, arc));
        const CircleFit fit = FitCircle(pts);
        ASSERT_TRUE(fit.valid);
        EXPECT_LT((fit.center - center).norm(), kExact * scale * 10) << scale << " " << arc;
        EXPECT_NEAR(fit.radius, radius, kExact * scale * 10);
        EXPECT_LT(AxisAngle(fit.normal, normal), kExact * 10);
        EXPECT_LT(fit.rms, kExact * scale * 10);
        EXPECT_LT(fit.plane.rms, kExact * scale * 10);
        EXPECT_NEAR(fit.plane.basis.determinant(), 1.0, 1e-12);  // Eq. 19: no reflection
        EXPECT_LT(
            (fit.plane.basis.transpose() * fit.plane.basis - Eigen::Matrix3d::Identity()).norm(),
            1e-12);
      }
    }
  }
}

// Gaussian noise sigma on every coordinate, N points over the full circle.
// Expected spreads (first-order least squares): centre ~ sigma sqrt(2/N) in
// the plane, radius ~ sigma / sqrt(N), normal ~ sigma / (r sqrt(N/2)); we
// allow 5 of those (a 5-sigma bound for each trial). The RMS distance to the
// circle collects two of the three noise components: sigma sqrt(2) minus the
// few degrees of freedom fitted, so within 20 % for N = 400.
TEST(FitCircle, NoisyCircleWithinStatisticalBounds) {
  std::mt19937 rng(11);
  const double sigma = 1e-4, radius = 1.0;
  const int n = 400;
  std::normal_distribution<double> noise(0.0, sigma);
  for (int trial = 0; trial < 10; ++trial) {
    const Eigen::Vector3d center(0.3, -0.2, 1.5);
    const Eigen::Vector3d normal = Eigen::Vector3d(0.2, 0.1 * trial, 1.0).normalized();
    auto pts = CirclePoints(center, normal, radius, Angles(n, 0.0, 2 * M_PI));
    for (auto& p : pts) p += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    const CircleFit fit = FitCircle(pts);
    ASSERT_TRUE(fit.valid);
    EXPECT_LT((fit.center - center).norm(), 5 * sigma * std::sqrt(2.0 / n) * 1.5);
    EXPECT_NEAR(fit.radius, radius, 5 * sigma / std::sqrt(n));
    EXPECT_LT(AxisAngle(fit.normal, normal), 5 * sigma / (radius * std::sqrt(n / 2.0)));
    EXPECT_NEAR(fit.rms, sigma * std::sqrt(2.0), 0.2 * sigma * std::sqrt(2.0));
  }
}

TEST(FitCircle, CollinearPointsAreInvalid) {
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 10; ++i) {
    pts.push_back(Eigen::Vector3d(1, 2, 3) + i * Eigen::Vector3d(1, 1, 0));
  }
  const CircleFit fit = FitCircle(pts);
  EXPECT_FALSE(fit.valid);
  EXPECT_TRUE(std::isinf(fit.rms));
}

TEST(FitCircle, TooFewPointsThrow) {
  EXPECT_THROW(FitCircle({Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX()}),
               std::invalid_argument);
  EXPECT_THROW(FitPlane({}), std::invalid_argument);
  EXPECT_THROW(FitLine({Eigen::Vector3d::Zero()}), std::invalid_argument);
}

TEST(FitPlane, ExactPlaneHasZeroResidualAndRightHandedBasis) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::Vector3d normal = Eigen::Vector3d(1, -2, 0.5).normalized();
  const Eigen::Vector3d e1 = normal.unitOrthogonal(), e2 = normal.cross(e1);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 30; ++i) pts.push_back(Eigen::Vector3d(4, 5, 6) + u(rng) * e1 + u(rng) * e2);
  const PlaneFit fit = FitPlane(pts);
  EXPECT_LT(AxisAngle(fit.Normal(), normal), kExact);
  EXPECT_LT(fit.rms, kExact);
  EXPECT_NEAR(fit.basis.determinant(), 1.0, 1e-12);
  EXPECT_NEAR(fit.singular_values[2], 0.0, kExact);
  // Eq. 18: k is the largest absolute centred coordinate.
  double k = 0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : pts) mean += p / 30.0;
  for (const auto& p : pts) k = std::max(k, (p - mean).cwiseAbs().maxCoeff());
  EXPECT_NEAR(fit.scale, k, 1e-14);  // same quantity, mean summed in another order
}

TEST(FitLine, ExactAndNoisyLines) {
  const Eigen::Vector3d dir = Eigen::Vector3d(1, 2, -1).normalized();
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 15; ++i) pts.push_back(Eigen::Vector3d(0.5, 0, 1) + 0.1 * i * dir);
  LineFit fit = FitLine(pts);
  EXPECT_LT(AxisAngle(fit.direction, dir), kExact);
  EXPECT_LT(fit.rms, kExact);
  EXPECT_NEAR(fit.extent, 1.4, kExact);

  // Noise sigma per coordinate: two of three components are perpendicular,
  // RMS ~ sigma sqrt(2) (20 % for 1000 points, as for the circle).
  std::mt19937 rng(2);
  const double sigma = 1e-3;
  std::normal_distribution<double> noise(0.0, sigma);
  pts.clear();
  for (int i = 0; i < 1000; ++i) {
    pts.push_back(i * 1e-3 * dir + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
  }
  fit = FitLine(pts);
  EXPECT_NEAR(fit.rms, sigma * std::sqrt(2.0), 0.2 * sigma * std::sqrt(2.0));
  // Direction error ~ sigma / (extent * sqrt(N / 12)); 5 of those.
  EXPECT_LT(AxisAngle(fit.direction, dir), 5 * sigma / (1.0 * std::sqrt(1000 / 12.0)));
}

TEST(CorrectNormalSign, PositiveRotationForIncreasingControl) {
  const Eigen::Vector3d normal = Eigen::Vector3d(0.1, -0.3, 1).normalized();
  const Eigen::Vector3d center(1, 2, 3);
  // Angles increase counter-clockwise about `normal` (CirclePoints).
  const auto pts = CirclePoints(center, normal, 2.0, {0.1, 0.5});
  EXPECT_LT((CorrectNormalSign(normal, center, pts[0], pts[1]) - normal).norm(), 1e-15);
  EXPECT_LT((CorrectNormalSign(-normal, center, pts[0], pts[1]) - normal).norm(), 1e-15);
  // Reversed order means a negative rotation about `normal`.
  EXPECT_LT((CorrectNormalSign(normal, center, pts[1], pts[0]) + normal).norm(), 1e-15);
  // Eq. 32: sign(0) = +1 keeps the normal.
  EXPECT_LT((CorrectNormalSign(normal, center, pts[0], pts[0]) - normal).norm(), 1e-15);
  // Fitted normal has arbitrary sign; after correction it matches.
  const auto sweep = CirclePoints(center, normal, 2.0, Angles(15, 0.0, 2 * M_PI));
  const CircleFit fit = FitCircle(sweep);
  EXPECT_LT((CorrectNormalSign(fit.normal, fit.center, sweep[0], sweep[1]) - normal).norm(), 1e-12);
}

TEST(CorrectDirectionSign, PointsAlongIncreasingControl) {
  const Eigen::Vector3d dir(0, 0, 1);
  EXPECT_EQ(CorrectDirectionSign(-dir, Eigen::Vector3d::Zero(), dir), dir);
  EXPECT_EQ(CorrectDirectionSign(dir, dir, Eigen::Vector3d::Zero()), -dir);
}

}  // namespace
}  // namespace rtscalib

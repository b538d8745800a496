#include "libcalib/geometry/kabsch.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

namespace rtscalib {
namespace {

Eigen::Matrix3d RandomRotation(std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::Quaterniond q(g(rng), g(rng), g(rng), g(rng));
  return q.normalized().toRotationMatrix();
}

// Exact correspondences of unit-scale point sets: round-off only (the SVD of
// a 3x3 matrix with well separated singular values); 1e-12 is generous.
constexpr double kKabschExact = 1e-12;

TEST(Kabsch, RecoversRandomTransforms) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int n : {3, 4, 10, 100}) {
    for (int trial = 0; trial < 20; ++trial) {
      const Rigid3 truth{RandomRotation(rng), Eigen::Vector3d(u(rng), u(rng), u(rng)) * 5};
      std::vector<Eigen::Vector3d> a, b;
      for (int i = 0; i < n; ++i) {
        a.emplace_back(u(rng), u(rng), u(rng));
        b.push_back(truth * a.back());
      }
      const KabschResult r = Kabsch(a, b);
      EXPECT_LT((r.b_from_a.rotation - truth.rotation).norm(), kKabschExact) << n;
      EXPECT_LT((r.b_from_a.translation - truth.translation).norm(), kKabschExact * 10) << n;
      EXPECT_LT(r.rms, kKabschExact);
      EXPECT_EQ(r.rank, n == 3 ? 2 : 3);  // three points are always coplanar
    }
  }
}

// Coplanar sets: H has rank 2 and the best orthogonal matrix is ambiguous
// between the rotation and its mirror; Eq. 56's det factor picks the rotation.
TEST(Kabsch, CoplanarPointsGiveTheRotationNotItsMirror) {
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 20; ++trial) {
    const Rigid3 truth{RandomRotation(rng), Eigen::Vector3d(u(rng), u(rng), u(rng))};
    std::vector<Eigen::Vector3d> a, b;
    for (int i = 0; i < 6; ++i) {
      a.emplace_back(u(rng), u(rng), 0.0);
      b.push_back(truth * a.back());
    }
    const KabschResult r = Kabsch(a, b);
    EXPECT_NEAR(r.b_from_a.rotation.determinant(), 1.0, kKabschExact);
    EXPECT_LT((r.b_from_a.rotation - truth.rotation).norm(), kKabschExact);
  }
}

// Mirrored data: b is a reflection of a. No rotation fits; the result must
// still be a proper rotation (det +1), and the best one: Arun's corrected
// solution flips the axis of the smallest singular value.
TEST(Kabsch, ReflectedDataStillGivesAProperRotation) {
  std::vector<Eigen::Vector3d> a, b;
  // Symmetric box, large in x and y, thin in z (diagonal covariance); mirror z.
  for (double x : {-3.0, 3.0}) {
    for (double y : {-2.0, 0.0, 2.0}) {
      for (double z : {-0.1, 0.1}) {
        a.emplace_back(x, y, z);
        b.emplace_back(x, y, -z);
      }
    }
  }
  const KabschResult r = Kabsch(a, b);
  EXPECT_NEAR(r.b_from_a.rotation.determinant(), 1.0, kKabschExact);
  // H = diag(Sxx, Syy, -Szz): the best proper rotation keeps x and y and
  // gives up the thin z extent, i.e. the identity.
  EXPECT_LT((r.b_from_a.rotation - Eigen::Matrix3d::Identity()).norm(), kKabschExact);
  EXPECT_GT(r.rms, 0.0);
}

// Noise sigma per coordinate on N points uniform in [-1, 1]^3 (RMS spread
// 1/sqrt(3) = 0.58 per axis): rotation error ~ sigma / (0.58 sqrt(N)); allow
// 5x (a 5-sigma bound). The residual RMS collects all three noise components,
// sigma sqrt(3), within 20 % for N = 200.
TEST(Kabsch, NoisyDataWithinStatisticalBounds) {
  std::mt19937 rng(10);
  std::uniform_real_distribution<double> u(-1, 1);
  const double sigma = 1e-4;
  std::normal_distribution<double> noise(0.0, sigma);
  const int n = 200;
  for (int trial = 0; trial < 10; ++trial) {
    const Rigid3 truth{RandomRotation(rng), Eigen::Vector3d(u(rng), u(rng), u(rng))};
    std::vector<Eigen::Vector3d> a, b;
    for (int i = 0; i < n; ++i) {
      a.emplace_back(u(rng), u(rng), u(rng));
      b.push_back(truth * a.back() + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
    }
    const KabschResult r = Kabsch(a, b);
    const Eigen::AngleAxisd err(r.b_from_a.rotation * truth.rotation.transpose());
    EXPECT_LT(std::abs(err.angle()), 5 * sigma / (0.58 * std::sqrt(n)));
    EXPECT_NEAR(r.rms, sigma * std::sqrt(3.0), 0.2 * sigma * std::sqrt(3.0));
  }
}

// RobustKabsch: with 20 % of the pairs moved by 1 cm to 1 km, the fit on the
// others equals plain Kabsch on the clean pairs (the same pairs, so to
// round-off: 1e-12), and the moved pairs are the ones reported. Without
// gross pairs it is plain Kabsch on all of them.
TEST(Kabsch, RobustKabschIgnoresGrossPairs) {
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> u(-1, 1), exponent(-2, 3);
  std::normal_distribution<double> noise(0.0, 1e-5), dir;
  const Rigid3 truth{RandomRotation(rng), Eigen::Vector3d(u(rng), u(rng), u(rng))};
  std::vector<Eigen::Vector3d> a, b, clean_a, clean_b;
  std::vector<int> moved;
  for (int i = 0; i < 60; ++i) {
    a.emplace_back(u(rng), u(rng), u(rng));
    b.push_back(truth * a.back() + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
    if (i % 5 == 2) {
      b.back() += std::pow(10.0, exponent(rng)) *
                  Eigen::Vector3d(dir(rng), dir(rng), dir(rng)).normalized();
      moved.push_back(i);
    } else {
      clean_a.push_back(a.back());
      clean_b.push_back(b.back());
    }
  }
  std::vector<int> outliers;
  const KabschResult r = RobustKabsch(a, b, 1e-4, &outliers);
  EXPECT_EQ(outliers, moved);
  const KabschResult c = Kabsch(clean_a, clean_b);
  EXPECT_TRUE(r.b_from_a.rotation.isApprox(c.b_from_a.rotation, 1e-12));
  EXPECT_TRUE(r.b_from_a.translation.isApprox(c.b_from_a.translation, 1e-12));

  const KabschResult all = RobustKabsch(clean_a, clean_b, 1e-4, &outliers);
  EXPECT_TRUE(outliers.empty());
  EXPECT_TRUE(all.b_from_a.rotation.isApprox(c.b_from_a.rotation, 1e-12));
}

TEST(Kabsch, RejectsBadInput) {
  std::vector<Eigen::Vector3d> two(2, Eigen::Vector3d::Zero()), three(3, Eigen::Vector3d::Zero());
  EXPECT_THROW(Kabsch(two, two), std::invalid_argument);
  EXPECT_THROW(Kabsch(three, two), std::invalid_argument);
}

}  // namespace
}  // namespace rtscalib

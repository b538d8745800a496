#include "libcalib/fit/manifolds.h"

#include <ceres/manifold_test_utils.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

namespace rtscalib {
namespace {

using namespace ceres;  // the matchers of EXPECT_THAT_MANIFOLD_INVARIANTS_HOLD

Eigen::VectorXd RandomUnitQuaternion(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::VectorXd q(4);
  for (int i = 0; i < 4; ++i) q[i] = n(rng);
  q.normalize();
  if (q[3] < 0) q = -q;
  return q;
}

// Ceres's own invariants (x [+] 0 = x, (x [+] d) [-] x = d, Jacobians against
// numeric differences, ...) at random quaternions and steps up to ~0.5 rad.
// `y` must be reachable from `x` on this 2-dimensional manifold (no roll), so
// it is x [+] (another step). Tolerance 1e-9: the invariants are exact up to
// round-off; the Jacobian checks use Ceres's numeric differences (~1e-10).
TEST(QuaternionNoRollManifold, InvariantsHold) {
  const QuaternionNoRollManifold manifold;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  constexpr double kTolerance = 1e-9;
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::VectorXd x = RandomUnitQuaternion(rng);
    Eigen::VectorXd delta(2), step(2);
    delta << u(rng), u(rng);
    step << u(rng), u(rng);
    Eigen::VectorXd y(4);
    ASSERT_TRUE(manifold.Plus(x.data(), step.data(), y.data()));
    EXPECT_THAT_MANIFOLD_INVARIANTS_HOLD(manifold, x, delta, y, kTolerance);
  }
}

// The step turns the frame about its own x and y axes only: its z axis (the
// EDM ray) moves, the roll about it stays.
TEST(QuaternionNoRollManifold, StepIsAboutLocalXAndYOnly) {
  const QuaternionNoRollManifold manifold;
  std::mt19937_64 rng(3);
  const Eigen::VectorXd x = RandomUnitQuaternion(rng);
  const double delta[2] = {0.02, -0.03};
  Eigen::VectorXd y(4);
  ASSERT_TRUE(manifold.Plus(x.data(), delta, y.data()));
  const Eigen::Quaterniond qx(x[3], x[0], x[1], x[2]), qy(y[3], y[0], y[1], y[2]);
  const Eigen::AngleAxisd local(qx.conjugate() * qy);
  const Eigen::Vector3d rotvec = local.angle() * local.axis();
  EXPECT_NEAR(rotvec.x(), 0.02, 1e-15);
  EXPECT_NEAR(rotvec.y(), -0.03, 1e-15);
  EXPECT_NEAR(rotvec.z(), 0.0, 1e-15);
  EXPECT_NEAR(qy.norm(), 1.0, 1e-15);
}

}  // namespace
}  // namespace rtscalib

#include "libcalib/model/kinematics.h"

#include <gtest/gtest.h>

#include <random>

namespace rtscalib {
namespace {

// The snapped PLT 300 model (Klug Tables 1/2, Eq. 84-88) in both kinematics
// must equal Eq. 90: R = Rz(-phi) Rx(-theta), zero translation. Tolerance 1e-12:
// a handful of double-precision products of unit-magnitude terms.
TEST(Kinematics, IdealModelsReproduceEq90) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> phi_dist(0, 2 * M_PI), theta_dist(0, M_PI);
  for (Kinematics k : {Kinematics::kDh, Kinematics::kSpherical}) {
    const InstrumentModel m = IdealModel(k, 1, CameraTool{});
    for (int i = 0; i < 50; ++i) {
      const double phi = phi_dist(rng), theta = theta_dist(rng);
      const Rigid3 ref_from_edm = RefFromEdm(m, phi, theta);
      const Eigen::Matrix3d expected = Rz(-phi) * Rx(-theta);
      EXPECT_LT((ref_from_edm.rotation - expected).norm(), 1e-12) << KinematicsName(k);
      const Eigen::Vector3d p = PredictEdm(m, phi, theta, 2.0);
      const Eigen::Vector3d ideal =
          2.0 * Eigen::Vector3d(std::sin(phi) * std::sin(theta), std::cos(phi) * std::sin(theta),
                                std::cos(theta));
      EXPECT_LT((p - ideal).norm(), 1e-12);
    }
  }
}

// A camera point at the principal point lies on the camera z axis.
TEST(Kinematics, CamPointAtPrincipalPointIsOnOpticalAxis) {
  const InstrumentModel m = IdealModel(Kinematics::kSpherical, 1, CameraTool{});
  const auto& c = m.cams[0].intrinsics;
  const Eigen::Vector3d p = PredictCam(m, 0, 0.3, 1.2, c[2], c[3], 1.0);
  EXPECT_LT((p - PredictEdm(m, 0.3, 1.2, 1.0)).norm(), 1e-12);
}

}  // namespace
}  // namespace rtscalib

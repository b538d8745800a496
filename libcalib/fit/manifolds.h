// Manifolds for the refinement.
//
// `QuaternionNoRollManifold`: a unit quaternion (Eigen order x, y, z, w)
// perturbed only about its own local x and y axes: q [+] d = q * exp([d0, d1, 0]).
// The EDM measures along its z axis, so rotation about that axis (roll) is not
// observable; it stays at the value the extraction set by convention (Klug
// Eq. 79: EDM x = camera x projected onto the plane normal to the ray).
#pragma once

#include <ceres/autodiff_manifold.h>
#include <ceres/manifold.h>
#include <ceres/rotation.h>

#include <ceres/problem.h>

#include <cmath>
#include <vector>

namespace rtscalib {

struct QuaternionNoRollPlus {
  template <typename T>
  bool Plus(const T* x, const T* delta, T* x_plus_delta) const {
    // exp of the rotation vector (d0, d1, 0) as a quaternion in Eigen order.
    using std::cos;
    using std::sin;
    using std::sqrt;
    const T n2 = delta[0] * delta[0] + delta[1] * delta[1];
    T e[4];  // x, y, z, w
    if (n2 > T(1e-30)) {
      const T n = sqrt(n2);
      const T s = sin(n / T(2)) / n;
      e[0] = delta[0] * s;
      e[1] = delta[1] * s;
      e[2] = T(0);
      e[3] = cos(n / T(2));
    } else {
      e[0] = delta[0] / T(2);
      e[1] = delta[1] / T(2);
      e[2] = T(0);
      e[3] = T(1);
    }
    // x * e (Hamilton product, Eigen storage).
    x_plus_delta[3] = x[3] * e[3] - x[0] * e[0] - x[1] * e[1] - x[2] * e[2];
    x_plus_delta[0] = x[3] * e[0] + x[0] * e[3] + x[1] * e[2] - x[2] * e[1];
    x_plus_delta[1] = x[3] * e[1] - x[0] * e[2] + x[1] * e[3] + x[2] * e[0];
    x_plus_delta[2] = x[3] * e[2] + x[0] * e[1] - x[1] * e[0] + x[2] * e[3];
    return true;
  }
  template <typename T>
  bool Minus(const T* y, const T* x, T* y_minus_x) const {
    // r = x^-1 * y; return the x, y components of its rotation vector.
    using std::atan2;
    using std::sqrt;
    const T xi[4] = {-x[0], -x[1], -x[2], x[3]};
    T r[4];
    r[3] = xi[3] * y[3] - xi[0] * y[0] - xi[1] * y[1] - xi[2] * y[2];
    r[0] = xi[3] * y[0] + xi[0] * y[3] + xi[1] * y[2] - xi[2] * y[1];
    r[1] = xi[3] * y[1] - xi[0] * y[2] + xi[1] * y[3] + xi[2] * y[0];
    r[2] = xi[3] * y[2] + xi[0] * y[1] - xi[1] * y[0] + xi[2] * y[3];
    const T s2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
    if (s2 > T(1e-30)) {
      const T s = sqrt(s2);
      const T angle = T(2) * atan2(s, r[3]);
      y_minus_x[0] = r[0] * angle / s;
      y_minus_x[1] = r[1] * angle / s;
    } else {
      y_minus_x[0] = T(2) * r[0];
      y_minus_x[1] = T(2) * r[1];
    }
    return true;
  }
};

using QuaternionNoRollManifold = ceres::AutoDiffManifold<QuaternionNoRollPlus, 4, 2>;

// How a parameter block enters a problem: held, free, or free on a manifold.
enum class BlockKind { kConstant, kFree, kQuaternion, kNoRoll, kSubset };

// The one place that turns a block's kind into Ceres calls (used by the
// refinement and by the diagnosis's linearisation). `frozen` lists the held
// indices of a kSubset block of `size` parameters.
inline void ParameterizeBlock(ceres::Problem* problem, double* p, BlockKind kind, int size,
                              const std::vector<int>& frozen) {
  switch (kind) {
    case BlockKind::kConstant:
      problem->SetParameterBlockConstant(p);
      break;
    case BlockKind::kQuaternion:
      problem->SetManifold(p, new ceres::EigenQuaternionManifold);
      break;
    case BlockKind::kNoRoll:
      problem->SetManifold(p, new QuaternionNoRollManifold);
      break;
    case BlockKind::kSubset:
      problem->SetManifold(p, new ceres::SubsetManifold(size, frozen));
      break;
    case BlockKind::kFree:
      break;
  }
}

}  // namespace rtscalib

// The robust loss applied per observation inside a grouped residual block
// (libcalib/fit/observation_loss.h) against Ceres's own LossFunction on one
// block per observation.
#include "libcalib/fit/observation_loss.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace rtscalib {
namespace {

// Points (x_i, y_i) on a line y = a x + c, two residuals per observation
// (the second a scaled copy, so that an observation's slice has dim 2).
struct LineResidual {
  std::vector<double> x, y;
  template <typename T>
  bool operator()(T const* const* params, T* r) const {
    const T* p = params[0];
    for (size_t i = 0; i < x.size(); ++i) {
      const T e = p[0] * x[i] + p[1] - y[i];
      r[2 * i] = e;
      r[2 * i + 1] = 0.5 * e + 0.1 * p[0];
    }
    return true;
  }
};

ceres::CostFunction* LineCost(std::vector<double> x, std::vector<double> y) {
  const int n = static_cast<int>(x.size());
  auto* f = new ceres::DynamicAutoDiffCostFunction<LineResidual>(new LineResidual{x, y});
  f->AddParameterBlock(2);
  f->SetNumResiduals(2 * n);
  return f;
}

TEST(ObservationLoss, SquaredResidualIsTheLossAndTheJacobianIsItsDerivative) {
  for (const RobustLoss loss : {RobustLoss::kHuber, RobustLoss::kCauchy}) {
    // Observations near 0 (the series branch of Cauchy), near the scale
    // and far beyond it (Huber's linear part).
    const std::vector<double> x = {0.0, 1.0, 2.0, 3.0};
    const std::vector<double> y = {1e-6, 0.9, 4.0, 30.0};
    ObservationLoss f(LineCost(x, y), 2, loss, 1.5);
    double p[2] = {0.3, 0.2};
    const double* params[] = {p};
    std::vector<double> r(8), J(16);
    double* jac[] = {J.data()};
    ASSERT_TRUE(f.Evaluate(params, r.data(), jac));
    std::vector<double> raw(8);
    ASSERT_TRUE(f.Inner().Evaluate(params, raw.data(), nullptr));
    for (int i = 0; i < 4; ++i) {
      const double s = raw[2 * i] * raw[2 * i] + raw[2 * i + 1] * raw[2 * i + 1];
      const double s_tilde = r[2 * i] * r[2 * i] + r[2 * i + 1] * r[2 * i + 1];
      // Round-off of a few operations on numbers of order 1e3.
      EXPECT_NEAR(s_tilde, LossOf(loss, 1.5, s), 1e-12 * (1 + s)) << "observation " << i;
    }
    // Central differences, step 1e-6: truncation ~1e-12 x the third
    // derivative, round-off ~1e-16 / 1e-6 x |r| ~ 1e-9.
    for (int c = 0; c < 2; ++c) {
      double pp[2] = {p[0], p[1]}, pm[2] = {p[0], p[1]};
      pp[c] += 1e-6;
      pm[c] -= 1e-6;
      std::vector<double> rp(8), rm(8);
      const double* ppp[] = {pp};
      const double* ppm[] = {pm};
      ASSERT_TRUE(f.Evaluate(ppp, rp.data(), nullptr));
      ASSERT_TRUE(f.Evaluate(ppm, rm.data(), nullptr));
      for (int k = 0; k < 8; ++k) {
        EXPECT_NEAR(J[2 * k + c], (rp[k] - rm[k]) / 2e-6, 1e-6) << "row " << k << " col " << c;
      }
    }
  }
}

TEST(ObservationLoss, GroupedFitHasCeresPerBlockMinimum) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.1);
  std::vector<double> x, y;
  for (int i = 0; i < 60; ++i) {
    x.push_back(0.1 * i);
    y.push_back(2.0 * x.back() - 1.0 + noise(rng) + (i % 10 == 3 ? 5.0 : 0.0));  // 6 outliers
  }
  for (const RobustLoss loss : {RobustLoss::kHuber, RobustLoss::kCauchy}) {
    double grouped[2] = {0, 0}, per_block[2] = {0, 0};
    ceres::Problem a, b;
    // Observations in groups of 6, as a photo's corners share a block.
    for (int g = 0; g < 10; ++g) {
      std::vector<double> gx(x.begin() + 6 * g, x.begin() + 6 * g + 6);
      std::vector<double> gy(y.begin() + 6 * g, y.begin() + 6 * g + 6);
      a.AddResidualBlock(new ObservationLoss(LineCost(gx, gy), 2, loss, 0.2), nullptr, grouped);
    }
    for (size_t i = 0; i < x.size(); ++i) {
      ceres::LossFunction* l = loss == RobustLoss::kHuber
                                   ? static_cast<ceres::LossFunction*>(new ceres::HuberLoss(0.2))
                                   : new ceres::CauchyLoss(0.2);
      b.AddResidualBlock(LineCost({x[i]}, {y[i]}), l, per_block);
    }
    ceres::Solver::Options o;
    o.function_tolerance = 1e-14;
    o.gradient_tolerance = 1e-14;
    o.parameter_tolerance = 1e-14;
    o.max_num_iterations = 200;
    ceres::Solver::Summary sa, sb;
    ceres::Solve(o, &a, &sa);
    ceres::Solve(o, &b, &sb);
    // The same objective: the same minimum and the same cost. Tolerance:
    // both stop at a relative step of 1e-14 on a well-conditioned 2-parameter
    // problem; 1e-7 leaves room for the flat robust valley.
    EXPECT_NEAR(grouped[0], per_block[0], 1e-7);
    EXPECT_NEAR(grouped[1], per_block[1], 1e-7);
    EXPECT_NEAR(sa.final_cost, sb.final_cost, 1e-9 * sb.final_cost);
    // And the outliers did not pull the line: slope within 5 sigma of 2
    // (the slope's sigma from 54 inliers of 0.1 over x in [0, 5.9] is ~0.008).
    EXPECT_NEAR(grouped[0], 2.0, 0.05);
  }
}

}  // namespace
}  // namespace rtscalib

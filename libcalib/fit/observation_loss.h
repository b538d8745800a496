// A robust loss per observation inside a residual block that holds many.
//
// The refinement evaluates one residual block per photo (and per record
// group): the chain from the base to the camera is differentiated once for
// all of a photo's corners. Ceres's LossFunction acts on a whole block, so a
// robust fit with Ceres's loss alone needs one block per observation, which
// evaluates the chain once per corner instead of once per photo. This decorator applies the loss to each observation's
// slice of a grouped block instead: the residual of observation i, r_i
// (2 numbers for a pixel, 3 for a record, already whitened), becomes
//
//   r~_i = g(s_i) r_i,  g(s) = sqrt(rho(s) / s),  s_i = |r_i|^2,
//
// so that |r~_i|^2 = rho(s_i): the block's cost is exactly the sum of the
// robust losses, the objective Ceres minimises with one block per
// observation and the same LossFunction. Its Jacobian follows by the chain
// rule, J~_i = g J_i + 2 g'(s_i) r_i (r_i^T J_i): Gauss-Newton on the
// rescaled residuals (Ceres corrects the Jacobian after Triggs et al. 2000
// instead; both converge to the minimiser of the same objective). rho is
// Ceres's: Huber rho(s) = s for s <= b, 2 sqrt(b s) - b beyond; Cauchy
// rho(s) = b log(1 + s / b); b = scale^2.
#pragma once

#include <memory>

#include <ceres/ceres.h>

#include "libcalib/fit/options.h"

namespace rtscalib {

// g(s) and g'(s) of the loss (see above); kNone gives g = 1, g' = 0.
struct LossScaling {
  double g = 1, dg = 0;
};
LossScaling ScalingOf(RobustLoss loss, double scale, double s);

// rho(s) of the loss: what an observation of squared whitened norm s adds
// to twice the cost.
double LossOf(RobustLoss loss, double scale, double s);

class ObservationLoss : public ceres::CostFunction {
 public:
  // `inner` (owned) returns `dim` residuals per observation, observation
  // after observation.
  ObservationLoss(ceres::CostFunction* inner, int dim, RobustLoss loss, double scale);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  // The block without the loss: the whitened residuals as least squares sees them.
  const ceres::CostFunction& Inner() const { return *inner_; }

 private:
  std::unique_ptr<ceres::CostFunction> inner_;
  int dim_;
  RobustLoss loss_;
  double scale_;
};

// The residuals of block `id` without any ObservationLoss (least squares'
// whitened residuals); false when the block cannot be evaluated.
bool EvaluateWithoutLoss(const ceres::Problem& problem, ceres::ResidualBlockId id,
                         std::vector<double>* residuals);

}  // namespace rtscalib

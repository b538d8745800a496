#include "libcalib/fit/observation_loss.h"

#include <cmath>
#include <stdexcept>
#include <vector>

namespace rtscalib {

double LossOf(RobustLoss loss, double scale, double s) {
  const double b = scale * scale;
  switch (loss) {
    case RobustLoss::kHuber:
      return s <= b ? s : 2.0 * std::sqrt(b * s) - b;
    case RobustLoss::kCauchy:
      return b * std::log1p(s / b);
    case RobustLoss::kNone:
      break;
  }
  return s;
}

LossScaling ScalingOf(RobustLoss loss, double scale, double s) {
  const double b = scale * scale;
  // h(s) = rho(s) / s and h' = (rho'(s) s - rho(s)) / s^2; g = sqrt(h),
  // g' = h' / (2 g).
  double h = 1, dh = 0;
  switch (loss) {
    case RobustLoss::kHuber:
      if (s > b) {
        const double rho = LossOf(loss, scale, s);
        h = rho / s;
        dh = (std::sqrt(b / s) * s - rho) / (s * s);  // rho' = sqrt(b / s)
      }
      break;
    case RobustLoss::kCauchy: {
      const double x = s / b;
      if (x < 1e-4) {
        // log1p(x) / x by its series: the quotient loses digits near 0.
        h = 1.0 - x / 2.0 + x * x / 3.0 - x * x * x / 4.0;
        dh = (-0.5 + 2.0 * x / 3.0 - 0.75 * x * x) / b;
      } else {
        const double rho = LossOf(loss, scale, s);
        h = rho / s;
        dh = (s / (1.0 + x) - rho) / (s * s);  // rho' = 1 / (1 + s / b)
      }
      break;
    }
    case RobustLoss::kNone:
      break;
  }
  LossScaling out;
  out.g = std::sqrt(h);
  out.dg = dh / (2.0 * out.g);
  return out;
}

ObservationLoss::ObservationLoss(ceres::CostFunction* inner, int dim, RobustLoss loss,
                                 double scale)
    : inner_(inner), dim_(dim), loss_(loss), scale_(scale) {
  if (dim <= 0 || inner->num_residuals() % dim != 0) {
    throw std::logic_error("ObservationLoss: " + std::to_string(inner->num_residuals()) +
                           " residuals are not observations of " + std::to_string(dim));
  }
  set_num_residuals(inner->num_residuals());
  *mutable_parameter_block_sizes() = inner->parameter_block_sizes();
}

bool ObservationLoss::Evaluate(double const* const* parameters, double* residuals,
                               double** jacobians) const {
  if (!inner_->Evaluate(parameters, residuals, jacobians)) return false;
  const std::vector<int32_t>& sizes = parameter_block_sizes();
  const int n = num_residuals();
  for (int row = 0; row < n; row += dim_) {
    double* r = residuals + row;
    double s = 0;
    for (int k = 0; k < dim_; ++k) s += r[k] * r[k];
    const LossScaling f = ScalingOf(loss_, scale_, s);
    if (jacobians != nullptr) {
      for (size_t b = 0; b < sizes.size(); ++b) {
        if (jacobians[b] == nullptr) continue;
        const int cols = sizes[b];
        double* J = jacobians[b] + static_cast<size_t>(row) * cols;  // dim_ rows, row-major
        for (int c = 0; c < cols; ++c) {
          double rtj = 0;  // r^T J, column c
          for (int k = 0; k < dim_; ++k) rtj += r[k] * J[k * cols + c];
          for (int k = 0; k < dim_; ++k) {
            J[k * cols + c] = f.g * J[k * cols + c] + 2.0 * f.dg * r[k] * rtj;
          }
        }
      }
    }
    for (int k = 0; k < dim_; ++k) r[k] *= f.g;
  }
  return true;
}

bool EvaluateWithoutLoss(const ceres::Problem& problem, ceres::ResidualBlockId id,
                         std::vector<double>* residuals) {
  const ceres::CostFunction* cost = problem.GetCostFunctionForResidualBlock(id);
  if (const auto* wrapped = dynamic_cast<const ObservationLoss*>(cost)) cost = &wrapped->Inner();
  std::vector<double*> blocks;
  problem.GetParameterBlocksForResidualBlock(id, &blocks);
  residuals->assign(cost->num_residuals(), 0.0);
  return cost->Evaluate(blocks.data(), residuals->data(), nullptr);
}

}  // namespace rtscalib

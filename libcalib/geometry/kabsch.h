// Least-squares rigid transform between two corresponding point sets: Arun et
// al. 1987 / Kabsch 1976, as in Klug et al. Sec. 3.1.9 (Eq. 51-57).
//
//   (R, t) = argmin sum_i |R a_i + t - b_i|^2                         (Eq. 51)
//   a_bar, b_bar = centroids                                           (Eq. 52)
//   H = sum_i (a_i - a_bar)(b_i - b_bar)^T                             (Eq. 53, 54)
//   SVD(H) = U S V^T                                                   (Eq. 55)
//   R = V diag(1, 1, det(V U^T)) U^T                                   (Eq. 56)
//   t = b_bar - R a_bar                                                (Eq. 57)
//
// The det(V U^T) factor makes R a proper rotation even when the best
// orthogonal fit is a reflection (noisy or coplanar/mirrored data). With
// exactly three non-collinear points, or any coplanar set, H has rank 2 and
// the factor also fixes the otherwise undetermined third axis, so the result
// is the unique rotation. Collinear or coincident points (rank < 2) leave the
// rotation about the line undetermined; KabschResult::rank reports it.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "libcalib/geometry/rotation.h"

namespace rtscalib {

struct KabschResult {
  Rigid3 b_from_a;   // b_i ~ b_from_a * a_i
  double rms = 0.0;  // sqrt(mean |R a_i + t - b_i|^2), units of the points
  // Numerical rank of H (singular values above 1e-12 times the largest):
  // 3 general, 2 coplanar (still unique), < 2 degenerate.
  int rank = 0;
};

// Throws std::invalid_argument when the sets differ in size or hold fewer than
// 3 points.
KabschResult Kabsch(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b);

// Kabsch on the correspondences that agree: least median of squares over
// random 3-point samples (a sample free of gross errors wins as long as
// fewer than half the pairs are wrong), then Kabsch on the pairs whose
// residual is within max(8 robust sigmas, `floor`) of that fit (robust sigma
// of one coordinate = median residual / 1.5382, the median of chi with 3
// degrees of freedom). Equal to Kabsch when no pair is off. `outliers`,
// when given, receives the indices of the pairs left out. Sets of fewer
// than 6 pairs go to Kabsch unchanged. Throws as Kabsch.
KabschResult RobustKabsch(const std::vector<Eigen::Vector3d>& a,
                          const std::vector<Eigen::Vector3d>& b, double floor,
                          std::vector<int>* outliers = nullptr);

}  // namespace rtscalib

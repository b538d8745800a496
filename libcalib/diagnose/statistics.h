// Distribution functions and the one regression test every diagnostic uses.
//
//   ChiSquareSurvival(x, k) = P(X > x), X ~ chi2(k): the regularised upper
//                             incomplete gamma function Q(k/2, x/2).
//   ChiSquareCritical(a, k) = x with P(X > x) = a.
//   NormalCritical(a)       = z with P(Z > z) = a, Z ~ N(0, 1).
//
// `TestColumns` answers "do the columns T explain part of y?" for a linear
// model y = T b + e whose other regressors (the fitted model's parameters and
// any nuisance columns) have already been projected out of both y and T
// (Frisch-Waugh-Lovell: b, e and every covariance below are then those of the
// full regression). It returns
//   b           = (T'T)^+ T'y
//   delta_rss   = y'y - e'e = b' T'y
//   cov_classic = s^2 (T'T)^+,  s^2 = e'e / (n - dof_used - rank(T))
//   cov_robust  = (T'T)^+ [G/(G-1) sum_c (T_c'e_c)(T_c'e_c)'] (T'T)^+
//                 (cluster sandwich, "CR1"; c runs over clusters of rows that
//                  share a pointing or a shot, so heteroscedastic or
//                  pointing-correlated noise does not fake significance)
//   wald        = min over both covariances of b' cov^+ b   (conservative)
//   p_value     = ChiSquareSurvival(wald, rank(T)).
// Rank deficiency inside T (columns that the data cannot separate) reduces
// the test's degrees of freedom instead of failing.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace rtscalib {

double ChiSquareSurvival(double x, double dof);
double ChiSquareCritical(double alpha, double dof);
double NormalCritical(double alpha);

struct ColumnTest {
  Eigen::VectorXd beta;
  Eigen::MatrixXd cov;  // the covariance behind `wald` (classical or robust)
  Eigen::MatrixXd cov_classic, cov_robust;
  Eigen::VectorXd fitted;  // T b
  double rss_before = 0;   // y'y
  double rss_after = 0;    // e'e
  double delta_rss = 0;
  double wald = 0;
  double p_value = 1;
  int rank = 0;
};

// `cluster[i]` in [0, num_clusters) for every row; `dof_used` = parameters
// already fitted (the model's free parameters plus nuisance columns).
ColumnTest TestColumns(const Eigen::Ref<const Eigen::VectorXd>& y,
                       const Eigen::Ref<const Eigen::MatrixXd>& t, const std::vector<int>& cluster,
                       int num_clusters, int dof_used);

// Pseudo-inverse of a symmetric positive semi-definite matrix after scaling it
// to unit diagonal; eigenvalues below `rel_tol` (of the largest) count as zero.
// `rank` (optional) receives the number of eigenvalues kept.
Eigen::MatrixXd PseudoInverseSpd(const Eigen::MatrixXd& a, double rel_tol, int* rank = nullptr);

// Orthonormal basis of the span of columns added so far; projects vectors onto
// its orthogonal complement. Columns that are (numerically) in the span
// already are dropped: a column is kept when the part of it outside the span
// exceeds `rel_tol` of its own norm.
class Projector {
 public:
  explicit Projector(int rows) : q_(rows, 0) {}
  // Returns how many of `cols` added a new direction; they are the last
  // columns of basis().
  int Add(const Eigen::Ref<const Eigen::MatrixXd>& cols, double rel_tol = 1e-7);
  Eigen::MatrixXd Apply(const Eigen::Ref<const Eigen::MatrixXd>& x) const;
  // x := (I - Q Q') x in place, Q = basis() from column `from` on. The basis
  // is orthonormal, so projecting an x that the first `from` columns have
  // already projected by the rest is projecting it by all of them: a
  // projection kept up to date while the basis grows costs only the new
  // directions, and n x cols temporaries are not allocated.
  void Project(Eigen::Ref<Eigen::MatrixXd> x, int from = 0) const;
  int rank() const { return static_cast<int>(q_.cols()); }
  const Eigen::MatrixXd& basis() const { return q_; }

 private:
  Eigen::MatrixXd q_;
};

}  // namespace rtscalib

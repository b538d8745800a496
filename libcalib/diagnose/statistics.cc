#include "libcalib/diagnose/statistics.h"

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

namespace rtscalib {
namespace {

// Regularised incomplete gamma functions by series (x < a + 1) and by Lentz's
// continued fraction (otherwise); both converge to double precision in well
// under 500 terms for the arguments the tests use.
double GammaPSeries(double a, double x) {
  double sum = 1.0 / a, term = sum, ap = a;
  for (int n = 0; n < 1000; ++n) {
    ap += 1.0;
    term *= x / ap;
    sum += term;
    if (std::abs(term) < std::abs(sum) * 1e-16) break;
  }
  return sum * std::exp(-x + a * std::log(x) - std::lgamma(a));
}

double GammaQFraction(double a, double x) {
  const double tiny = 1e-300;
  double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
  for (int i = 1; i < 1000; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < 1e-16) break;
  }
  return std::exp(-x + a * std::log(x) - std::lgamma(a)) * h;
}

}  // namespace

double ChiSquareSurvival(double x, double dof) {
  if (!(x > 0)) return 1.0;
  if (dof <= 0) return 0.0;
  const double a = 0.5 * dof, h = 0.5 * x;
  if (h < a + 1.0) return std::clamp(1.0 - GammaPSeries(a, h), 0.0, 1.0);
  return std::clamp(GammaQFraction(a, h), 0.0, 1.0);
}

double ChiSquareCritical(double alpha, double dof) {
  double lo = 0.0, hi = std::max(1.0, dof);
  for (int i = 0; i < 200 && ChiSquareSurvival(hi, dof) > alpha; ++i) hi *= 2.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (ChiSquareSurvival(mid, dof) > alpha ? lo : hi) = mid;
    if (hi - lo < 1e-10 * hi) break;
  }
  return 0.5 * (lo + hi);
}

double NormalCritical(double alpha) { return std::sqrt(ChiSquareCritical(2.0 * alpha, 1.0)); }

Eigen::MatrixXd PseudoInverseSpd(const Eigen::MatrixXd& a, double rel_tol, int* rank) {
  const int k = static_cast<int>(a.rows());
  Eigen::VectorXd d(k);
  for (int i = 0; i < k; ++i) d[i] = a(i, i) > 0 ? 1.0 / std::sqrt(a(i, i)) : 0.0;
  const Eigen::MatrixXd s = d.asDiagonal() * a * d.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(s);
  const Eigen::VectorXd& l = eig.eigenvalues();
  const double lmax = k > 0 ? std::max(l.maxCoeff(), 0.0) : 0.0;
  Eigen::VectorXd inv = Eigen::VectorXd::Zero(k);
  int r = 0;
  for (int i = 0; i < k; ++i) {
    if (lmax > 0 && l[i] > rel_tol * lmax) {
      inv[i] = 1.0 / l[i];
      ++r;
    }
  }
  if (rank) *rank = r;
  const Eigen::MatrixXd& v = eig.eigenvectors();
  return d.asDiagonal() * (v * inv.asDiagonal() * v.transpose()) * d.asDiagonal();
}

ColumnTest TestColumns(const Eigen::Ref<const Eigen::VectorXd>& y,
                       const Eigen::Ref<const Eigen::MatrixXd>& t, const std::vector<int>& cluster,
                       int num_clusters, int dof_used) {
  ColumnTest out;
  const int n = static_cast<int>(y.size());
  const int k = static_cast<int>(t.cols());
  out.rss_before = y.squaredNorm();
  out.rss_after = out.rss_before;
  out.beta = Eigen::VectorXd::Zero(k);
  out.cov = out.cov_classic = out.cov_robust = Eigen::MatrixXd::Zero(k, k);
  out.fitted = Eigen::VectorXd::Zero(n);
  if (k == 0 || n == 0) return out;

  const Eigen::MatrixXd a = t.transpose() * t;
  const Eigen::MatrixXd a_inv = PseudoInverseSpd(a, 1e-12, &out.rank);
  if (out.rank == 0) return out;
  const Eigen::VectorXd g = t.transpose() * y;
  out.beta = a_inv * g;
  out.fitted = t * out.beta;
  const Eigen::VectorXd e = y - out.fitted;
  out.delta_rss = std::max(out.beta.dot(g), 0.0);
  out.rss_after = std::max(out.rss_before - out.delta_rss, 0.0);

  const double s2 = e.squaredNorm() / std::max(n - dof_used - out.rank, 1);
  out.cov_classic = s2 * a_inv;

  Eigen::MatrixXd scores = Eigen::MatrixXd::Zero(num_clusters, k);
  for (int i = 0; i < n; ++i) scores.row(cluster[i]) += e[i] * t.row(i);
  int used = 0;
  for (int c = 0; c < num_clusters; ++c) used += scores.row(c).squaredNorm() > 0 ? 1 : 0;
  const double cr1 = used > 1 ? double(used) / (used - 1) : 1.0;
  const Eigen::MatrixXd meat = cr1 * scores.transpose() * scores;
  out.cov_robust = a_inv * meat * a_inv;

  auto wald = [&](const Eigen::MatrixXd& cov) {
    int r = 0;
    const Eigen::MatrixXd inv = PseudoInverseSpd(cov, 1e-12, &r);
    return r == 0 ? 0.0 : out.beta.dot(inv * out.beta);
  };
  const double w_classic = wald(out.cov_classic);
  const double w_robust = wald(out.cov_robust);
  if (w_robust < w_classic) {
    out.wald = w_robust;
    out.cov = out.cov_robust;
  } else {
    out.wald = w_classic;
    out.cov = out.cov_classic;
  }
  out.p_value = ChiSquareSurvival(out.wald, out.rank);
  return out;
}

namespace {

// Q1 Z for the thin Q1 of a tall n x m matrix x = Q1 R1 (n >= m) and an m x
// k matrix Z, with R1, by a tall-skinny QR (Demmel et al. 2012, TSQR): x is
// cut into row blocks small enough to stay in cache, each block factored
// (x_i = Q_i R_i), the stacked R_i factored once more ([R_1; ...; R_p] =
// Q_s R1), so that Q1 = diag(Q_i) Q_s. One Householder QR of all n rows
// sweeps the whole matrix from memory once per column (level-2 work on
// 57,826 x 58 Jacobians in the diagnosis); the blocks are swept in cache.
// Same R1 up to the signs of its rows, same span, same stability.
class TallQr {
 public:
  explicit TallQr(const Eigen::MatrixXd& x) {
    const Eigen::Index n = x.rows(), m = x.cols();
    // About 256 KiB of doubles per block, and at least 2 m rows.
    const Eigen::Index rows = std::max<Eigen::Index>(2 * m, 32768 / std::max<Eigen::Index>(m, 1));
    for (Eigen::Index start = 0; start < n;) {
      Eigen::Index size = std::min(rows, n - start);
      if (n - start - size < m) size = n - start;  // no last block shorter than m
      starts_.push_back(start);
      blocks_.emplace_back(x.middleRows(start, size));
      start += size;
    }
    Eigen::MatrixXd stacked(static_cast<Eigen::Index>(blocks_.size()) * m, m);
    for (size_t i = 0; i < blocks_.size(); ++i) {
      stacked.middleRows(static_cast<Eigen::Index>(i) * m, m) =
          blocks_[i].matrixQR().topRows(m).triangularView<Eigen::Upper>();
    }
    stacked_ = Eigen::HouseholderQR<Eigen::MatrixXd>(stacked);
    r_ = stacked_.matrixQR().topRows(m).triangularView<Eigen::Upper>();
  }

  const Eigen::MatrixXd& R() const { return r_; }

  Eigen::MatrixXd QTimes(const Eigen::MatrixXd& z) const {
    const Eigen::Index m = r_.cols(), k = z.cols();
    Eigen::MatrixXd w = Eigen::MatrixXd::Zero(stacked_.rows(), k);
    w.topRows(m) = z;
    w.applyOnTheLeft(stacked_.householderQ());
    Eigen::Index n = 0;
    for (const auto& b : blocks_) n += b.rows();
    Eigen::MatrixXd out(n, k);
    for (size_t i = 0; i < blocks_.size(); ++i) {
      Eigen::MatrixXd part = Eigen::MatrixXd::Zero(blocks_[i].rows(), k);
      part.topRows(m) = w.middleRows(static_cast<Eigen::Index>(i) * m, m);
      part.applyOnTheLeft(blocks_[i].householderQ());
      out.middleRows(starts_[i], part.rows()) = part;
    }
    return out;
  }

 private:
  std::vector<Eigen::Index> starts_;
  std::vector<Eigen::HouseholderQR<Eigen::MatrixXd>> blocks_;
  Eigen::HouseholderQR<Eigen::MatrixXd> stacked_;
  Eigen::MatrixXd r_;
};

}  // namespace

int Projector::Add(const Eigen::Ref<const Eigen::MatrixXd>& cols, double rel_tol) {
  const int n = static_cast<int>(q_.rows());
  const int m = static_cast<int>(cols.cols());
  if (m == 0) return 0;
  // Projected twice: classical Gram-Schmidt is stable when repeated once.
  Eigen::MatrixXd x = cols;
  Project(x);
  Project(x);
  for (int j = 0; j < m; ++j) {
    const double norm = cols.col(j).norm();
    x.col(j) *= norm > 0 ? 1.0 / norm : 0.0;
  }
  // A column-pivoted QR of x, in two steps: a Householder QR of the n rows
  // (x = Q1 R1; matrix-matrix work, where the pivoted QR of x itself
  // updates all n rows once per column), then the pivoted QR of the small
  // R1 (R1 P = Q2 R2). x P = Q1 Q2 R2: R2 and the pivots are those of the
  // pivoted QR of x (the column norms and inner products it pivots on are
  // R1's), up to rounding.
  const int k = std::min(n, m);
  Eigen::MatrixXd r1;
  std::optional<TallQr> tall;
  std::optional<Eigen::HouseholderQR<Eigen::MatrixXd>> outer;
  if (n >= 4 * m) {
    tall.emplace(x);
    r1 = tall->R();
  } else {
    outer.emplace(x);
    r1 = outer->matrixQR().topRows(k).triangularView<Eigen::Upper>().toDenseMatrix();
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(r1);
  const auto& r = qr.matrixR();
  int rank = 0;
  for (int i = 0; i < k; ++i) {
    if (std::abs(r(i, i)) > rel_tol) ++rank;
  }
  if (rank == 0) return 0;
  const Eigen::MatrixXd q2 = qr.householderQ() * Eigen::MatrixXd::Identity(k, rank);
  Eigen::MatrixXd fresh;
  if (tall) {
    fresh = tall->QTimes(q2);
  } else {
    Eigen::MatrixXd inner = Eigen::MatrixXd::Zero(n, rank);
    inner.topRows(k) = q2;
    fresh = outer->householderQ() * inner;
  }
  const int old = static_cast<int>(q_.cols());
  if (old == 0) {
    q_ = std::move(fresh);
    return rank;
  }
  q_.conservativeResize(n, old + rank);
  q_.rightCols(rank) = fresh;
  return rank;
}

Eigen::MatrixXd Projector::Apply(const Eigen::Ref<const Eigen::MatrixXd>& x) const {
  Eigen::MatrixXd out = x;
  Project(out);
  return out;
}

void Projector::Project(Eigen::Ref<Eigen::MatrixXd> x, int from) const {
  const Eigen::Index k = q_.cols() - from;
  if (k <= 0 || x.cols() == 0) return;
  const auto q = q_.rightCols(k);
  const Eigen::MatrixXd c = q.transpose() * x;
  x.noalias() -= q * c;
}

}  // namespace rtscalib

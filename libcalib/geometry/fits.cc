#include "libcalib/geometry/fits.h"

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace rtscalib {
namespace {

using Matrix3X = Eigen::Matrix<double, 3, Eigen::Dynamic>;

void RequirePoints(const std::vector<Eigen::Vector3d>& points, size_t n, const char* what) {
  if (points.size() < n) {
    throw std::invalid_argument(std::string(what) + " needs at least " + std::to_string(n) +
                                " points, got " + std::to_string(points.size()));
  }
}

// Eq. 14, 17, 18: centroid, centred and normalised measurement matrix.
Matrix3X NormalisedCentred(const std::vector<Eigen::Vector3d>& points, Eigen::Vector3d* centroid,
                           double* scale) {
  const int n = static_cast<int>(points.size());
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += p;
  mean /= n;
  Matrix3X a(3, n);
  for (int i = 0; i < n; ++i) a.col(i) = points[i] - mean;
  double k = a.cwiseAbs().maxCoeff();
  // All points equal: nothing to normalise; keep k = 1 so that the result is
  // finite (and degenerate, which the callers detect from the spread).
  if (!(k > 0.0)) k = 1.0;
  a /= k;
  *centroid = mean;
  *scale = k;
  return a;
}

// The triangular factor R (3 x 3, zero below the rows there are) of the
// Householder QR of an n x 3 matrix: its singular values and right singular
// vectors are the matrix's own. This is the QR preconditioning Eigen's
// JacobiSVD applies to a non-square matrix before its 3 x 3 Jacobi sweeps;
// written out, only fixed-size SVDs are instantiated (an SVD of a dynamic
// matrix instantiates Eigen's QR preconditioners for both shapes, a large
// part of the library's compile time).
Eigen::Matrix3d TriangularFactor(const Eigen::Ref<const Eigen::MatrixX3d>& m) {
  const Eigen::HouseholderQR<Eigen::MatrixX3d> qr(m);
  Eigen::Matrix3d r = Eigen::Matrix3d::Zero();
  const Eigen::Index rows = std::min<Eigen::Index>(3, m.rows());
  r.topRows(rows) = qr.matrixQR().topRows(rows).triangularView<Eigen::Upper>();
  return r;
}

PlaneFit PlaneFromNormalised(const Matrix3X& a, const Eigen::Vector3d& centroid, double k) {
  // Eq. 15: a = U S V'. With a' = Q R, a = R' Q': U and S are R''s.
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(TriangularFactor(a.transpose()).transpose(),
                                              Eigen::ComputeFullU);
  Eigen::Matrix3d u = svd.matrixU();
  PlaneFit fit;
  fit.centroid = centroid;
  fit.scale = k;
  fit.singular_values = svd.singularValues();
  // Eq. 19: flip u_3 if U is a reflection.
  if (u.determinant() < 0) u.col(2) *= -1.0;
  fit.basis = u;
  // Point-to-plane distances are the third coordinates in B, times k.
  const Eigen::RowVectorXd h = u.col(2).transpose() * a;
  fit.rms = k * std::sqrt(h.squaredNorm() / static_cast<double>(a.cols()));
  return fit;
}

}  // namespace

PlaneFit FitPlane(const std::vector<Eigen::Vector3d>& points) {
  RequirePoints(points, 3, "FitPlane");
  Eigen::Vector3d centroid;
  double k;
  const Matrix3X a = NormalisedCentred(points, &centroid, &k);
  return PlaneFromNormalised(a, centroid, k);
}

CircleFit FitCircle(const std::vector<Eigen::Vector3d>& points) {
  RequirePoints(points, 3, "FitCircle");
  Eigen::Vector3d centroid;
  double k;
  const Matrix3X a = NormalisedCentred(points, &centroid, &k);
  CircleFit fit;
  fit.plane = PlaneFromNormalised(a, centroid, k);
  fit.normal = fit.plane.Normal();
  const int n = static_cast<int>(points.size());

  // Eq. 21: 2D coordinates in the plane (normalised units).
  const Eigen::Matrix<double, 2, Eigen::Dynamic> ac = fit.plane.basis.leftCols<2>().transpose() * a;
  // Eq. 25/26: [2u 2v 1] [c1 c2 k3]^T = u^2 + v^2.
  Eigen::MatrixX3d m(n, 3);
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) {
    m(i, 0) = 2.0 * ac(0, i);
    m(i, 1) = 2.0 * ac(1, i);
    m(i, 2) = 1.0;
    b[i] = ac.col(i).squaredNorm();
  }
  // Eq. 27-29: pseudo-inverse with all three singular values. A relative
  // smallest singular value below 1e-12 means collinear (or coincident)
  // points: the system has no unique circle and Eq. 29 would divide by ~0.
  // Eq. 27 through the QR of m (n >= 3 rows): m = Q R and R = U_R S V' give
  // m = (Q U_R) S V', and the pseudo-inverse's U' b is U_R' (Q' b), the
  // first three entries of Q' b.
  const Eigen::HouseholderQR<Eigen::MatrixX3d> qr(m);
  const Eigen::Matrix3d r = qr.matrixQR().topRows<3>().triangularView<Eigen::Upper>();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Vector3d s = svd.singularValues();
  constexpr double kRankTolerance = 1e-12;
  if (!(s[2] > kRankTolerance * s[0])) {
    const double inf = std::numeric_limits<double>::infinity();
    fit.center = Eigen::Vector3d::Constant(inf);
    fit.radius = inf;
    fit.rms = inf;
    fit.valid = false;
    return fit;
  }
  const Eigen::VectorXd qtb = qr.householderQ().transpose() * b;
  const Eigen::Vector3d x =
      svd.matrixV() * s.cwiseInverse().asDiagonal() * svd.matrixU().transpose() * qtb.head<3>();
  const double c1 = x[0], c2 = x[1], k3 = x[2];
  // Eq. 30, scaled back by k.
  fit.center = centroid + k * (fit.plane.basis * Eigen::Vector3d(c1, c2, 0.0));
  fit.radius = k * std::sqrt(std::max(0.0, k3 + c1 * c1 + c2 * c2));
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d local = fit.plane.basis.transpose() * (points[i] - fit.center);
    const double rho = std::hypot(local[0], local[1]);
    sum += local[2] * local[2] + (rho - fit.radius) * (rho - fit.radius);
  }
  fit.rms = std::sqrt(sum / n);
  fit.valid = true;
  return fit;
}

LineFit FitLine(const std::vector<Eigen::Vector3d>& points) {
  RequirePoints(points, 2, "FitLine");
  Eigen::Vector3d centroid;
  double k;
  const Matrix3X a = NormalisedCentred(points, &centroid, &k);
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(TriangularFactor(a.transpose()).transpose(),
                                              Eigen::ComputeFullU);
  LineFit fit;
  fit.point = centroid;
  fit.direction = svd.matrixU().col(0);
  double sum = 0.0, lo = 0.0, hi = 0.0;
  for (int i = 0; i < a.cols(); ++i) {
    const double along = fit.direction.dot(a.col(i));
    sum += (a.col(i) - along * fit.direction).squaredNorm();
    lo = std::min(lo, along);
    hi = std::max(hi, along);
  }
  fit.rms = k * std::sqrt(sum / static_cast<double>(a.cols()));
  fit.extent = k * (hi - lo);
  return fit;
}

Eigen::Vector3d CorrectNormalSign(const Eigen::Vector3d& normal, const Eigen::Vector3d& center,
                                  const Eigen::Vector3d& x_first, const Eigen::Vector3d& x_second) {
  const double s = (x_first - center).cross(x_second - center).dot(normal);
  return s < 0.0 ? Eigen::Vector3d(-normal) : normal;  // Eq. 32: sign(0) = +1
}

Eigen::Vector3d CorrectDirectionSign(const Eigen::Vector3d& direction,
                                     const Eigen::Vector3d& x_first,
                                     const Eigen::Vector3d& x_second) {
  return (x_second - x_first).dot(direction) < 0.0 ? Eigen::Vector3d(-direction) : direction;
}

}  // namespace rtscalib

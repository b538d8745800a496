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

PlaneFit PlaneFromNormalised(const Matrix3X& a, const Eigen::Vector3d& centroid, double k) {
  Eigen::JacobiSVD<Matrix3X> svd(a, Eigen::ComputeFullU);
  Eigen::Matrix3d u = svd.matrixU();
  PlaneFit fit;
  fit.centroid = centroid;
  fit.scale = k;
  fit.singular_values = Eigen::Vector3d::Zero();
  const auto& s = svd.singularValues();
  for (int i = 0; i < s.size() && i < 3; ++i) fit.singular_values[i] = s[i];
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
  Eigen::MatrixXd m(n, 3);
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
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(m, Eigen::ComputeThinU | Eigen::ComputeThinV);
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
  const Eigen::Vector3d x =
      svd.matrixV() * s.cwiseInverse().asDiagonal() * svd.matrixU().transpose() * b;
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
  Eigen::JacobiSVD<Matrix3X> svd(a, Eigen::ComputeFullU);
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

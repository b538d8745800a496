#include "libcalib/geometry/kabsch.h"

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rtscalib {

KabschResult Kabsch(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
  if (a.size() != b.size()) {
    throw std::invalid_argument("Kabsch: point sets differ in size (" + std::to_string(a.size()) +
                                " vs " + std::to_string(b.size()) + ")");
  }
  if (a.size() < 3) {
    throw std::invalid_argument("Kabsch needs at least 3 correspondences, got " +
                                std::to_string(a.size()));
  }
  const double n = static_cast<double>(a.size());
  Eigen::Vector3d a_bar = Eigen::Vector3d::Zero(), b_bar = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < a.size(); ++i) {
    a_bar += a[i];
    b_bar += b[i];
  }
  a_bar /= n;  // Eq. 52
  b_bar /= n;
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < a.size(); ++i) h += (a[i] - a_bar) * (b[i] - b_bar).transpose();  // Eq. 53

  Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);  // Eq. 55
  const Eigen::Matrix3d& u = svd.matrixU();
  const Eigen::Matrix3d& v = svd.matrixV();
  Eigen::Vector3d diag(1.0, 1.0, (v * u.transpose()).determinant() < 0.0 ? -1.0 : 1.0);
  KabschResult out;
  out.b_from_a.rotation = v * diag.asDiagonal() * u.transpose();     // Eq. 56
  out.b_from_a.translation = b_bar - out.b_from_a.rotation * a_bar;  // Eq. 57

  const Eigen::Vector3d s = svd.singularValues();
  out.rank = 0;
  for (int i = 0; i < 3; ++i) {
    if (s[i] > 1e-12 * s[0]) ++out.rank;
  }
  double sum = 0.0;
  for (size_t i = 0; i < a.size(); ++i) sum += (out.b_from_a * a[i] - b[i]).squaredNorm();
  out.rms = std::sqrt(sum / n);
  return out;
}

}  // namespace rtscalib

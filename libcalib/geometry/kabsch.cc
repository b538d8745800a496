#include "libcalib/geometry/kabsch.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>
#include <set>
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

namespace {

std::vector<double> Residuals(const Rigid3& t, const std::vector<Eigen::Vector3d>& a,
                              const std::vector<Eigen::Vector3d>& b) {
  std::vector<double> e(a.size());
  for (size_t i = 0; i < a.size(); ++i) e[i] = (t * a[i] - b[i]).norm();
  return e;
}

double MedianOf(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

}  // namespace

KabschResult RobustKabsch(const std::vector<Eigen::Vector3d>& a,
                          const std::vector<Eigen::Vector3d>& b, double floor,
                          std::vector<int>* outliers) {
  if (outliers) outliers->clear();
  if (a.size() != b.size() || a.size() < 6) return Kabsch(a, b);
  // 0.5^3: a sample is clean with probability >= 1/8 while fewer than half
  // the pairs are off; 300 samples miss every clean one with p < 1e-17.
  constexpr int kSamples = 300;
  constexpr double kChi3Median = 1.5382, kReject = 8.0;
  std::mt19937_64 rng(0x6b616273 + a.size());
  std::uniform_int_distribution<int> pick(0, static_cast<int>(a.size()) - 1);
  double best = std::numeric_limits<double>::infinity();
  Rigid3 best_fit;
  for (int s = 0; s < kSamples; ++s) {
    std::set<int> sample;
    while (sample.size() < 3) sample.insert(pick(rng));
    std::vector<Eigen::Vector3d> sa, sb;
    for (int i : sample) {
      sa.push_back(a[i]);
      sb.push_back(b[i]);
    }
    const KabschResult k = Kabsch(sa, sb);
    if (k.rank < 2) continue;
    const double median = MedianOf(Residuals(k.b_from_a, a, b));
    if (median < best) {
      best = median;
      best_fit = k.b_from_a;
    }
  }
  if (!std::isfinite(best)) return Kabsch(a, b);
  const double limit = std::max(kReject * best / kChi3Median, floor);
  const std::vector<double> e = Residuals(best_fit, a, b);
  std::vector<Eigen::Vector3d> ia, ib;
  std::vector<int> out;
  for (size_t i = 0; i < a.size(); ++i) {
    if (e[i] <= limit) {
      ia.push_back(a[i]);
      ib.push_back(b[i]);
    } else {
      out.push_back(static_cast<int>(i));
    }
  }
  if (ia.size() < 3) return Kabsch(a, b);
  if (outliers) *outliers = out;
  return Kabsch(ia, ib);
}

}  // namespace rtscalib

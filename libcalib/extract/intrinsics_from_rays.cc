#include "libcalib/extract/intrinsics_from_rays.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

namespace rtscalib {
namespace {

struct PoseData {
  std::vector<const Record*> edm, cam;
};

double Median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// Normalised DLT for pixels ~ H * directions, then K from H = K R^T.
std::optional<Eigen::Matrix3d> IntrinsicsFromDirections(const std::vector<Eigen::Vector3d>& dirs,
                                                        const std::vector<Eigen::Vector2d>& pix) {
  const int n = static_cast<int>(dirs.size());
  if (n < 4) return std::nullopt;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : pix) mean += p;
  mean /= n;
  double spread = 0;
  for (const auto& p : pix) spread += (p - mean).norm();
  spread /= n;
  if (spread < 1e-9) return std::nullopt;
  const double s = std::sqrt(2.0) / spread;
  Eigen::Matrix3d t;
  t << s, 0, -s * mean.x(), 0, s, -s * mean.y(), 0, 0, 1;
  Eigen::MatrixXd a(2 * n, 9);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p = t * Eigen::Vector3d(pix[i].x(), pix[i].y(), 1.0);
    const Eigen::RowVector3d d = dirs[i].transpose();
    a.row(2 * i) << Eigen::RowVector3d::Zero(), -p.z() * d, p.y() * d;
    a.row(2 * i + 1) << p.z() * d, Eigen::RowVector3d::Zero(), -p.x() * d;
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeFullV);
  if (svd.singularValues()(7) < 1e-12 * svd.singularValues()(0)) return std::nullopt;
  const Eigen::VectorXd h = svd.matrixV().col(8);
  Eigen::Matrix3d hm;
  hm << h(0), h(1), h(2), h(3), h(4), h(5), h(6), h(7), h(8);
  hm = t.inverse() * hm;
  // H = K R^T  <=>  H^-1 = R K^-1 = Q * U (QR), K = U^-1.
  if (hm.determinant() < 0) hm = -hm;
  Eigen::HouseholderQR<Eigen::Matrix3d> qr(hm.inverse());
  Eigen::Matrix3d q = qr.householderQ();
  Eigen::Matrix3d u = qr.matrixQR().triangularView<Eigen::Upper>();
  for (int i = 0; i < 3; ++i) {
    if (u(i, i) < 0) {
      u.row(i) *= -1.0;
      q.col(i) *= -1.0;
    }
  }
  Eigen::Matrix3d k = u.inverse();
  k /= k(2, 2);
  if (!(k(0, 0) > 0) || !(k(1, 1) > 0)) return std::nullopt;
  return k;
}

}  // namespace

std::optional<RayIntrinsicsEstimate> EstimateIntrinsicsFromRays(const std::vector<Record>& records,
                                                                int zoom) {
  std::map<std::tuple<int, double, double>, PoseData> poses;
  double umax = 0, vmax = 0;
  for (const Record& r : records) {
    PoseData& p = poses[{r.face, r.phi, r.theta}];
    if (r.tool == Tool::kEdm) p.edm.push_back(&r);
    if (r.tool == Tool::kCam && r.zoom == zoom) {
      p.cam.push_back(&r);
      umax = std::max(umax, r.u);
      vmax = std::max(vmax, r.v);
    }
  }
  std::vector<double> fx, fy, cx, cy;
  for (const auto& [key, p] : poses) {
    // Directions per pixel: from two ray lengths if present.
    std::map<std::pair<double, double>, std::vector<const Record*>> by_pixel;
    for (const Record* r : p.cam) by_pixel[{r->u, r->v}].push_back(r);
    std::optional<Eigen::Vector3d> centre;
    if (p.edm.size() >= 2) {
      const Record* a = *std::min_element(p.edm.begin(), p.edm.end(),
                                          [](auto* x, auto* y) { return x->d < y->d; });
      const Record* b = *std::max_element(p.edm.begin(), p.edm.end(),
                                          [](auto* x, auto* y) { return x->d < y->d; });
      if (b->d > a->d) centre = a->x - a->d * (b->x - a->x) / (b->d - a->d);
    }
    std::vector<Eigen::Vector3d> dirs;
    std::vector<Eigen::Vector2d> pix;
    for (const auto& [uv, rows] : by_pixel) {
      const Record* a =
          *std::min_element(rows.begin(), rows.end(), [](auto* x, auto* y) { return x->d < y->d; });
      const Record* b =
          *std::max_element(rows.begin(), rows.end(), [](auto* x, auto* y) { return x->d < y->d; });
      Eigen::Vector3d dir;
      if (b->d > a->d) {
        dir = (b->x - a->x) / (b->d - a->d);
      } else if (centre) {
        dir = a->x - *centre;
      } else {
        continue;
      }
      if (dir.norm() < 1e-12) continue;
      dirs.push_back(dir.normalized());
      pix.emplace_back(uv.first, uv.second);
    }
    const std::optional<Eigen::Matrix3d> k = IntrinsicsFromDirections(dirs, pix);
    if (!k) continue;
    fx.push_back((*k)(0, 0));
    fy.push_back((*k)(1, 1));
    cx.push_back((*k)(0, 2));
    cy.push_back((*k)(1, 2));
  }
  if (fx.empty()) return std::nullopt;
  RayIntrinsicsEstimate out;
  out.poses = static_cast<int>(fx.size());
  out.camera.intrinsics = {Median(fx), Median(fy), Median(cx), Median(cy)};
  out.camera.distortion.fill(0.0);
  out.camera.width =
      static_cast<int>(std::ceil(std::max(2.0 * out.camera.intrinsics[2], umax + 1.0)));
  out.camera.height =
      static_cast<int>(std::ceil(std::max(2.0 * out.camera.intrinsics[3], vmax + 1.0)));
  out.note = "zoom " + std::to_string(zoom) + ": intrinsics from view rays at " +
             std::to_string(out.poses) + " poses (DLT, median): fx " +
             std::to_string(out.camera.intrinsics[0]) + ", fy " +
             std::to_string(out.camera.intrinsics[1]) + ", cx " +
             std::to_string(out.camera.intrinsics[2]) + ", cy " +
             std::to_string(out.camera.intrinsics[3]) + " px; image size taken as " +
             std::to_string(out.camera.width) + " x " + std::to_string(out.camera.height);
  return out;
}

}  // namespace rtscalib

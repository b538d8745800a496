#include "libcalib/fit/two_face.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <vector>

#include "libcalib/model/kinematics.h"

namespace rtscalib {
namespace {

// Horizontal direction and zenith angle of a model's line of sight at a reading.
void RayAngles(const InstrumentModel& m, int zoom, double phi, double theta, double* hz,
               double* z) {
  const Eigen::Vector3d dir =
      (zoom < 0 ? RefFromEdm(m, phi, theta) : RefFromCam(m, zoom, phi, theta)).rotation.col(2);
  *hz = std::atan2(dir.x(), dir.y());
  *z = std::acos(std::clamp(dir.z(), -1.0, 1.0));
}

}  // namespace

TwoFaceDifferences TwoFaceCheck(const InstrumentModel& face1, const InstrumentModel& face2,
                                int zoom) {
  std::vector<Eigen::Vector2d> rows;
  std::vector<double> b, dz;
  for (int i = 0; i < 12; ++i) {
    for (int j = 0; j < 7; ++j) {
      const double phi = 2 * M_PI * i / 12;
      const double theta = (50.0 + 80.0 * j / 6) * M_PI / 180;
      double phi2, theta2, hz1, z1, hz2, z2;
      OtherFace(phi, theta, &phi2, &theta2);
      RayAngles(face1, zoom, phi, theta, &hz1, &z1);
      RayAngles(face2, zoom, phi2, theta2, &hz2, &z2);
      rows.emplace_back(2.0 / std::sin(z1), 2.0 * std::cos(z1) / std::sin(z1));
      b.push_back(WrapAngle(hz1 - hz2));
      dz.push_back(z1 - z2);
    }
  }
  const int n = static_cast<int>(rows.size());
  Eigen::MatrixXd a(n, 2);
  for (int k = 0; k < n; ++k) a.row(k) = rows[k].transpose();
  const Eigen::Map<const Eigen::VectorXd> rhs(b.data(), n);
  const Eigen::Vector2d ci = a.colPivHouseholderQr().solve(rhs);
  TwoFaceDifferences out;
  out.collimation = ci[0];
  out.tilting_axis = ci[1];
  double s = 0;
  for (double x : dz) s += x;
  out.vertical_index = s / n / 2.0;
  out.rms_hz = std::sqrt((a * ci - rhs).squaredNorm() / n);
  double s2 = 0;
  for (double x : dz) s2 += (x - 2.0 * out.vertical_index) * (x - 2.0 * out.vertical_index);
  out.rms_z = std::sqrt(s2 / n);
  out.num_pointings = n;
  return out;
}

}  // namespace rtscalib

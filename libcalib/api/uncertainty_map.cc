#include "libcalib/api/uncertainty_map.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "libcalib/geometry/convex_hull.h"

namespace rtscalib {
namespace {

// Sigma and extremes where no cell has a value.
constexpr double kNoValue = std::numeric_limits<double>::quiet_NaN();

// Median of the finite values (sorted copy), NaN when there are none.
double Median(std::vector<double> v) {
  if (v.empty()) return kNoValue;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// The pixel's derivatives by a small rotation w (rad, about the camera's
// centre: x -> c + (I + [w]x) (x - c)) of the point it sees, by central
// differences of 1e-6 rad (errors ~1e-12 relative, as the parameters' own).
Eigen::Matrix<double, 2, 3> RotationJacobian(const CalibratedInstrument& inst, int zoom,
                                             double phi, double theta, const Eigen::Vector3d& x,
                                             const Eigen::Vector3d& centre) {
  constexpr double kStep = 1e-6;
  Eigen::Matrix<double, 2, 3> j;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d w = Eigen::Vector3d::Unit(k) * kStep;
    const Eigen::Vector3d r = x - centre;
    const Eigen::Vector2d plus = inst.Pixel(zoom, phi, theta, centre + r + w.cross(r));
    const Eigen::Vector2d minus = inst.Pixel(zoom, phi, theta, centre + r - w.cross(r));
    j.col(k) = (plus - minus) / (2 * kStep);
  }
  return j;
}

}  // namespace

std::string UncertaintyMapOptions::Check() const {
  if (!(range_m > 0) || !std::isfinite(range_m)) return "range_m must be a finite range > 0";
  if (cols < 1 || rows < 1 || cols > 1000 || rows > 1000) return "cells must be 1..1000 each";
  if (!std::isfinite(phi) || !std::isfinite(theta)) return "phi and theta must be finite";
  return "";
}

std::string MapSubject(const UncertaintyMap& map, const UncertaintyMapOptions& o) {
  if (map.up_to_rotation) return "a direction (up to the camera's rotation)";
  char text[160];
  std::snprintf(text, sizeof(text), "a point at %g m, pointing phi %.4g, theta %.4g rad", o.range_m,
                o.phi, o.theta);
  return text;
}

std::vector<UncertaintyMap> ProjectionUncertaintyMaps(const CalibratedInstrument& inst,
                                                      const UncertaintyMapOptions& o) {
  const std::string msg = o.Check();
  if (!msg.empty()) throw std::invalid_argument("uncertainty map: " + msg);
  if (!inst.HasParameterCovariance()) {
    throw std::logic_error("uncertainty map: the model has no parameter covariance");
  }
  std::vector<UncertaintyMap> out;
  for (int z = 0; z < inst.NumZooms(); ++z) {
    const CameraTool& cam = inst.Model().cams[z];
    UncertaintyMap map;
    map.zoom = z;
    map.determined = cam.determined;
    map.cols = o.cols;
    map.rows = o.rows;
    map.width = cam.width;
    map.height = cam.height;
    map.sigma_px.assign(o.cols * o.rows, kNoValue);
    map.inside.assign(o.cols * o.rows, 0);
    map.up_to_rotation = inst.Model().kinematics == Kinematics::kNone;
    // Per predictable cell: its covariance, or (up to rotation) the
    // pixel's derivatives by the parameters and by a rotation.
    std::vector<int> cells;
    std::vector<Eigen::Matrix2d> covariance;
    std::vector<Eigen::Matrix<double, 2, Eigen::Dynamic>> by_parameters;
    std::vector<Eigen::Matrix<double, 2, 3>> by_rotation;
    for (int r = 0; r < o.rows; ++r) {
      for (int c = 0; c < o.cols; ++c) {
        const Eigen::Vector2d uv(map.CellU(c), map.CellV(r));
        const bool in = InsideConvexHull(cam.valid_region, uv);
        map.inside[r * o.cols + c] = in;
        if (!in) ++map.cells_outside;
        if (!cam.determined) continue;
        try {
          const Eigen::Vector3d x = inst.CameraPoint(z, o.phi, o.theta, uv[0], uv[1], o.range_m);
          if (map.up_to_rotation) {
            const Eigen::Vector3d centre = inst.CameraRay(z, o.phi, o.theta, uv[0], uv[1]).origin;
            by_parameters.push_back(inst.PixelJacobian(z, o.phi, o.theta, x));
            by_rotation.push_back(RotationJacobian(inst, z, o.phi, o.theta, x, centre));
          } else {
            covariance.push_back(inst.PixelWithUncertainty(z, o.phi, o.theta, x).covariance);
          }
          cells.push_back(r * o.cols + c);
        } catch (const PredictionError&) {
          // Not predictable there (outside the trusted region): NaN, drawn as such.
        }
      }
    }
    if (map.up_to_rotation && !cells.empty()) {
      // A camera on its own has no frame but its own: a change of its
      // parameters that a turn of the camera undoes (the principal point
      // against a small rotation, most of all) moves no pixel of anything
      // the camera will measure, since whatever it is used with (a pose
      // from solvePnP, a board, another camera) carries that turn. As
      // mrcal's projection uncertainty does, the rotation that best
      // undoes the parameters' change over the cells inside the points'
      // hull (all cells when none is) is taken out before the change is
      // measured: J* = J - J_w A, A = (sum J_w^T J_w)^-1 sum J_w^T J.
      // A camera has no distance to translate by here, so the rotation is
      // all of it.
      Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
      Eigen::Matrix<double, 3, Eigen::Dynamic> rhs =
          Eigen::Matrix<double, 3, Eigen::Dynamic>::Zero(3, inst.NumParameters());
      bool any_inside = false;
      for (int cell : cells) any_inside = any_inside || map.inside[cell];
      for (size_t k = 0; k < cells.size(); ++k) {
        if (any_inside && !map.inside[cells[k]]) continue;
        normal += by_rotation[k].transpose() * by_rotation[k];
        rhs += by_rotation[k].transpose() * by_parameters[k];
      }
      const Eigen::Matrix<double, 3, Eigen::Dynamic> a = normal.ldlt().solve(rhs);
      const Eigen::MatrixXd& p = inst.ParameterCovariance();
      for (size_t k = 0; k < cells.size(); ++k) {
        const Eigen::Matrix<double, 2, Eigen::Dynamic> j = by_parameters[k] - by_rotation[k] * a;
        covariance.push_back(j * p * j.transpose());
      }
    }
    std::vector<double> all, inside;
    for (size_t k = 0; k < cells.size(); ++k) {
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(covariance[k]);
      const double sigma = std::sqrt(std::max(eig.eigenvalues()[1], 0.0));
      map.sigma_px[cells[k]] = sigma;
      all.push_back(sigma);
      if (map.inside[cells[k]]) inside.push_back(sigma);
    }
    map.min_px = all.empty() ? kNoValue : *std::min_element(all.begin(), all.end());
    map.max_px = all.empty() ? kNoValue : *std::max_element(all.begin(), all.end());
    map.median_px = Median(all);
    map.inside_median_px = Median(inside);
    map.inside_max_px = inside.empty() ? kNoValue : *std::max_element(inside.begin(), inside.end());
    out.push_back(std::move(map));
  }
  return out;
}

}  // namespace rtscalib

#include "libcalib/api/uncertainty_map.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "libcalib/geometry/convex_hull.h"
#include "libcalib/model/kinematics.h"

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

}  // namespace

std::string UncertaintyMapOptions::Check() const {
  if (!(range_m > 0) || !std::isfinite(range_m)) return "range_m must be a finite range > 0";
  if (cols < 1 || rows < 1 || cols > 1000 || rows > 1000) return "cells must be 1..1000 each";
  if (!std::isfinite(phi) || !std::isfinite(theta)) return "phi and theta must be finite";
  return "";
}

Eigen::Matrix<double, 2, 3> PixelByRotation(const InstrumentModel& model, int zoom, double phi,
                                            double theta, const Eigen::Vector3d& x_ref) {
  constexpr double kStep = 1e-6;  // errors ~1e-12 relative, as the parameters' own steps
  const Eigen::Vector3d centre = RefFromCam(model, zoom, phi, theta).translation;
  const Eigen::Vector3d r = x_ref - centre;
  Eigen::Matrix<double, 2, 3> j;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d w = Eigen::Vector3d::Unit(k) * kStep;
    Eigen::Vector2d plus, minus;
    if (!PredictPixel(model, zoom, phi, theta, centre + r + w.cross(r), &plus) ||
        !PredictPixel(model, zoom, phi, theta, centre + r - w.cross(r), &minus)) {
      throw PredictionError(PredictionFailure::kNonFinite,
                            "a pixel that stays defined when its point turns by 1e-6 rad",
                            "a failure");
    }
    j.col(k) = (plus - minus) / (2 * kStep);
  }
  return j;
}

void TakeOutRotation(const std::vector<Eigen::Matrix<double, 2, 3>>& by_rotation,
                     const std::vector<char>& fit, Eigen::MatrixXd* by_parameters) {
  const bool any = std::find(fit.begin(), fit.end(), 1) != fit.end();
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(3, by_parameters->cols());
  for (size_t k = 0; k < by_rotation.size(); ++k) {
    if (any && !fit[k]) continue;
    normal += by_rotation[k].transpose() * by_rotation[k];
    rhs += by_rotation[k].transpose() * by_parameters->middleRows(2 * k, 2);
  }
  const Eigen::MatrixXd a = normal.ldlt().solve(rhs);
  for (size_t k = 0; k < by_rotation.size(); ++k) {
    by_parameters->middleRows(2 * k, 2) -= by_rotation[k] * a;
  }
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
            by_parameters.push_back(inst.PixelJacobian(z, o.phi, o.theta, x));
            by_rotation.push_back(PixelByRotation(inst.Model(), z, o.phi, o.theta, x));
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
      // A camera on its own (header): the rotation that best undoes the
      // parameters' change over the cells inside the points' hull is
      // taken out. A camera has no distance to translate by here, so the
      // rotation is all of it.
      Eigen::MatrixXd j(2 * cells.size(), inst.NumParameters());
      std::vector<char> fit(cells.size());
      for (size_t k = 0; k < cells.size(); ++k) {
        j.middleRows(2 * k, 2) = by_parameters[k];
        fit[k] = map.inside[cells[k]];
      }
      TakeOutRotation(by_rotation, fit, &j);
      const Eigen::MatrixXd& p = inst.ParameterCovariance();
      for (size_t k = 0; k < cells.size(); ++k) {
        covariance.push_back(j.middleRows(2 * k, 2) * p * j.middleRows(2 * k, 2).transpose());
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

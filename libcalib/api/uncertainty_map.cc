#include "libcalib/api/uncertainty_map.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
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

}  // namespace

std::string UncertaintyMapOptions::Check() const {
  if (!(range_m > 0) || !std::isfinite(range_m)) return "range_m must be a finite range > 0";
  if (cols < 1 || rows < 1 || cols > 1000 || rows > 1000) return "cells must be 1..1000 each";
  if (!std::isfinite(phi) || !std::isfinite(theta)) return "phi and theta must be finite";
  return "";
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
    std::vector<double> all, inside;
    for (int r = 0; r < o.rows; ++r) {
      for (int c = 0; c < o.cols; ++c) {
        const Eigen::Vector2d uv(map.CellU(c), map.CellV(r));
        const bool in = InsideConvexHull(cam.valid_region, uv);
        map.inside[r * o.cols + c] = in;
        if (!in) ++map.cells_outside;
        if (!cam.determined) continue;
        try {
          const Eigen::Vector3d x = inst.CameraPoint(z, o.phi, o.theta, uv[0], uv[1], o.range_m);
          const Eigen::Matrix2d s = inst.PixelWithUncertainty(z, o.phi, o.theta, x).covariance;
          const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(s);
          const double sigma = std::sqrt(std::max(eig.eigenvalues()[1], 0.0));
          map.sigma_px[r * o.cols + c] = sigma;
          all.push_back(sigma);
          if (in) inside.push_back(sigma);
        } catch (const PredictionError&) {
          // Not predictable there (outside the trusted region): NaN, drawn as such.
        }
      }
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

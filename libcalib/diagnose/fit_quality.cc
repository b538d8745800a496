#include "libcalib/diagnose/fit_quality.h"

#include <cmath>
#include <map>
#include <tuple>

#include "libcalib/diagnose/statistics.h"

namespace rtscalib {

bool FitQuality::Exceeds() const {
  for (const FitQualityCell& c : cells) {
    if (c.exceeds) return true;
  }
  return false;
}

FitQuality AssessFitQuality(const Linearization& lin, const Observations& obs,
                            const FitOptions& apriori, int num_parameters, double significance) {
  FitQuality out;
  // (group, zoom, face) -> cell; the map orders EDM, camera, image points.
  std::map<std::tuple<int, int, int>, FitQualityCell> cells;
  std::map<std::tuple<int, int, int>, double> sums;
  std::map<std::tuple<int, int, int>, int> last_index;
  for (int i = 0; i < lin.NumRows(); ++i) {
    const ResidualRow& row = lin.rows[i];
    const int g = static_cast<int>(row.group);
    int zoom = -1;
    if (row.group == ObsGroup::kPixel) zoom = obs.pixels[row.index].zoom;
    if (row.group == ObsGroup::kCam) zoom = obs.records[row.index].zoom;
    const auto key = std::make_tuple(g, zoom, row.face);
    FitQualityCell& c = cells[key];
    if (c.rows == 0) {
      c.group = row.group;
      c.zoom = zoom;
      c.face = row.face;
      const bool pixel = row.group == ObsGroup::kPixel;
      c.unit = pixel ? "px" : "m";
      c.apriori = row.group == ObsGroup::kEdm   ? apriori.sigma_edm_m
                  : row.group == ObsGroup::kCam ? apriori.sigma_cam_m
                                                : apriori.sigma_pixel_px;
      c.name = std::string(row.group == ObsGroup::kEdm   ? "EDM points"
                           : row.group == ObsGroup::kCam ? "camera points"
                                                         : "image points") +
               (zoom >= 0 ? " of zoom " + std::to_string(zoom) : "") + ", face " +
               std::to_string(row.face);
      last_index[key] = -1;
    }
    const double r = lin.r[i] * lin.sigma[g];
    sums[key] += r * r;
    ++c.rows;
    if (last_index[key] != row.index) {
      ++c.observations;
      last_index[key] = row.index;
    }
  }
  const int total = lin.NumRows();
  const double redundancy = total > 0 ? std::max(1.0 - double(num_parameters) / total, 0.0) : 0.0;
  out.level = significance / std::max<size_t>(cells.size(), 1);
  for (auto& [key, c] : cells) {
    const double ss = sums[key];
    c.rms = std::sqrt(ss / c.rows);
    c.dof = c.rows * redundancy;
    if (c.dof > 0 && c.apriori > 0) {
      c.chi2 = ss / (c.apriori * c.apriori);
      c.factor = std::sqrt(c.chi2 / c.dof);
      c.p_value = ChiSquareSurvival(c.chi2, c.dof);
      c.exceeds = c.p_value < out.level && c.factor > kMinFactor;
    }
    out.cells.push_back(c);
  }
  return out;
}

}  // namespace rtscalib

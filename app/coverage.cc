#include "app/coverage.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

namespace rtscalib::app {
namespace {

// Below this share of the corner radius the outer image is extrapolated.
constexpr double kMinRadiusFraction = 0.8;
const char* const kDistortionNames[kNumDistortion] = {"k1", "k2", "p1", "p2", "k3", "k4",   "k5",
                                                      "k6", "s1", "s2", "s3", "s4", "taux", "tauy"};

}  // namespace

CoverageReport ComputeCoverage(const Observations& obs, const InstrumentModel& model) {
  CoverageReport out;
  std::map<int, std::vector<Eigen::Vector2d>> by_zoom;
  for (const PixelObservation& p : obs.pixels) by_zoom[p.zoom].push_back(p.uv);
  for (const auto& [z, uvs] : by_zoom) {
    if (z >= model.NumZooms()) continue;
    const CameraTool& cam = model.cams[z];
    ZoomCoverage c;
    c.zoom = z;
    c.width = cam.width;
    c.height = cam.height;
    c.points = static_cast<int>(uvs.size());
    c.counts.assign(kCoverageCells * kCoverageCells, 0);
    const Eigen::Vector2d pp(cam.intrinsics[2], cam.intrinsics[3]);
    double corner_r = 0;
    for (double u : {-0.5, cam.width - 0.5}) {
      for (double v : {-0.5, cam.height - 0.5}) {
        corner_r = std::max(corner_r, (Eigen::Vector2d(u, v) - pp).norm());
      }
    }
    double rmax = 0;
    bool corner3[4] = {false, false, false, false};
    for (const Eigen::Vector2d& uv : uvs) {
      const int i = std::clamp(static_cast<int>((uv.x() + 0.5) / cam.width * kCoverageCells), 0,
                               kCoverageCells - 1);
      const int j = std::clamp(static_cast<int>((uv.y() + 0.5) / cam.height * kCoverageCells), 0,
                               kCoverageCells - 1);
      ++c.counts[j * kCoverageCells + i];
      rmax = std::max(rmax, (uv - pp).norm());
      const int i3 = std::clamp(static_cast<int>((uv.x() + 0.5) / cam.width * 3), 0, 2);
      const int j3 = std::clamp(static_cast<int>((uv.y() + 0.5) / cam.height * 3), 0, 2);
      if (i3 != 1 && j3 != 1) corner3[(j3 / 2) * 2 + i3 / 2] = true;
    }
    c.covered_fraction = static_cast<double>(std::count_if(c.counts.begin(), c.counts.end(),
                                                           [](int n) { return n > 0; })) /
                         c.counts.size();
    c.radius_fraction = corner_r > 0 ? rmax / corner_r : 0;
    c.corners_covered = corner3[0] && corner3[1] && corner3[2] && corner3[3];
    char line[400];
    if (c.radius_fraction < kMinRadiusFraction || !c.corners_covered) {
      std::snprintf(line, sizeof line,
                    "zoom %d: distortion extrapolated: points reach %.0f%% of the image corner's "
                    "radius%s (%.0f%% of the image covered); take photos with the boards in the "
                    "image corners",
                    z, 100 * c.radius_fraction,
                    c.corners_covered ? "" : ", some corner ninths of the image hold no points",
                    100 * c.covered_fraction);
      out.warnings.push_back(line);
    }
    if (model.sigmas.valid && z < static_cast<int>(model.sigmas.distortion.size())) {
      for (int k = 0; k < kNumDistortion; ++k) {
        const double x = cam.distortion[k], s = model.sigmas.distortion[z][k];
        if (s > 0 && s > std::abs(x)) {
          // What one sigma means in the image: the shift it gives at the
          // image corner (radial terms k r^(2n) on a radius r; tangential
          // ones at most 3 p r^2), so that a coefficient that is merely
          // near zero can be told from one that moves pixels.
          const double r = corner_r / cam.intrinsics[0];
          double shift = -1;
          if (k == 0) shift = s * std::pow(r, 3);
          if (k == 1) shift = s * std::pow(r, 5);
          if (k == 4) shift = s * std::pow(r, 7);
          if (k == 2 || k == 3) shift = 3 * s * r * r;
          char effect[96] = "";
          if (shift >= 0) {
            std::snprintf(effect, sizeof effect, "; 1 sigma moves the image corner by %.2g px",
                          shift * cam.intrinsics[0]);
          }
          std::snprintf(line, sizeof line,
                        "zoom %d: distortion %s = %.3g +- %.3g is badly determined (relative "
                        "sigma %.1f > 1%s)",
                        z, kDistortionNames[k], x, s, x != 0 ? s / std::abs(x) : INFINITY, effect);
          out.warnings.push_back(line);
        }
      }
    }
    out.zooms.push_back(c);
  }
  return out;
}

}  // namespace rtscalib::app

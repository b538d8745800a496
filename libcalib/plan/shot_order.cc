#include "libcalib/plan/shot_order.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

namespace rtscalib {
namespace {

// Azimuth of a placement's boards seen from the origin (SPEC 1: clockwise
// from +y) [rad].
double PlacementAzimuth(const TargetScene& scene) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const TagBoard& b : scene.boards) sum += b.CentreInRef();
  return std::atan2(sum.x(), sum.y());
}

double Wrapped(double a) {
  a = std::fmod(std::abs(a), 2.0 * M_PI);
  return std::min(a, 2.0 * M_PI - a);
}

// Nearest-neighbour tour of `shots` starting at `from`.
void Tour(PlannedShot* from, std::vector<PlanShot>* shots) {
  std::vector<PlanShot> out;
  std::vector<bool> used(shots->size(), false);
  for (size_t k = 0; k < shots->size(); ++k) {
    size_t best = 0;
    double best_d = 1e300;
    for (size_t i = 0; i < shots->size(); ++i) {
      if (used[i]) continue;
      const double d = MotorTravel(*from, (*shots)[i].pointing);
      if (d < best_d) {
        best_d = d;
        best = i;
      }
    }
    used[best] = true;
    out.push_back((*shots)[best]);
    *from = out.back().pointing;
  }
  *shots = std::move(out);
}

}  // namespace

double MotorTravel(const PlannedShot& a, const PlannedShot& b) {
  return std::max(Wrapped(a.phi - b.phi), std::abs(a.theta - b.theta));
}

double OrderShots(const PlacedScenes& scenes, std::vector<PlanShot>* shots) {
  // Placements: a walk around the instrument, starting with the placement of
  // the first shot's smallest azimuth and then always the nearest azimuth.
  std::map<std::string, double> azimuth;
  for (const auto& [name, scene] : scenes) azimuth[name] = PlacementAzimuth(scene);
  std::vector<std::string> order;
  std::vector<std::string> left;
  for (const PlanShot& s : *shots) {
    if (std::find(left.begin(), left.end(), s.pointing.placement) == left.end())
      left.push_back(s.pointing.placement);
  }
  std::sort(left.begin(), left.end(),
            [&](const std::string& a, const std::string& b) { return azimuth[a] < azimuth[b]; });
  while (!left.empty()) {
    size_t best = 0;
    if (!order.empty()) {
      double best_d = 1e300;
      for (size_t i = 0; i < left.size(); ++i) {
        const double d = Wrapped(azimuth[left[i]] - azimuth[order.back()]);
        if (d < best_d) {
          best_d = d;
          best = i;
        }
      }
    }
    order.push_back(left[best]);
    left.erase(left.begin() + static_cast<long>(best));
  }
  std::vector<PlanShot> out;
  PlannedShot at;  // the instrument starts at phi = 0, theta = pi/2, face 1
  at.theta = M_PI / 2;
  for (const std::string& placement : order) {
    for (int face : {1, 2}) {
      std::map<int, std::vector<PlanShot>> by_zoom;
      for (const PlanShot& s : *shots) {
        if (s.pointing.placement == placement && s.pointing.face == face)
          by_zoom[s.pointing.zoom].push_back(s);
      }
      for (auto& [zoom, group] : by_zoom) {
        Tour(&at, &group);
        out.insert(out.end(), group.begin(), group.end());
      }
    }
  }
  double travel = 0;
  PlannedShot from;
  from.theta = M_PI / 2;
  for (const PlanShot& s : out) {
    travel += MotorTravel(from, s.pointing);
    from = s.pointing;
  }
  *shots = std::move(out);
  return travel;
}

}  // namespace rtscalib

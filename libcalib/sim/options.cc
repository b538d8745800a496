#include "libcalib/sim/options.h"

#include <algorithm>

namespace rtscalib {

std::string NoiseOptions::Check() const {
  if (angle_rad < 0 || distance_m < 0 || point_m < 0 || pixel_px < 0) {
    return "noise sigmas must be >= 0";
  }
  return "";
}

std::string AcquisitionPlan::Check() const {
  if (sweeps && sweep_points < 4)
    return "plan.sweep_points must be >= 4 (got " + std::to_string(sweep_points) + ")";
  if (edm_distances.empty()) return "plan.edm_distances must not be empty";
  for (double d : edm_distances) {
    if (!(d > 0)) return "plan.edm_distances must be > 0";
  }
  if (!(cam_ray_length > 0)) return "plan.cam_ray_length must be > 0";
  if (grid_phi_steps < 0 || grid_theta_steps < 0) return "plan.grid steps must be >= 0";
  for (int f : faces) {
    if (f != 1 && f != 2)
      return "plan.faces entries must be 1 or 2 (got " + std::to_string(f) + ")";
  }
  if (faces.empty()) return "plan.faces must not be empty";
  for (int z : zooms) {
    if (z < 0) return "plan.zooms entries must be >= 0";
  }
  return "";
}

std::string SimulationOptions::Check() const {
  std::string msg = noise.Check();
  if (msg.empty()) msg = plan.Check();
  if (msg.empty()) {
    for (int z : plan.zooms) {
      if (z >= truth.NumZooms()) {
        return "plan.zooms has zoom " + std::to_string(z) + " but the truth has " +
               std::to_string(truth.NumZooms()) + " camera(s)";
      }
    }
  }
  return msg;
}

int PlanNumZooms(const AcquisitionPlan& plan) {
  int max_zoom = -1;
  for (int z : plan.zooms) max_zoom = std::max(max_zoom, z);
  return max_zoom + 1;
}

}  // namespace rtscalib

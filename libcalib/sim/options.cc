#include "libcalib/sim/options.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <map>

namespace rtscalib {

std::string NoiseOptions::Check() const {
  if (angle_rad < 0 || distance_m < 0 || point_m < 0 || pixel_px < 0) {
    return "noise sigmas must be >= 0";
  }
  return "";
}

double AcquisitionPlan::EstimatedRecords() const {
  const double zoom_count = static_cast<double>(zooms.size());
  const double sweep_poses = sweeps ? 2.0 * sweep_points : 0.0;
  // Per sweep pose: the EDM distances and three pixels of one ray per zoom.
  const double per_sweep_pose = static_cast<double>(edm_distances.size()) + 3.0 * zoom_count;
  const double grid_poses = static_cast<double>(grid_phi_steps) * grid_theta_steps;
  const double pixels = static_cast<double>(grid_pixels_per_axis) * grid_pixels_per_axis;
  const double per_grid_pose =
      static_cast<double>(grid_edm_distances.size()) +
      zoom_count * static_cast<double>(grid_cam_ray_lengths.size()) * pixels;
  return static_cast<double>(faces.size()) *
         (sweep_poses * per_sweep_pose + grid_poses * per_grid_pose);
}

std::string AcquisitionPlan::CheckSize() const {
  for (int z : zooms) {
    if (z >= kMaxZoomLevels) {
      return "simulate.plan.zooms entries must be < " + std::to_string(kMaxZoomLevels) + " (got " +
             std::to_string(z) + "; zoom levels are 0..N-1, SPEC 2)";
    }
  }
  const double records = EstimatedRecords();
  if (records > kMaxRecords) {
    char text[160];
    std::snprintf(text, sizeof text,
                  "the plan gives %.3g records, more than the limit of %.3g (grid %d x %d poses, "
                  "%d sweep points)",
                  records, kMaxRecords, grid_phi_steps, grid_theta_steps, sweep_points);
    return std::string(text) +
           "; make simulate.plan.grid.phi_steps x theta_steps, grid.pixels_per_axis or "
           "sweep_points smaller";
  }
  return "";
}

std::string AcquisitionPlan::Check() const {
  const std::string size = CheckSize();
  if (!size.empty()) return size;
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
  if (msg.empty() && !placements.empty()) {
    if (!targets.boards.empty()) {
      return "targets and placements: give the boards in one of them (placements holds the "
             "boards of each placement)";
    }
    for (const auto& [name, scene] : placements) {
      bool valid = !name.empty() && name[0] != '.';
      for (char c : name) {
        valid = valid && (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' ||
                          c == '.');
      }
      if (!valid) {
        return "placements: name '" + name +
               "': expected letters, digits, '_', '-', '.' (no leading '.')";
      }
      if (scene.boards.empty()) return "placements: " + name + " has no boards";
    }
    // A board bends alike wherever it is put (board_warp): one warp per board.
    std::map<int, std::array<double, 2>> warp_of;
    for (const auto& [name, scene] : placements) {
      for (const TagBoard& b : scene.boards) {
        const auto [it, fresh] = warp_of.emplace(b.first_id, b.warp);
        if (!fresh && it->second != b.warp) {
          return "placements: " + name + ": board " + std::to_string(b.first_id) +
                 " has another warp than in an earlier placement (a board bends alike "
                 "wherever it is put)";
        }
      }
    }
  }
  return msg;
}

PlacedScenes SimulationOptions::Scenes() const {
  if (!placements.empty()) return placements;
  return PlacedScenes{{"", targets}};
}

int PlanNumZooms(const AcquisitionPlan& plan) {
  int max_zoom = -1;
  for (int z : plan.zooms) max_zoom = std::max(max_zoom, z);
  return max_zoom + 1;
}

}  // namespace rtscalib

#include "libcalib/extract/options.h"

#include <sstream>

namespace rtscalib {

std::string ExtractOptions::Check() const {
  std::ostringstream err;
  if (const std::string region = critical_region.Check(); !region.empty()) {
    err << region;
  } else if (!(angle_tolerance_rad > 0.0 && angle_tolerance_rad < 0.1)) {
    err << "angle_tolerance_rad must be in (0, 0.1), got " << angle_tolerance_rad;
  } else if (!(distance_tolerance_m > 0.0)) {
    err << "distance_tolerance_m must be > 0, got " << distance_tolerance_m;
  } else if (!(pixel_tolerance_px > 0.0 && pixel_tolerance_px < 0.5)) {
    err << "pixel_tolerance_px must be in (0, 0.5), got " << pixel_tolerance_px;
  } else if (min_sweep_points < 3) {
    err << "min_sweep_points must be >= 3 (a circle needs 3 points), got " << min_sweep_points;
  } else if (!(max_fit_rms_m > 0.0)) {
    err << "max_fit_rms_m must be > 0, got " << max_fit_rms_m;
  } else if (!(min_radius_m > 0.0)) {
    err << "min_radius_m must be > 0, got " << min_radius_m;
  } else if (const std::string e = axis_tolerances.Check(); !e.empty()) {
    err << "axis_tolerances: " << e;
  }
  return err.str();
}

}  // namespace rtscalib

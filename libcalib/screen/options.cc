#include "libcalib/screen/options.h"

#include <cmath>

namespace rtscalib {
namespace {
// The largest allowed max_missing_zooms: the cameras of missing levels are
// allocated, so the bound keeps memory independent of the option's value.
constexpr int kMaxMissingZoomsLimit = 1000;
}  // namespace

std::string ScreenOptions::Check() const {
  if (!(pixel_margin_px >= 0) || !std::isfinite(pixel_margin_px))
    return "screen.pixel_margin_px must be a finite number >= 0 [px]";
  if (!(max_extent_m > 0) || !std::isfinite(max_extent_m))
    return "screen.max_extent_m must be a finite number > 0 [m]";
  if (max_missing_zooms < 0 || max_missing_zooms > kMaxMissingZoomsLimit) {
    return "screen.max_missing_zooms must be in 0.." + std::to_string(kMaxMissingZoomsLimit) +
           " (got " + std::to_string(max_missing_zooms) + ")";
  }
  return gross_errors.Check();
}

std::string GrossScreenOptions::Check() const {
  if (!(sphere_threshold > 0) || !std::isfinite(sphere_threshold))
    return "screen.gross_errors.sphere_threshold must be > 0 [robust sigmas]";
  if (!(sphere_floor_m >= 0) || !std::isfinite(sphere_floor_m))
    return "screen.gross_errors.sphere_floor_m must be >= 0 [m]";
  if (min_rows < 5) return "screen.gross_errors.min_rows must be >= 5";
  return "";
}

}  // namespace rtscalib

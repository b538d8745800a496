// The critical regions (Klug Sec. 5; SPEC 3: rows excluded there are counted
// and reported): sights steeper than min_zenith_rad towards the zenith or
// beyond max_zenith_rad towards the nadir, where the instrument's model is
// not to be trusted (the tilting axis near the vertical, the camera seeing
// the instrument's own base). Rows there are left out of the extraction
// (ExtractOptions), the start from pixels (InitFromPixelsOptions), the fit
// and its checks (FitOptions), and counted.
//
// One region for the whole calibration: the config's fit.critical_region
// (docs/config.md) is read once into FitOptions::critical_region, and
// Calibrate (libcalib/calibrate) hands that same region to the extraction and
// to the start from pixels.
#pragma once

#include <cmath>
#include <string>

namespace rtscalib {

struct CriticalRegion {
  double min_zenith_rad = 10.0 * M_PI / 180.0;
  double max_zenith_rad = 135.0 * M_PI / 180.0;

  // Whether a reading's zenith angle (ZenithOf(theta): theta in face 1,
  // 2 pi - theta in face 2) lies outside [min_zenith_rad, max_zenith_rad].
  // The limits themselves are usable.
  bool Contains(double theta) const;
  // "" when 0 <= min < max <= pi, else "zenith limits must satisfy ..."
  // with both values.
  std::string Check() const;
};

}  // namespace rtscalib

// The options of the projection uncertainty maps (ProjectionUncertaintyMaps,
// libcalib/api/uncertainty_map.h): the config's `report.uncertainty_map`
// (docs/config.md) reads into this struct and the report passes it on as it
// is. It lives in io, not in api, because api is built on io (model.yaml,
// covariance.yaml) and io must not include api; both include it from here.
#pragma once

#include <cmath>
#include <string>

namespace rtscalib {

struct UncertaintyMapOptions {
  double range_m = 10.0;    // ray length of the points [m]
  int cols = 24;            // cells across the image
  int rows = 18;            // cells down the image
  double phi = 0.0;         // pointing [rad] (face 1, towards +y)
  double theta = M_PI / 2;  // zenith angle [rad] (horizontal)
  // "" when valid, else what is wrong.
  std::string Check() const;
};

}  // namespace rtscalib

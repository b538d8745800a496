#include "libcalib/model/critical_region.h"

#include <sstream>

#include "libcalib/model/instrument.h"

namespace rtscalib {

bool CriticalRegion::Contains(double theta) const {
  const double z = ZenithOf(theta);
  return z < min_zenith_rad || z > max_zenith_rad;
}

std::string CriticalRegion::Check() const {
  if (min_zenith_rad >= 0.0 && min_zenith_rad < max_zenith_rad && max_zenith_rad <= M_PI) return "";
  std::ostringstream err;
  err << "zenith limits must satisfy 0 <= min < max <= pi, got min " << min_zenith_rad << ", max "
      << max_zenith_rad;
  return err.str();
}

}  // namespace rtscalib

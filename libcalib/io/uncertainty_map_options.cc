#include "libcalib/io/uncertainty_map_options.h"

namespace rtscalib {

std::string UncertaintyMapOptions::Check() const {
  if (!(range_m > 0) || !std::isfinite(range_m)) return "range_m must be a finite range > 0";
  if (cols < 1 || rows < 1 || cols > 1000 || rows > 1000) return "cells must be 1..1000 each";
  if (!std::isfinite(phi) || !std::isfinite(theta)) return "phi and theta must be finite";
  return "";
}

}  // namespace rtscalib

// Options of the screening of observations before any fit
// (libcalib/screen/screen.h; the config's `screen` section, docs/config.md).
#pragma once

#include <string>

namespace rtscalib {

// The gross-error screening before the fit (libcalib/screen/gross.h; key
// `screen.gross_errors`).
struct GrossScreenOptions {
  bool enabled = true;
  double sphere_threshold = 8.0;  // robust sigmas (1.4826 MAD)
  // Never flag below this departure [m]. 1 mm: the extraction's circle and
  // line fits accept 1 mm RMS (ExtractOptions::max_fit_rms_m), so a sweep
  // row off by more must not reach them (a 5 mm floor let a 7 mm error stop
  // the extraction of joint 2 in bench/calibrate_benchmark.cc).
  double sphere_floor_m = 1e-3;
  int min_rows = 12;          // fewer rows per sphere: not screened
  std::string Check() const;  // empty if valid
};

struct ScreenOptions {
  // A pixel may lie this far outside its zoom's image (model.cameras) before
  // it is an error: detectors report corners a little beyond the border [px].
  double pixel_margin_px = 50.0;
  // Known points of pixels.csv farther than this from the origin are errors
  // (millimetres read as metres) [m].
  double max_extent_m = 10000.0;
  // Zoom levels below the largest one that may have no camera rows and no
  // pixels (a device with 7 zooms calibrated at zooms 0 and 6 lacks 5).
  // Memory grows with the largest zoom, so a zoom far beyond the data's
  // levels is an error, not an allocation.
  int max_missing_zooms = 8;
  GrossScreenOptions gross_errors;
  // Empty if valid, else what is wrong (the key's name, what it must be).
  std::string Check() const;
};

}  // namespace rtscalib

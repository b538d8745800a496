// A fit that went wild: parameters the data do not hold, or values no
// instrument has. Where the model lacks an effect, the fit's free
// coefficients bend to absorb it (a k3 of -8.5e5 whose sigma moves the image
// corners by 8e4 px); such values are not estimates, and the report says so
// at its top instead of advising to drop a coefficient.
//
// Checks (each zoom's image size S = max(width, height) [px]):
//   distortion coefficient  its sigma or its value moves the image corners by
//                           more than S (DistortionTerm::corner_px,
//                           corner_value_px, distortion_terms.h)
//   fx, fy                  <= 0, sigma > S, or |fy / fx - 1| > kMaxAspect
//                           (square pixels to within a few per mille on any
//                           sensor; 5 % is no camera)
//   cx, cy                  outside the image, or sigma > S
//   focus kf                |kf| > kMaxFocusKf (the camera constant's growth
//                           per 1/D is about the lens's focal length, below a
//                           metre for a telescope camera) or kf / D_min < -0.5
//   focus au, av            |au| / D_min or |av| / D_min > S
//   kinematic effects       beyond kMaxEffectReport in report units: 2000
//                           arcsec (0.01 rad: an instrument that far off is
//                           broken, not calibrated), 1000 ppm, 100 mm
// Sigmas come from the linearisation's normal matrix C = (J^T J)^-1 of the
// fit's free parameters (whitened by the fit's sigmas).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "libcalib/diagnose/distortion_terms.h"
#include "libcalib/diagnose/linearization.h"
#include "libcalib/model/instrument.h"

namespace rtscalib {

constexpr double kMaxAspect = 0.05;
constexpr double kMaxFocusKf = 1.0;  // m
constexpr double kMaxArcsec = 2000, kMaxPpm = 1000, kMaxMm = 100;

struct WildParameter {
  std::string name;   // "k3 of zoom 1", "fx of zoom 0", "focus kf of zoom 2", "hz_scale"
  int zoom = -1;      // -1: not a camera parameter
  std::string value;  // "-8.5e+05 +- 1.2e+06"
  std::string why;    // "its sigma alone moves the image corners by 8.26e4 px, more than the image (1280 px)"
  bool undetermined = false;  // its sigma is the problem (else its value)
};

// `min_distance[z]`: the nearest target distance of zoom z's photos and
// camera records [m] (0: unknown).
std::vector<WildParameter> FindWildParameters(const Linearization& lin,
                                              const InstrumentModel& model,
                                              const DistortionTerms& terms,
                                              const std::map<int, double>& min_distance);

}  // namespace rtscalib

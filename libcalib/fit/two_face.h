// The classical two-face check (SPEC 4 signatures) between a model fitted to
// face-1 data and one fitted to face-2 data (`faces: separate`).
//
// Both models are read along their line of sight (the EDM ray, or a camera's
// optical axis) over a grid of
// face-1 pointings (phi every 30 deg, zenith 50 .. 130 deg) and the face-2
// readings of the same pointings (SPEC 1). With hz the ray's horizontal
// direction (clockwise from +y) and z its zenith angle:
//   hz1 - hz2 = 2 c / sin z + 2 i cot z       (collimation c, tilting axis i)
//   z1 - z2   = 2 v0                          (vertical index v0)
// c and i are the least-squares solution over the grid, v0 the mean. Angles in
// radians. Valid for small c, i, v0 (first order; the neglected terms are
// ~c^2, i.e. < 1e-8 rad for c < 100").
#pragma once

#include "libcalib/model/instrument.h"

namespace rtscalib {

struct TwoFaceDifferences {
  double collimation = 0;     // c [rad]
  double tilting_axis = 0;    // i [rad]
  double vertical_index = 0;  // v0 [rad]
  // RMS of the hz and z equations' residuals over the grid [rad]: what c, i,
  // v0 do not explain (e.g. face-dependent effects beyond the classical three).
  double rms_hz = 0, rms_z = 0;
  int num_pointings = 0;
};

// `zoom` < 0: along the EDM ray; otherwise along that zoom's optical axis
// (camera z, for models fitted to pixels only, whose EDM tool is not observed).
TwoFaceDifferences TwoFaceCheck(const InstrumentModel& face1, const InstrumentModel& face2,
                                int zoom = -1);

}  // namespace rtscalib

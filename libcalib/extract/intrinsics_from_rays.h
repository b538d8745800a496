// Pinhole intrinsics of each zoom level from camera records alone, for data
// without Klug's pixel triplets (Eq. 67) and without configured intrinsics.
//
// At one pose, camera rows give view rays in the reference frame: the
// direction through pixel p is (x(d2) - x(d1)) / (d2 - d1) from two ray
// lengths, or, with one length, (x - c) / |x - c| with the camera centre c
// taken at the EDM's origin (two EDM distances at the pose). A pinhole maps
// ray directions r to pixels by the homography H = K R^T (points at
// infinity), found by the normalised DLT from >= 4 pixels; an RQ split gives
// K (skew dropped). K is the median over poses. Distortion is not estimated
// (the refinement does that when it is enabled).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"

namespace rtscalib {

struct RayIntrinsicsEstimate {
  CameraTool camera;  // intrinsics, width, height; pose and distortion zero
  int poses = 0;      // poses that gave a homography
  std::string note;
};

// Returns nullopt when no pose of `zoom` has >= 4 distinct pixels with known
// ray directions.
std::optional<RayIntrinsicsEstimate> EstimateIntrinsicsFromRays(const std::vector<Record>& records,
                                                                int zoom);

}  // namespace rtscalib

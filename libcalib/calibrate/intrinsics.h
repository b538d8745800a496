// The intrinsics decision: whether the calibration's fits free the cameras'
// fx, fy, cx, cy (FitOptions::fit_intrinsics, which Refine obeys). It is made
// here, once per calibration, from the config's model.intrinsics
// (ModelSettings::intrinsics, docs/config.md) and the data; the config does
// not set fit_intrinsics, and CalibrationResult::intrinsics_fitted reports
// what was decided.
//
//   kFit   -> always;
//   kFixed -> never: model.cameras stay as given;
//   kAuto  -> when the camera data of every zoom level in the data span its
//             image (CamDataSpanImage), the condition under which the
//             intrinsics are observable; never without camera data.
//
// The reduced set (Klug's Table 5, a subset of the records) is fitted first:
// its fit frees the intrinsics only when the whole calibration does and the
// subset's own camera data of zoom 0 span the image (the sweeps alone never
// do), so that the subset does not fit what it cannot observe.
#pragma once

#include <set>

#include "libcalib/calibrate/options.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"

namespace rtscalib {

// The zoom levels of the camera data: camera records and pixels.
std::set<int> ZoomsInData(const Observations& obs);

// Camera rows (or pixels) of `zoom` span the image of `model`'s camera there
// when their pixels cover more than a quarter of its width and of its height.
bool CamDataSpanImage(const Observations& obs, const InstrumentModel& model, int zoom);

// The decision for the calibration of `obs` from `start` (see above).
bool FitIntrinsics(IntrinsicsMode mode, const Observations& obs, const InstrumentModel& start);

// The decision for the reduced set's fit: `whole` is FitIntrinsics' answer
// for the whole calibration.
bool FitIntrinsicsOnReducedSet(bool whole, const Observations& reduced,
                               const InstrumentModel& start);

}  // namespace rtscalib

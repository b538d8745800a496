// Starting models for the refinement, derived from the extraction (never from
// the simulator's truth).
#pragma once

#include "libcalib/model/instrument.h"

namespace rtscalib {

// A `spherical` model (Klug Sec. 4.1 + SPEC 4) that matches a `dh` model at
// the horizontal face-1 pointing (phi = 0, theta = pi/2): the station base is
// the dh model's line-of-sight frame there, turned back by the ideal
// Rz(0) Rx(-pi/2); each camera tool is the dh camera pose relative to it; the
// EDM keeps the ideal rotation and takes the dh EDM origin's x, y offsets.
InstrumentModel SphericalFromDh(const InstrumentModel& dh);

// Copies `effects` (enabled set and values) onto `model`; effects that `dh`
// already contains (redundant_in_dh) are dropped for a dh model.
void EnableEffects(const EffectSet& effects, InstrumentModel* model);

}  // namespace rtscalib

// The surveying terms a `dh` model already contains (SPEC 4: collimation,
// tilting_axis, vertical_index, edm_offset live in its links and tools), read
// off the model: a `spherical` model with those four terms (and the dh model's
// own kinematic effects) is fitted, without noise, to the dh model's EDM
// predictions on a grid of both faces and several distances. Its term values
// are the dh model's equivalent values; `fit_rms_m` says how exactly the
// spherical form reproduces the dh model (DH link offsets it cannot express
// show up there, not in the terms).
#pragma once

#include <array>

#include "libcalib/fit/refine.h"
#include "libcalib/model/instrument.h"

namespace rtscalib {

struct EquivalentTerms {
  bool valid = false;
  // SI values and 2x2 covariances (zero: read off a model, not estimated) per
  // kinematic effect; only the four redundant terms are filled.
  std::array<std::array<double, 2>, kNumKinematicEffects> value{};
  double fit_rms_m = 0;
  std::string message;
};

// `fit` supplies the zenith limits; `dh` must have dh kinematics.
EquivalentTerms EquivalentSurveyingTerms(const InstrumentModel& dh, const FitOptions& fit);

}  // namespace rtscalib

// model.yaml: the fitted instrument, everything needed to predict (SPEC 5).
//
// Layout (all angles in radians, lengths in metres, pixels in pixels):
//   format: rtscalib-model, version: 1, metadata: {free text pairs}
//   kinematics, edm_cyclic_unit_length, uncertainties (whether sigmas follow)
//   base, edm:         {q: [x, y, z, w], t, euler: [a, b, g] (Klug Eq. 83), sigma}
//   links (dh only):   [{d, gamma_offset, alpha, a, sigma}, x2]
//   effects:           [{name, si: [..], covariance: [2x2 row major],
//                        report: {param: {value, sigma, unit}}}]   kinematic/EDM effects
//                      [{name}]   distortion groups (coefficients are in cameras)
//   cameras (index = zoom): {zoom, width, height, flange_from_cam: pose,
//                        intrinsics: {fx, fy, cx, cy}, distortion: {k1 .. tauy},
//                        distortion_held: [k3, ...]  coefficients of enabled groups the
//                                  user held (model.<group>.coefficients): not estimated;
//                        intrinsics_sigma, distortion_sigma}  a coefficient the fit did not
//                                  free (held, or of a group not in the model) has the sigma
//                                  `held`, never a number (read back as 0: no uncertainty)
//   determined: false  on edm or a camera (and its flange_from_cam) the data
//                      did not determine: its values are the start's and it
//                      has no sigma keys (never a sigma of 0); absent = true.
// The parameter blocks (q, t, links, si, intrinsics, distortion) are written
// with %.17g and are what predictions use, so a model read back predicts bit
// for bit the same. Euler angles and report-unit values are for people; when
// read back they must agree with the blocks (a hand edit of a derived value
// would otherwise be silently ignored).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"

namespace rtscalib {

// Free-form key/value pairs stored with the model (program version, date,
// config path, fit summary...), kept in order.
using ModelMetadata = std::vector<std::pair<std::string, std::string>>;

// Throws std::runtime_error if the file cannot be written.
void WriteModelYaml(const std::string& path, const InstrumentModel& model,
                    const ModelMetadata& metadata = {});
// Throws InputError naming file and key for anything malformed. Files
// without `determined` keys (older ones) read as fully determined.
InstrumentModel ReadModelYaml(const std::string& path, ModelMetadata* metadata = nullptr);

}  // namespace rtscalib

// covariance.yaml: the fit's full parameter covariance, written beside
// model.yaml (docs/output.md, docs/library.md). model.yaml keeps one sigma
// per parameter for people; this file keeps the joint covariance P that the
// API's uncertainties need (correlations included).
//
// Layout:
//   format: rtscalib-covariance, version: 1
//   parameters: N
//   blocks: [{name, offset, size, unit, at: [stored values]}]   ParameterLayout order
//   covariance: N rows of N numbers (%.17g, exactly symmetric)
// `at` is each block's values in model.yaml (a quaternion's 4, a block's
// own values otherwise) when P was computed: the file belongs to the model
// whose blocks equal them bit for bit (model.yaml writes %.17g too); any
// other model.yaml is refused, never paired silently with a foreign P.
#pragma once

#include <string>

#include "libcalib/model/instrument.h"

namespace rtscalib {

// The companion file of a model.yaml: covariance.yaml in the folder of the
// file `model_yaml` resolves to (through symlinks, so that a published
// OUT/model.yaml -> latest/model.yaml pairs with the same run's file).
std::string CovariancePathFor(const std::string& model_yaml);

// Writes model.sigmas.covariance (ParameterLayout(model) square). Throws
// std::invalid_argument when it has another size, std::runtime_error when the
// file cannot be written.
void WriteCovarianceYaml(const std::string& path, const InstrumentModel& model);

// Reads `path` into model->sigmas.covariance. Throws InputError naming the
// file and key for anything malformed: wrong format, blocks that are not
// model's (names, sizes) or whose values differ from model's (another run's
// model), a non-symmetric or non-finite matrix, a negative variance.
void ReadCovarianceYaml(const std::string& path, InstrumentModel* model);

}  // namespace rtscalib

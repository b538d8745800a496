// The diagnosis part of report.json and report.txt: DiagnosisJson is SPEC 6's
// `diagnosis` object (plus more keys, the stepwise ladder among them);
// DiagnosisText the same for a person. The diagnosis itself is computed by
// Calibrate (libcalib/calibrate/calibrate.h).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "libcalib/calibrate/calibrate.h"

namespace rtscalib::app {

nlohmann::json DiagnosisJson(const CalibrationResult& result);
std::string DiagnosisText(const CalibrationResult& result);

}  // namespace rtscalib::app

// The diagnosis step of a run and its report.json / report.txt parts.
//
// RunDiagnosis: after the refinement, rank the missing effects, look for
// structure outside the catalogue and for outliers (libcalib/diagnose); with
// `diagnose.auto` first climb the forward stepwise ladder and make its last
// rung the run's model. DiagnosisJson is SPEC 6's `diagnosis` object (plus
// more keys); DiagnosisText the same for a person.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "app/pipeline.h"
#include "app/progress.h"
#include "libcalib/io/config.h"

namespace rtscalib::app {

// Fills result->diagnosis (and, with config.diagnose.auto_add, result->ladder
// and the stepwise model, fit and final errors). No-op when
// config.diagnose.enabled is false. A diagnosis that fails (e.g. nothing
// outside the critical regions) leaves a note instead of failing the run;
// RunDiagnosisOrThrow lets the exception through.
void RunDiagnosis(const RunConfig& config, PipelineResult* result, Progress* progress);
void RunDiagnosisOrThrow(const RunConfig& config, PipelineResult* result, Progress* progress);

nlohmann::json DiagnosisJson(const PipelineResult& result);
std::string DiagnosisText(const PipelineResult& result);

}  // namespace rtscalib::app

// Forward stepwise model building (`rtscalib diagnose --auto`): diagnose, add
// the recommended effect (Diagnosis::Next: significant and worth adding),
// refine (from the current model, the new effect at zero, as the ranking's
// refit), repeat until no effect is recommended or `max_steps` effects have
// been added. The ladder records every rung: the
// model, its error per observation group, the effect added and its BIC with
// one free variance per group (GroupRms::Bic), so rungs compare.
#pragma once

#include <string>
#include <vector>

#include "libcalib/diagnose/diagnose.h"

namespace rtscalib {

struct LadderStep {
  std::string added;  // "" on the first rung
  std::string model_description;
  std::vector<std::string> effects;
  GroupRms rms;
  double bic = 0;
  int num_parameters = 0;
  FitSummary fit;
};

struct StepwiseResult {
  std::vector<LadderStep> ladder;
  InstrumentModel model;  // the last rung's model
  FitSummary fit;
  Diagnosis diagnosis;  // of the last rung
  std::string stop_reason;
};

// `model` and `fit` are a fitted model and its summary; `fit_options` what the
// fit used. Throws what Refine throws.
StepwiseResult ForwardStepwise(const Observations& obs, const InstrumentModel& model,
                               const FitSummary& fit, const FitOptions& fit_options,
                               const DiagnosisSettings& settings, int max_steps = 8);

}  // namespace rtscalib

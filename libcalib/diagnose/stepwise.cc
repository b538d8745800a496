#include "libcalib/diagnose/stepwise.h"

namespace rtscalib {

StepwiseResult ForwardStepwise(const Observations& obs, const InstrumentModel& model,
                               const FitSummary& fit, const FitOptions& fit_options,
                               const DiagnosisSettings& settings, int max_steps) {
  StepwiseResult out;
  out.model = model;
  out.fit = fit;
  std::string added;
  for (int step = 0;; ++step) {
    out.diagnosis = Diagnose(obs, out.model, ContextOf(fit_options, out.fit), settings);
    LadderStep rung;
    rung.added = added;
    rung.model_description = out.diagnosis.model_description;
    rung.effects = out.diagnosis.effects;
    rung.rms = out.diagnosis.current;
    rung.num_parameters = out.diagnosis.num_parameters;
    rung.bic = rung.rms.Bic(rung.num_parameters);
    rung.fit = out.fit;
    out.ladder.push_back(rung);

    const RankedEffect* next = out.diagnosis.Next();
    if (!next) {
      out.stop_reason = "no catalogue effect is significant and worth adding";
      break;
    }
    if (step >= max_steps) {
      out.stop_reason = "stopped after " + std::to_string(max_steps) + " added effects";
      break;
    }
    // From the current model with the effect at zero, as the ranking's
    // refit starts (ranking.h): its first step is the linear estimate with
    // every other parameter moved along.
    InstrumentModel m = out.model;
    m.effects.Add(next->effect);
    m.sigmas = {};
    added = next->name;
    out.fit = Refine(obs, fit_options, &m);
    out.model = m;
  }
  return out;
}

}  // namespace rtscalib

#include "libcalib/diagnose/equivalents.h"

#include <cmath>
#include <vector>

#include "libcalib/eval/error_measures.h"
#include "libcalib/fit/parameterization.h"
#include "libcalib/fit/start_models.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib {

EquivalentTerms EquivalentSurveyingTerms(const InstrumentModel& dh, const FitOptions& fit) {
  EquivalentTerms out;
  if (dh.kinematics != Kinematics::kDh) {
    out.message = "not a dh model";
    return out;
  }
  // Both faces, zenith over the admissible range, distances over a decade:
  // enough to separate c/sin z, i cot z, the index and the offset exactly.
  AcquisitionPlan plan;
  plan.sweeps = false;
  plan.grid_phi_steps = 12;
  plan.grid_theta_steps = 10;
  plan.grid_edm_distances = {2.0, 10.0, 30.0};
  plan.faces = {1, 2};
  plan.zooms = {};
  Observations obs;
  obs.records = PlanRecords(plan, dh);
  obs.records_source = "dh model predictions";

  InstrumentModel sph = SphericalFromDh(dh);
  // The terms dh contains (SPEC 4), fitted as spherical effects.
  std::vector<Effect> terms;
  for (const EffectInfo& info : EffectCatalogue()) {
    if (ContainedInKinematics(Kinematics::kDh, info.effect)) terms.push_back(info.effect);
  }
  for (Effect e : terms) {
    sph.effects.Add(e);
    sph.EffectValue(e) = {0.0, 0.0};
  }
  // SphericalFromDh keeps only the EDM's lateral offsets; the offset along the
  // ray is edm_offset's to find.
  FitOptions o = fit;
  o.reestimate_sigmas = false;
  o.compute_covariance = false;
  o.loss = RobustLoss::kNone;
  o.sigma_edm_m = 1e-6;
  o.translation_bound_m = 0;  // the spherical translations need not stay near dh's
  o.max_iterations = 100;
  try {
    const FitSummary s = Refine(obs, o, &sph);
    std::vector<double> dist;
    for (const RecordResidual& r : RecordResiduals(sph, obs.records)) {
      if (r.valid &&
          !o.critical_region.Contains(obs.records[r.index].theta)) {
        dist.push_back(r.distance);
      }
    }
    out.fit_rms_m = StatsOf(dist).rms_m;
    for (Effect e : terms) out.value[static_cast<int>(e)] = sph.EffectValue(e);
    out.valid = s.converged || s.final_cost < 1e-6;
    out.message = s.message;
  } catch (const std::exception& e) {
    out.message = e.what();
  }
  return out;
}

}  // namespace rtscalib

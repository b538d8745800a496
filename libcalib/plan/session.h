// The session a config describes for `rtscalib plan` (SPEC 8): the a-priori
// instrument (plan.prior_model, else the simulated truth), what will be
// estimated (the `model` and `fit` sections), the boards and their
// placements (simulate.targets or simulate.placements) and the records a
// tracker session measures anyway (the simulate.plan's sweeps and grid, at
// the prior, without noise: only their information counts).
#pragma once

#include "libcalib/config/config.h"
#include "libcalib/plan/planner.h"
#include "libcalib/plan/settings.h"

namespace rtscalib {

// Throws InputError naming the config when it has no `simulate` section
// (the boards and the a-priori instrument come from it).
PlanSession SessionFromConfig(const RunConfig& config, const PlanSettings& settings);

}  // namespace rtscalib

// The ladder: the error per observation group across rungs (this run's
// forward stepwise search, `diagnose --auto`) or across the runs of the
// output folder, as Vega specs (plot/vega_spec.h).
#pragma once

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/plot/vega_spec.h"

namespace rtscalib::app {

// One rung: its label and the rms error of each group (NaN: none).
struct Rung {
  std::string label;  // "step 1: +hz_eccentricity"
  double edm_mm = NAN, cam_mm = NAN, px = NAN;
};

// The rungs' errors on log scales, mm (EDM and camera points) and px.
Figure LadderFigure(const std::vector<Rung>& rungs, const std::string& name,
                    const std::string& title, const std::string& caption);

// The final error of the output folder's earlier complete runs (`history`,
// report.json's "history", oldest first) and of this run (`effects`,
// `final` as in report.json), the latest kLadderRunsShown of them; its
// summary's "runs" counts them all.
constexpr size_t kLadderRunsShown = 12;
Figure RunsLadderFigure(const nlohmann::json& history, const std::vector<std::string>& effects,
                        const nlohmann::json& final);

}  // namespace rtscalib::app

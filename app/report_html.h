// report.html: one self-contained page (no external files: the figures are
// Vega specs drawn as SVG by the Vega runtime inlined in the page, app/plot/vega.h)
// that a person reads top-down:
//   verdict (how good the model is, what to add next, the config line)
//   the ladder (this run's stepwise rungs, the runs in the output folder)
//   error maps
//   tables: ranking of the missing effects, structure outside the catalogue,
//           outliers, final errors, fit
//   image coverage (its warnings, the plan command that fills the gaps),
//   projection uncertainty
//   image residuals, the worst photos, residuals against the variables,
//   histograms
// The same figures are files in the run's figures/ folder (WriteFigureFiles).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/figures.h"
#include "app/output_folder.h"
#include "app/pipeline.h"
#include "libcalib/config/config.h"

namespace rtscalib::app {

// `report` is the run's report.json (for the history and the final errors).
std::string ReportHtml(const RunConfig& config, const PipelineResult& result,
                       const nlohmann::json& report, const std::vector<Figure>& figures);

// A page with one figure (`rtscalib show`).
std::string FigurePage(const Figure& f);

std::string Base64(const std::vector<unsigned char>& bytes);

}  // namespace rtscalib::app

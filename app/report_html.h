// report.html: one self-contained page (pictures embedded as base64 PNG, no
// scripts, no external files) that a person reads top-down:
//   verdict (how good the model is, what to add next, the config line)
//   the ladder (this run's stepwise rungs, the runs in the output folder)
//   error maps
//   tables: ranking of the missing effects, structure outside the catalogue,
//           outliers, final errors, fit
//   image residuals and histograms
// The same pictures are written as PNG files to the run's figures/ folder.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/figures.h"
#include "app/output_folder.h"
#include "app/pipeline.h"
#include "libcalib/io/config.h"

namespace rtscalib::app {

// `report` is the run's report.json (for the history and the final errors).
std::string ReportHtml(const RunConfig& config, const PipelineResult& result,
                       const nlohmann::json& report, const std::vector<Figure>& figures);

// Writes <run>/figures/*.png and <run>/report.html.
void WriteReportHtml(const RunConfig& config, const PipelineResult& result,
                     const nlohmann::json& report, const OutputFolder& out);

std::string Base64(const std::vector<unsigned char>& bytes);

}  // namespace rtscalib::app

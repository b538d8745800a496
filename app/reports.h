// Turns a PipelineResult into files: report.json (SPEC 6), report.txt (the
// analogues of Klug Tables 1, 2, 4, 5, 6, 7 for a person) and model.yaml.
// The reports only format what the pipeline computed.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "app/figures.h"
#include "app/output_folder.h"
#include "app/pipeline.h"

namespace rtscalib::app {

// `history`: HistoryJson(out), read once per run and shared with the
// figures.
nlohmann::json ReportJson(const RunConfig& config, const PipelineResult& result,
                          const OutputFolder& out, const nlohmann::json& history);
std::string ReportText(const RunConfig& config, const PipelineResult& result);
// The rows taken out as gross errors, a line each (the first 50), for
// report.txt and report.html; empty when there are none.
std::string GrossRowsText(const PipelineResult& result);
// The pairs of fitted parameters with |rho| > 0.95 (FitSummary::
// strong_correlations), the strongest 16 among the model's own a line each
// and those with an estimated board pose counted on one line, for
// report.txt; empty when there are none.
std::string StrongCorrelationsText(const FitSummary& fit);
// The refinement's a-posteriori sigmas (pixels per zoom) and how the
// covariance treats correlated errors, one sentence for report.txt and
// report.html; `records` false leaves out the EDM and camera-record sigmas.
std::string FitSigmasText(const FitSummary& fit, bool records = true);
// Where the calibration's points leave the image's corners empty
// (coverage warnings): the `rtscalib plan --from` command that proposes the
// photos to add, one sentence for report.txt and report.html; empty
// otherwise.
std::string PlanHint(const RunConfig& config, const PipelineResult& result);
// The estimated board poses (SPEC 7, one per board and placement, SPEC
// 7.1) with their sigmas, a line each; empty when there are none.
std::string BoardsText(const InstrumentModel& model);

// Key figures of earlier runs, read back from their report.json (for the
// ladder of errors across runs): the latest complete run's report.json
// lists the runs before it, so only the runs it does not list are read
// one by one.
// Every earlier entry has "run" and "status" (RunStateName; "reason" when not
// complete); only complete runs carry "kinematics", "effects" and "final".
nlohmann::json HistoryJson(const OutputFolder& out);
// The history for report.txt: one line per earlier run, killed and failed
// runs marked as such.
std::string HistoryText(const nlohmann::json& history);

nlohmann::json StatsJson(const ErrorStats& s);

// residuals.csv: the calibration's residual table (CalibrationResult::
// residuals), one row per observation as given, columns ResidualColumns()
// (docs/output.md); report.json's "residuals" says what it holds (rows per
// status, rms of the fitted rows per group and zoom).
const std::vector<std::string>& ResidualColumns();
std::string ResidualsCsv(const PipelineResult& result);
nlohmann::json ResidualsJson(const PipelineResult& result);
// report.json's "figures": each figure's name, section, title, files and
// key numbers; `note` says why no PNG was written ("" when they were).
nlohmann::json FiguresJson(const std::vector<Figure>& figures,
                           const std::vector<std::vector<std::string>>& files,
                           const std::string& note);

}  // namespace rtscalib::app

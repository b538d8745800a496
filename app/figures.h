// The pictures of a run, as Vega specs (app/vega.h draws them: SVG in
// report.html, PNG files beside it). Every plotted number comes from the
// calibration's own tables: the residual table (CalibrationResult::residuals,
// one row per observation at the final model, boards of unknown pose at their
// estimates), the coverage, the ladder, the run history and the uncertainty
// maps. Nothing here predicts or fits; axes, ticks, legends and colour
// schemes are Vega's. In the order report.html shows them:
//   ladder        error per observation group across this run's stepwise rungs
//                 and across the runs of the output folder
//   maps          rms error per pointing over phi and theta, per face, per tool
//                 (EDM, camera rows and image points per zoom)
//   image         per zoom: fitted image residuals binned over the image (mean
//                 vector per cell, scaled, the scale in pixels, points per cell)
//   photos        the worst photos of each zoom with their corners and scaled
//                 residual arrows (any photo: `rtscalib show --shot ID`)
//   variables     residuals against each variable the diagnosis tests (binned
//                 mean and its 2-sigma band), one row per variable
//   histograms    residual coordinates per group against the Gaussian of the
//                 fitted sigma
//   uncertainty   projection uncertainty per zoom
// `summary` holds each figure's key numbers for report.json (docs/output.md).
// The figures themselves: residual_figures.h (maps, image, variables,
// histograms), photo_figure.h, ladder_figures.h, heat_map_figures.h
// (uncertainty, and `rtscalib compare`'s difference), all built from
// vega_spec.h's blocks; this file chooses and orders them and writes them.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/pipeline.h"
#include "app/vega.h"
#include "app/vega_spec.h"

namespace rtscalib::app {

// `history` = report.json's "history" array (earlier runs, oldest first).
std::vector<Figure> MakeFigures(const PipelineResult& result, const nlohmann::json& history);

// Writes <dir>/<name>.vg.json for each figure and, when the PNG renderer is
// installed (app/vega.h), <name>.svg and <name>.png; returns the names of
// the files written per figure (in figure order) and, in *note, why a PNG
// was not written ("" when every one was). `renderer`: one started earlier
// (the run starts its own when it has read its config, app/vega.h), else
// one is started here.
std::vector<std::vector<std::string>> WriteFigureFiles(const std::vector<Figure>& figures,
                                                       const std::string& dir, std::string* note,
                                                       VegaRenderer* renderer = nullptr);

}  // namespace rtscalib::app

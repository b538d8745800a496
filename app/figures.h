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
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/pipeline.h"
#include "app/vega.h"
#include "libcalib/api/compare.h"

namespace rtscalib::app {

struct Figure {
  std::string name;     // file stem: figures/<name>.vg.json, .svg, .png
  std::string section;  // "ladder", "maps", "image", "photos", "variables", ...
  std::string title;
  std::string caption;
  nlohmann::json spec;     // Vega 5
  nlohmann::json summary;  // what report.json says of the figure
};

// `history` = report.json's "history" array (earlier runs, oldest first).
std::vector<Figure> MakeFigures(const PipelineResult& result, const nlohmann::json& history);

// The final error of the output folder's earlier complete runs (`history`,
// report.json's "history", oldest first) and of this run (`effects`,
// `final` as in report.json), the latest kLadderRunsShown of them; its
// summary's "runs" counts them all.
constexpr size_t kLadderRunsShown = 12;
Figure RunsLadderFigure(const nlohmann::json& history, const std::vector<std::string>& effects,
                        const nlohmann::json& final);

// One photo with its observed corners and scaled residual arrows. `rows`:
// the residual table's pixel rows of that shot (any status: only fitted
// rows get arrows, the others are marked); `image` the photo file ("" or
// unreadable: the corners on a blank image of width x height).
Figure PhotoFigure(const std::string& shot, const std::vector<ObservationResidual>& rows,
                   const std::string& image, int width, int height);

// The photo files of a run by shot id (the photo session's shots.csv rows,
// resolved against its folder).
std::map<std::string, std::string> PhotoFiles(const PhotoSessionSummary& photos);

// The projection difference of one zoom between two models (`rtscalib
// compare`, libcalib/api/compare.h) as a heat map.
Figure DifferenceFigure(const ZoomDifference& d);

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

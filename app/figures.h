// The pictures of a run, as Vega specs (app/plot/vega.h draws them: SVG in
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
// plot/vega_spec.h's blocks; this file chooses and orders them and writes them.
#pragma once

#include <chrono>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "app/pipeline.h"
#include "app/plot/vega.h"
#include "app/plot/vega_spec.h"

namespace rtscalib::app {

// Each figure but the uncertainty maps', in their order, handed to `made`
// as soon as it is made (the run draws it while the next are made, and
// before the maps are computed). `history` = report.json's "history" array
// (earlier runs, oldest first).
void MakeFigures(const PipelineResult& result, const nlohmann::json& history,
                 const std::function<void(Figure)>& made);
// The uncertainty maps' figures, which come last.
std::vector<Figure> MakeUncertaintyFigures(const PipelineResult& result);
// Every figure, all at once.
std::vector<Figure> MakeFigures(const PipelineResult& result, const nlohmann::json& history);

// The files of figures handed over one at a time (Add), drawn while the
// next ones are made: <dir>/<name>.vg.json, <name>.svg and, when librsvg
// is installed (app/plot/vega.h), <name>.png for each figure, written as
// soon as the figure is drawn. `renderer`: one started
// earlier (the run starts its own when it has read its config, app/plot/vega.h),
// else one is started here.
class FigureFiles {
 public:
  FigureFiles(std::string dir, VegaRenderer* renderer = nullptr);
  // Ends the drawing (End) and waits for it when Finish did not.
  ~FigureFiles();
  FigureFiles(const FigureFiles&) = delete;
  FigureFiles& operator=(const FigureFiles&) = delete;

  // Figure `index` of the figures' order (report.json, report.html); the
  // figures are drawn in the order they are added.
  void Add(size_t index, Figure figure);
  // No more figures come (Finish says it too).
  void End();
  // Waits for the drawing; the names of the files written per figure (by
  // index) and, in *note, why a PNG was not written ("" when every one
  // was). *figures: the figures by index. Once.
  std::vector<std::vector<std::string>> Finish(std::string* note, std::vector<Figure>* figures);
  // When the last PNG was drawn (after Finish).
  std::chrono::steady_clock::time_point drawn_at() const { return drawn_at_; }

 private:
  void Write(size_t index, const RenderedFigure* drawn);

  std::string dir_;
  std::unique_ptr<VegaRenderer> own_;
  VegaRenderer* renderer_;
  std::mutex mutex_;  // guards figures_ and spec_written_
  std::map<size_t, std::pair<Figure, std::string>> figures_;  // the figure, its spec's text
  std::set<size_t> spec_written_;
  std::string note_;
  std::chrono::steady_clock::time_point drawn_at_;
  std::future<std::vector<RenderedFigure>> drawing_;
};

// FigureFiles of `figures` (by index), the largest first.
std::vector<std::vector<std::string>> WriteFigureFiles(const std::vector<Figure>& figures,
                                                       const std::string& dir, std::string* note,
                                                       VegaRenderer* renderer = nullptr);

}  // namespace rtscalib::app

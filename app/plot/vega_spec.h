// The building blocks of the run's figures as Vega 5 specs (app/plot/vega.h draws
// them): a figure record, the chart with its title, linear scales, axes,
// marks, grid layouts, tooltips, lines per series, image-shaped panels with
// their pixel scales, residual arrows and the reference arrow. Every figure
// file (residual_figures.h, photo_figure.h, ladder_figures.h,
// heat_map_figures.h) composes its specs from these; axes, ticks, legends
// and colour schemes are Vega's.
#pragma once

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "libcalib/diagnose/residuals.h"

namespace rtscalib::app {

struct Figure {
  std::string name;     // file stem: figures/<name>.vg.json, .svg, .png
  std::string section;  // "ladder", "maps", "image", "photos", "variables", ...
  std::string title;
  std::string caption;
  nlohmann::json spec;     // Vega 5
  nlohmann::json summary;  // what report.json says of the figure
};

// Units the figures show angles in.
constexpr double kDegPerRad = 180.0 / M_PI;
constexpr double kArcsecPerRad = 180.0 * 3600.0 / M_PI;
// Display size of an image-shaped panel (the longer side), in SVG pixels.
constexpr int kImagePanel = 640;
// Size of the small panels of a figure with several (variables, histograms,
// ladder), in SVG pixels. The scales of a panel (a group mark) map to it.
constexpr int kPanelW = 260, kPanelH = 170;

// 1, 2 or 5 times a power of ten, at least x: the length a reference arrow
// stands for.
double NiceAbove(double x);
// The q-quantile of `v` (nearest rank), 0 for none.
double Percentile(std::vector<double> v, double q);
// A row the fit used (ResidualStatus::kFitted).
bool Fitted(const ObservationResidual& o);

// A Vega spec with its title; the rest is added by each figure.
nlohmann::json Chart(const std::string& title, const std::string& subtitle);
nlohmann::json Linear(const std::string& name, const nlohmann::json& domain,
                      const nlohmann::json& range, bool nice = false, bool zero = false);
nlohmann::json Axis(const std::string& orient, const std::string& scale, const std::string& title);
// A mark of `type` drawn from `data` ("" for one item) with its `enter`
// encoding.
nlohmann::json Mark(const std::string& type, const std::string& data, nlohmann::json enter);
// Panels (group marks) on a grid of `columns`, aligned by their plot areas
// ("flush": the axes and titles go into the padding between them).
nlohmann::json Grid(size_t columns, int row_padding, int column_padding);
// A tooltip: Vega's tooltip handler shows "key: value" per entry.
nlohmann::json Tip(const std::vector<std::pair<std::string, std::string>>& entries);
nlohmann::json Field(const std::string& scale, const std::string& field);
// A line through (x, y) per series of `data` (grouped by `by`, coloured by
// the ordinal scale `colour`), with a dot and `tooltip` on each point.
nlohmann::json SeriesLines(const std::string& data, const std::string& by,
                           const std::string& colour, const std::string& x, const std::string& y,
                           double width, double dot, const nlohmann::json& tooltip,
                           nlohmann::json extra_marks = nlohmann::json::array());

// A panel over the image part [u0, u1] x [v0, v1] (pixel coordinates:
// u right, v down, SPEC 2), kImagePanel display pixels on its longer side;
// `w`, `h` its display size.
struct ImageBox {
  double u0, u1, v0, v1;
};
void ImageScales(nlohmann::json* spec, const ImageBox& box, int* w, int* h);
// The whole image.
void ImageScales(nlohmann::json* spec, int width, int height, int* w, int* h);
// Arrow marks over an image: a rule from (u, v) to (tip_u, tip_v) and a
// wedge at the tip, both from `data`; `tooltip` on both.
void Arrows(nlohmann::json* marks, const std::string& data, const std::string& colour,
            const nlohmann::json& tooltip);
// The reference arrow of a figure, above the panel's top right corner:
// `length` display pixels, labelled with the residual it stands for.
void ScaleBar(nlohmann::json* marks, double length, const std::string& text, int w);

}  // namespace rtscalib::app

// The figures' SVG files, drawn from their Vega specs in this process.
//
// report.html draws each figure with Vega itself (app/plot/vega.h: the browser
// runs the spec). The files beside it (figures/<name>.svg, and the PNG that
// librsvg draws from the SVG, svg_raster.h) are drawn here from the same
// spec, by the same rules: the same scales (d3's linear, sqrt, log, point
// and ordinal scales with Vega's defaults: zero, nice, clamp), the same tick
// values and labels (d3-array's ticks, Vega's log-tick filter, d3-format),
// the same symbol shapes and colour schemes, Vega's guide defaults (tick
// size 5, label padding 2, legend offset 18, gradient 200 x 16, title
// offset and subtitle padding) and its grid layout of panels. A figure is
// therefore the same picture of the same numbers in both; only the text
// metrics differ a little (here a width table of DejaVu Sans, the font
// librsvg draws with; in the browser its own fonts).
//
// Only the part of Vega that rtscalib's figures use is drawn (vega_spec.h's
// blocks: data values and filters, facets, group panels on a grid, rect,
// rule, symbol, line, area, text and image marks, axes, symbol and
// gradient legends, titles). A spec outside it is refused with a
// vega::SubsetError naming the part, never drawn wrong; the tests draw every
// figure of the runs they make, so a new figure that needs more fails there.
//
// Why not Vega itself, headless in node: node's start and Vega's dataflow
// cost several times the whole calibration of a camera on a bench, where a
// figure drawn here takes about half a millisecond (figures_benchmark's
// BM_BenchFiguresSvg).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "app/plot/vega_expression.h"

namespace rtscalib::app::vega {

// The SVG of `spec` (a Vega 5 spec of the subset above), sized as Vega's
// "pad" autosize sizes it: the content and the spec's padding around it.
// Throws SubsetError naming what is outside the subset.
std::string DrawSvg(const nlohmann::json& spec);

// The advance width of `text` in DejaVu Sans at `size` px (bold or book).
double TextWidth(const std::string& text, double size, bool bold);

}  // namespace rtscalib::app::vega

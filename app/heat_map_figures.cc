#include "app/heat_map_figures.h"

#include "libcalib/text/number_text.h"

namespace rtscalib::app {

using nlohmann::json;

json HeatMapSpec(const std::string& title, const std::string& subtitle, int width, int height,
                 int cols, int rows, const std::vector<double>& value,
                 const std::vector<unsigned char>& inside, const std::string& legend,
                 const std::vector<Eigen::Vector2d>& hull, ColourScale colours) {
  json spec = Chart(title, subtitle);
  int w = 0, h = 0;
  ImageScales(&spec, width, height, &w, &h);
  json cells = json::array();
  for (int j = 0; j < rows; ++j) {
    for (int i = 0; i < cols; ++i) {
      const double v = value[j * cols + i];
      json c = {{"u0", i * width / double(cols) - 0.5},
                {"u1", (i + 1) * width / double(cols) - 0.5},
                {"v0", j * height / double(rows) - 0.5},
                {"v1", (j + 1) * height / double(rows) - 0.5},
                {"inside", bool(inside[j * cols + i])}};
      c["value"] = std::isfinite(v) ? json(v) : json(nullptr);
      cells.push_back(c);
    }
  }
  spec["data"].push_back({{"name", "cells"}, {"values", cells}});
  json colour = {{"name", "colour"},
                 {"type", colours == ColourScale::kLog ? "log" : "linear"},
                 {"scheme", "viridis"},
                 {"domain", {{"data", "cells"}, {"field", "value"}}},
                 {"nice", true}};
  if (colours == ColourScale::kLinear) colour["zero"] = true;
  spec["scales"].push_back(colour);
  spec["legends"].push_back({{"fill", "colour"}, {"title", legend}, {"type", "gradient"}});
  const json tip =
      Tip({{"u", "format((datum.u0 + datum.u1) / 2, '.0f')"},
           {"v", "format((datum.v0 + datum.v1) / 2, '.0f')"},
           {legend, "datum.value === null ? 'not predictable' : format(datum.value, '.3g')"},
           {"inside the points' hull", "datum.inside"}});
  spec["marks"].push_back(Mark(
      "rect", "cells",
      {{"x", Field("u", "u0")},
       {"x2", Field("u", "u1")},
       {"y", Field("v", "v0")},
       {"y2", Field("v", "v1")},
       {"fill", {{"signal", "datum.value === null ? '#bbbbbb' : scale('colour', datum.value)"}}},
       // fillOpacity, not opacity (the same picture: the cells have no
       // stroke): an element's opacity makes librsvg draw it on a layer of
       // its own, a third of the PNG's time with a few hundred cells.
       {"fillOpacity", {{"signal", "datum.inside ? 1 : 0.55"}}},
       {"tooltip", tip}}));
  spec["data"].push_back({{"name", "outside"},
                          {"source", "cells"},
                          {"transform", {{{"type", "filter"}, {"expr", "!datum.inside"}}}}});
  spec["marks"].push_back(Mark("rule", "outside",
                               {{"x", Field("u", "u0")},
                                {"y", Field("v", "v1")},
                                {"x2", Field("u", "u1")},
                                {"y2", Field("v", "v0")},
                                {"stroke", {{"value", "white"}}},
                                {"strokeOpacity", {{"value", 0.8}}}}));
  if (hull.size() >= 3) {
    json pts = json::array();
    for (size_t k = 0; k <= hull.size(); ++k) {
      const Eigen::Vector2d& p = hull[k % hull.size()];
      pts.push_back({{"k", k}, {"u", p.x()}, {"v", p.y()}});
    }
    spec["data"].push_back({{"name", "hull"}, {"values", pts}});
    spec["marks"].push_back(Mark("line", "hull",
                                 {{"x", Field("u", "u")},
                                  {"y", Field("v", "v")},
                                  {"stroke", {{"value", "white"}}},
                                  {"strokeWidth", {{"value", 2}}}}));
  }
  return spec;
}

Figure UncertaintyFigure(const UncertaintyMap& m, const UncertaintyMapOptions& o,
                         const CameraTool& cam, bool full) {
  Figure f;
  f.name = "uncertainty_zoom" + std::to_string(m.zoom);
  f.section = "uncertainty";
  f.title = "Projection uncertainty, zoom " + std::to_string(m.zoom) + ", " +
            (m.up_to_rotation ? std::string("up to the camera's rotation")
                              : "point at " + Significant(o.range_m, 3) + " m");
  f.spec = HeatMapSpec(
      f.title,
      "1 sigma, worst direction [px]: min " + Significant(m.min_px, 3) + ", median " +
          Significant(m.median_px, 3) + ", max " + Significant(m.max_px, 3) + "; " +
          (m.up_to_rotation ? std::string("a camera on its own")
                            : "pointing phi " + Significant(o.phi, 4) + ", theta " +
                                  Significant(o.theta, 4) + " rad") +
          "; " + (full ? "full covariance" : "diagonal approximation (no full covariance)") +
          "; faded and struck through: outside the points' hull (white)",
      m.width, m.height, m.cols, m.rows, m.sigma_px,
      std::vector<unsigned char>(m.inside.begin(), m.inside.end()), "1-sigma [px]",
      cam.valid_region, ColourScale::kLog);
  f.caption =
      "How far (1 sigma, worst direction, pixels) the pixel where " + MapSubject(m, o) +
      " is seen may lie from the model's prediction, from the uncertainty of this zoom's " +
      (m.up_to_rotation
           ? std::string("intrinsics and distortion, less what a turn of the camera undoes: a "
                         "camera on its own has no frame but its own, and whatever it is used "
                         "with (a pose from solvePnP, a board) carries that turn, as in mrcal's "
                         "projection uncertainty")
           : std::string("intrinsics, distortion and camera tool and of the kinematic chain")) +
      " (first order, J P J^T with the fit's full covariance). Cells outside the convex hull of "
      "the calibration's image points (white outline) are faded and struck through: there the "
      "distortion is extrapolated and the number is a lower bound at best.";
  f.summary = {{"zoom", m.zoom}, {"max_px", m.max_px}, {"median_px", m.median_px}};
  return f;
}

Figure DifferenceFigure(const ZoomDifference& d) {
  Figure f;
  f.name = "compare_zoom" + std::to_string(d.zoom);
  f.section = "compare";
  f.title = "Projection difference, zoom " + std::to_string(d.zoom);
  f.spec = HeatMapSpec(f.title,
                       "RMS " + Significant(d.rms_px, 3) + ", max " + Significant(d.max_px, 3) +
                           " px; rotation removed " + Significant(d.rotation_rad * kArcsecPerRad, 3) +
                           "\"; " + std::to_string(d.width) + " x " + std::to_string(d.height) +
                           " px (first model's image); faded: outside either model's valid region",
                       d.width, d.height, d.cols, d.rows, d.diff_px,
                       std::vector<unsigned char>(d.inside.begin(), d.inside.end()),
                       "difference [px]", {});
  f.caption =
      "How far apart the two models project one ray, after the best rotation between "
      "their camera frames is removed (docs/compare.md).";
  f.summary = {{"zoom", d.zoom}, {"rms_px", d.rms_px}, {"max_px", d.max_px}};
  return f;
}

}  // namespace rtscalib::app

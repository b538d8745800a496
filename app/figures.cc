#include "app/figures.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <functional>
#include <future>
#include <iomanip>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>
#include <string_view>
#include <tuple>

#include "app/report_html.h"
#include "app/vega.h"
#include "libcalib/diagnose/statistics.h"
#include "libcalib/eval/error_measures.h"
#include "libcalib/io/safe_write.h"
#include "libcalib/text/number_text.h"

namespace rtscalib::app {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr double kDeg = 180.0 / M_PI;
constexpr double kArcsec = 180.0 * 3600.0 / M_PI;
// Display size of an image-shaped panel (the longer side), in SVG pixels.
constexpr int kImagePanel = 640;
// Size of the small panels of a figure with several (variables, histograms,
// ladder), in SVG pixels. The scales of a panel (a group mark) map to it.
constexpr int kPanelW = 260, kPanelH = 170;
// Photos shown per zoom, worst first (rms of their fitted corners).
constexpr int kWorstPhotosPerZoom = 2;

// 1, 2 or 5 times a power of ten, at least x: the length a reference arrow
// stands for.
double NiceAbove(double x) {
  if (!(x > 0) || !std::isfinite(x)) return 1.0;
  const double mag = std::pow(10.0, std::floor(std::log10(x)));
  for (double m : {1.0, 2.0, 5.0}) {
    if (m * mag >= x * (1 - 1e-12)) return m * mag;
  }
  return 10 * mag;
}

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1) + 0.5))];
}

bool Fitted(const ObservationResidual& o) { return o.status == ResidualStatus::kFitted; }

// A Vega spec with its title; the rest is added by each figure.
json Chart(const std::string& title, const std::string& subtitle) {
  // One line per clause: a figure is as wide as its panels, not its text.
  json lines = json::array();
  size_t from = 0;
  for (size_t at = subtitle.find("; ");; at = subtitle.find("; ", from)) {
    lines.push_back(subtitle.substr(from, at == std::string::npos ? std::string::npos : at - from));
    if (at == std::string::npos) break;
    from = at + 2;
  }
  return {{"$schema", "https://vega.github.io/schema/vega/v5.json"},
          {"background", "white"},
          {"padding", 10},
          {"autosize", "pad"},
          {"title",
           {{"text", title},
            {"subtitle", lines},
            {"anchor", "start"},
            {"fontSize", 14},
            {"subtitleFontSize", 11},
            {"offset", 12}}},
          {"data", json::array()},
          {"scales", json::array()},
          {"axes", json::array()},
          {"legends", json::array()},
          {"marks", json::array()}};
}

json Linear(const std::string& name, const json& domain, const json& range, bool nice = false,
            bool zero = false) {
  return {{"name", name},   {"type", "linear"}, {"domain", domain},
          {"range", range}, {"nice", nice},     {"zero", zero}};
}

json Axis(const std::string& orient, const std::string& scale, const std::string& title) {
  return {{"orient", orient},
          {"scale", scale},
          {"title", title},
          {"labelFontSize", 10},
          {"titleFontSize", 11}};
}

// A mark of `type` drawn from `data` ("" for one item) with its `enter`
// encoding.
json Mark(const std::string& type, const std::string& data, json enter) {
  json m = {{"type", type}, {"encode", {{"enter", std::move(enter)}}}};
  if (!data.empty()) m["from"] = {{"data", data}};
  return m;
}

// Panels (group marks) on a grid of `columns`, aligned by their plot areas
// ("flush": the axes and titles go into the padding between them).
json Grid(size_t columns, int row_padding, int column_padding) {
  return {{"columns", columns},
          {"align", "all"},
          {"bounds", "flush"},
          {"padding", {{"row", row_padding}, {"column", column_padding}}}};
}

// A tooltip: Vega's tooltip handler shows "key: value" per entry.
json Tip(const std::vector<std::pair<std::string, std::string>>& entries) {
  std::string s = "{";
  for (size_t i = 0; i < entries.size(); ++i) {
    std::string key;
    for (char c : entries[i].first) key += c == '\'' ? std::string("\\'") : std::string(1, c);
    s += (i ? ", '" : "'") + key + "': " + entries[i].second;
  }
  return {{"signal", s + "}"}};
}

json Field(const std::string& scale, const std::string& field) {
  return {{"scale", scale}, {"field", field}};
}

// A line through (x, y) per series of `data` (grouped by `by`, coloured by
// the ordinal scale `colour`), with a dot and `tooltip` on each point.
json SeriesLines(const std::string& data, const std::string& by, const std::string& colour,
                 const std::string& x, const std::string& y, double width, double dot,
                 const json& tooltip, json extra_marks = json::array()) {
  const std::string each = data + "_series";
  json marks = std::move(extra_marks);
  for (json& m : marks) m["from"] = {{"data", each}};
  marks.push_back(Mark("line", each,
                       {{"x", Field("x", x)},
                        {"y", Field("y", y)},
                        {"stroke", Field(colour, by)},
                        {"strokeWidth", {{"value", width}}}}));
  marks.push_back(Mark("symbol", each,
                       {{"x", Field("x", x)},
                        {"y", Field("y", y)},
                        {"fill", Field(colour, by)},
                        {"size", {{"value", dot}}},
                        {"tooltip", tooltip}}));
  return {{"type", "group"},
          {"from", {{"facet", {{"name", each}, {"data", data}, {"groupby", by}}}}},
          {"marks", marks}};
}

// A panel over the image part [u0, u1] x [v0, v1] (pixel coordinates:
// u right, v down, SPEC 2), kImagePanel display pixels on its longer side;
// `w`, `h` its display size.
struct ImageBox {
  double u0, u1, v0, v1;
};
void ImageScales(json* spec, const ImageBox& box, int* w, int* h) {
  const double s = kImagePanel / std::max(box.u1 - box.u0, box.v1 - box.v0);
  *w = static_cast<int>(std::lround((box.u1 - box.u0) * s));
  *h = static_cast<int>(std::lround((box.v1 - box.v0) * s));
  (*spec)["width"] = *w;
  (*spec)["height"] = *h;
  (*spec)["scales"].push_back(Linear("u", {box.u0, box.u1}, {0, *w}));
  (*spec)["scales"].push_back(Linear("v", {box.v0, box.v1}, {0, *h}));
  json ax = Axis("bottom", "u", "u [px]");
  ax["tickCount"] = 8;
  (*spec)["axes"].push_back(ax);
  json ay = Axis("left", "v", "v [px]");
  ay["tickCount"] = 6;
  (*spec)["axes"].push_back(ay);
}
// The whole image.
void ImageScales(json* spec, int width, int height, int* w, int* h) {
  ImageScales(spec, {-0.5, width - 0.5, -0.5, height - 0.5}, w, h);
}

// Arrow marks over an image: a rule from (u, v) to (tip_u, tip_v) and a
// wedge at the tip, both from `data`; `tooltip` on both.
void Arrows(json* marks, const std::string& data, const std::string& colour, const json& tooltip) {
  marks->push_back(Mark("rule", data,
                        {{"x", Field("u", "u")},
                         {"y", Field("v", "v")},
                         {"x2", Field("u", "tip_u")},
                         {"y2", Field("v", "tip_v")},
                         {"stroke", {{"value", colour}}},
                         {"strokeWidth", {{"value", 1.6}}},
                         {"tooltip", tooltip}}));
  marks->push_back(Mark("symbol", data,
                        {{"x", Field("u", "tip_u")},
                         {"y", Field("v", "tip_v")},
                         {"shape", {{"value", "wedge"}}},
                         {"angle", {{"field", "angle"}}},
                         {"size", {{"value", 40}}},
                         {"fill", {{"value", colour}}},
                         {"tooltip", tooltip}}));
}

// The reference arrow of a figure, above the panel's top right corner:
// `length` display pixels, labelled with the residual it stands for.
void ScaleBar(json* marks, double length, const std::string& text, int w) {
  marks->push_back(Mark("rule", "",
                        {{"x", {{"value", w - length}}},
                         {"x2", {{"value", w}}},
                         {"y", {{"value", -8}}},
                         {"stroke", {{"value", "#c0392b"}}},
                         {"strokeWidth", {{"value", 2}}}}));
  marks->push_back(Mark("symbol", "",
                        {{"x", {{"value", w}}},
                         {"y", {{"value", -8}}},
                         {"shape", {{"value", "wedge"}}},
                         {"angle", {{"value", 90}}},
                         {"size", {{"value", 40}}},
                         {"fill", {{"value", "#c0392b"}}}}));
  marks->push_back(Mark("text", "",
                        {{"x", {{"value", w - length - 6}}},
                         {"y", {{"value", -8}}},
                         {"align", {{"value", "right"}}},
                         {"baseline", {{"value", "middle"}}},
                         {"fontSize", {{"value", 11}}},
                         {"text", {{"value", text}}}}));
}

// ---------------------------------------------------------------------------
// Error maps: rms of |observed - model| per pointing and face.

struct MapSource {
  std::string key, title, unit;
  double scale = 1;  // to the unit shown
  ObsGroup group = ObsGroup::kEdm;
  int zoom = 0;
};

Figure ErrorMap(const MapSource& src, const std::vector<ObservationResidual>& rows,
                const std::set<int>& faces, const FitOptions& fit, const std::string& model) {
  std::map<std::tuple<int, double, double>, std::pair<double, int>> cells;
  std::map<int, std::set<long>> phis, thetas;
  for (const ObservationResidual& o : rows) {
    // Fitted and critical-region rows: the map shows where the model fails,
    // in the critical regions too (shaded).
    if (!o.valid || o.status == ResidualStatus::kGrossError || o.group != src.group ||
        (src.group != ObsGroup::kEdm && o.zoom != src.zoom))
      continue;
    const double phi = std::fmod(std::fmod(o.phi * kDeg, 360.0) + 360.0, 360.0);
    auto& c = cells[{o.face, phi, o.theta * kDeg}];
    c.first += o.size * o.size;
    ++c.second;
    phis[o.face].insert(std::lround(phi * 100));
    thetas[o.face].insert(std::lround(o.theta * kDeg * 100));
  }
  json values = json::array();
  std::vector<double> rms;
  for (const auto& [k, c] : cells) {
    const double v = std::sqrt(c.first / c.second) * src.scale;
    rms.push_back(v);
    values.push_back({{"face", std::get<0>(k)},
                      {"phi", std::get<1>(k)},
                      {"theta", std::get<2>(k)},
                      {"rms", v},
                      {"n", c.second}});
  }
  const double vmax = std::max(Percentile(rms, 0.98), 1e-12);
  json spec = Chart(src.title + ": rms error per pointing [" + src.unit + "]",
                    "model " + model +
                        "; grey bands: critical regions (not fitted); one colour scale for both "
                        "faces; cells beyond the scale outlined red");
  spec["data"].push_back({{"name", "cells"}, {"values", values}});
  spec["scales"].push_back({{"name", "colour"},
                            {"type", "linear"},
                            {"scheme", "viridis"},
                            {"domain", {0, vmax}},
                            {"clamp", true},
                            {"nice", true}});
  spec["legends"].push_back(
      {{"fill", "colour"}, {"title", "rms [" + src.unit + "]"}, {"type", "gradient"}});
  spec["layout"] = Grid(faces.size(), 60, 90);
  const int w = 420, h = 280;
  const double zmin = fit.critical_region.min_zenith_rad * kDeg;
  const double zmax = fit.critical_region.max_zenith_rad * kDeg;
  for (int face : faces) {
    const std::string data = "face" + std::to_string(face);
    spec["data"].push_back(
        {{"name", data},
         {"source", "cells"},
         {"transform", {{{"type", "filter"}, {"expr", "datum.face == " + std::to_string(face)}}}}});
    const int cw = std::clamp(w / std::max<int>(phis[face].size(), 8), 6, 28);
    const int ch = std::clamp(h / std::max<int>(thetas[face].size(), 6), 6, 28);
    // Readings of this face (SPEC 1): face 2's zenith angle z is read 360 - z;
    // zenith at the top in both.
    const json domain = face == 1 ? json{0, 180} : json{360, 180};
    const json bands = face == 1
                           ? json{{{"a", 0}, {"b", zmin}}, {{"a", zmax}, {"b", 180}}}
                           : json{{{"a", 360 - zmin}, {"b", 360}}, {{"a", 180}, {"b", 360 - zmax}}};
    json ay = Axis("left", "y", "theta [deg] (zenith at the top)");
    json ax = Axis("bottom", "x", "phi [deg]");
    ax["values"] = {0, 45, 90, 135, 180, 225, 270, 315, 360};
    json group = {
        {"type", "group"},
        {"title", {{"text", "face " + std::to_string(face)}, {"fontSize", 12}}},
        {"encode",
         {{"enter",
           {{"width", {{"value", w}}},
            {"height", {{"value", h}}},
            {"stroke", {{"value", "#888"}}}}}}},
        {"data", {{{"name", "bands"}, {"values", bands}}}},
        {"scales", {Linear("x", {0, 360}, {0, w}), Linear("y", domain, {0, h})}},
        {"axes", {ax, ay}},
        {"marks",
         {Mark("rect", "bands",
               {{"x", {{"value", 0}}},
                {"x2", {{"value", w}}},
                {"y", Field("y", "a")},
                {"y2", Field("y", "b")},
                {"fill", {{"value", "#dddddd"}}}}),
          Mark("rect", data,
               {{"xc", Field("x", "phi")},
                {"yc", Field("y", "theta")},
                {"width", {{"value", cw}}},
                {"height", {{"value", ch}}},
                {"fill", Field("colour", "rms")},
                {"stroke",
                 {{"signal", "datum.rms > " + std::to_string(vmax) + " ? '#d62728' : null"}}},
                {"tooltip", Tip({{"face", "datum.face"},
                                 {"phi [deg]", "format(datum.phi, '.2f')"},
                                 {"theta [deg]", "format(datum.theta, '.2f')"},
                                 {"rms [" + src.unit + "]", "format(datum.rms, '.3g')"},
                                 {"observations", "datum.n"}})}})}}};
    spec["marks"].push_back(group);
  }
  Figure f;
  f.name = "error_map_" + src.key;
  f.section = "maps";
  f.title = src.title;
  f.caption = "Root mean square of the observed-minus-model error (" + src.unit +
              ") at each pointing, from the residual table at the final model (boards and points "
              "of unknown position at their estimates), for the fitted rows and the critical "
              "regions (grey, not fitted); gross errors are left out.";
  f.spec = spec;
  f.summary = {{"pointings", cells.size()}, {"colour_max", vmax}, {"unit", src.unit}};
  return f;
}

// ---------------------------------------------------------------------------
// Image residuals per zoom: the fitted pixel rows binned over the image.

// Photos a cell needs before its mean is tested (the 2 x 2 scatter of fewer
// is too rough for the chi-square below).
constexpr int kStructureMinPhotos = 10;
// Family-wise level of the cells' tests: "structure" is a cell mean that
// fewer than 1 % of noise-only images would show anywhere.
constexpr double kStructureLevel = 0.01;

Figure ImageResiduals(int zoom, const CameraTool& cam,
                      const std::vector<ObservationResidual>& rows) {
  const int nx = 16;
  const int ny = std::max(1, static_cast<int>(std::lround(nx * double(cam.height) / cam.width)));
  struct Cell {
    double du = 0, dv = 0;
    int n = 0;
    // Per photo (a camera record: on its own) the sum of its residuals here.
    std::map<std::string, std::pair<Eigen::Vector2d, int>> photos;
  };
  std::vector<Cell> cells(nx * ny);
  double ss = 0;
  int n = 0, records = 0;
  for (const ObservationResidual& o : rows) {
    // Fitted image observations: pixels and camera records of this zoom.
    if (!Fitted(o) || o.group == ObsGroup::kEdm || o.zoom != zoom ||
        !std::isfinite(o.image_delta.x()))
      continue;
    const int i = std::clamp(static_cast<int>((o.u + 0.5) / cam.width * nx), 0, nx - 1);
    const int j = std::clamp(static_cast<int>((o.v + 0.5) / cam.height * ny), 0, ny - 1);
    Cell& c = cells[j * nx + i];
    c.du += o.image_delta.x();
    c.dv += o.image_delta.y();
    ++c.n;
    const std::string photo = o.shot.empty() ? "record " + std::to_string(o.index) : o.shot;
    auto& sum = c.photos.try_emplace(photo, Eigen::Vector2d::Zero(), 0).first->second;
    sum.first += o.image_delta;
    ++sum.second;
    ss += o.image_delta.squaredNorm();
    ++n;
    records += o.group == ObsGroup::kCam;
  }
  const double rms = n ? std::sqrt(ss / n) : 0;
  // Structure: a cell whose mean residual the scatter of its photos does
  // not explain. A photo's points in one cell share its errors (its pose,
  // its detection), so the photos are the independent samples: with m_p
  // each photo's mean residual in the cell (P photos), m their mean and S
  // their 2 x 2 scatter, Hotelling's T^2 = P m' S^-1 m against chi^2 with 2
  // degrees of freedom at kStructureLevel over the cells tested
  // (Bonferroni). A lens term the model lacks, a bent board or a detector's
  // bias there shows as a mean no photo-to-photo scatter gives.
  int tested = 0;
  for (const Cell& c : cells) tested += static_cast<int>(c.photos.size()) >= kStructureMinPhotos;
  const double critical = tested ? ChiSquareCritical(kStructureLevel / tested, 2) : 0;
  std::vector<double> lengths;
  for (const Cell& c : cells) {
    if (c.n) lengths.push_back(std::hypot(c.du / c.n, c.dv / c.n));
  }
  // The reference arrow: a round residual near the longest cell means (the
  // 90th percentile, so that one cell of few points does not set it), drawn
  // 0.9 cell widths long; a longer arrow is cut at the cell's width.
  const double reference_px = NiceAbove(Percentile(lengths, 0.9));
  const double cell_w = double(cam.width) / nx;
  const double gain = 0.9 * cell_w / reference_px;
  json values = json::array();
  int significant = 0, with_points = 0, cut = 0;
  double max_significant = 0, max_u = 0, max_v = 0;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const Cell& c = cells[j * nx + i];
      const double u0 = i * cam.width / double(nx) - 0.5,
                   u1 = (i + 1) * cam.width / double(nx) - 0.5;
      const double v0 = j * cam.height / double(ny) - 0.5,
                   v1 = (j + 1) * cam.height / double(ny) - 0.5;
      json cell = {{"i", i}, {"j", j}, {"u0", u0}, {"u1", u1}, {"v0", v0}, {"v1", v1}, {"n", c.n}};
      if (c.n) {
        ++with_points;
        const double du = c.du / c.n, dv = c.dv / c.n;
        const double u = 0.5 * (u0 + u1), v = 0.5 * (v0 + v1);
        double t2 = 0;
        const int photos = static_cast<int>(c.photos.size());
        if (photos >= kStructureMinPhotos) {
          Eigen::Vector2d m = Eigen::Vector2d::Zero();
          for (const auto& [name, sum] : c.photos) m += sum.first / sum.second;
          m /= photos;
          Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
          for (const auto& [name, sum] : c.photos) {
            const Eigen::Vector2d e = sum.first / sum.second - m;
            scatter += e * e.transpose() / (photos - 1.0);
          }
          if (scatter.determinant() > 0) t2 = photos * m.dot(scatter.inverse() * m);
        }
        const bool structure = photos >= kStructureMinPhotos && t2 > critical;
        const double length = std::hypot(du, dv);
        if (structure) {
          ++significant;
          if (length > max_significant) {
            max_significant = length;
            max_u = u;
            max_v = v;
          }
        }
        // Drawn at most a cell's width long.
        const double drawn = std::min(gain, length > 0 ? cell_w / length : gain);
        cut += drawn < gain;
        cell.update({{"du", du},
                     {"dv", dv},
                     {"u", u},
                     {"v", v},
                     {"tip_u", u + drawn * du},
                     {"tip_v", v + drawn * dv},
                     {"angle", std::atan2(du, -dv) * kDeg},
                     {"t2", t2},
                     {"structure", structure}});
      }
      values.push_back(cell);
    }
  }
  std::string subtitle =
      std::to_string(n - records) + " fitted image points and " + std::to_string(records) +
      " camera records, rms " + Significant(rms, 3) + " px; arrow: " +
      Significant(reference_px, 3) + " px residual = " + Significant(0.9, 3) +
      " cell widths (longer ones cut at a cell's width: " + std::to_string(cut) + ")";
  std::string structure_line =
      "red: structure, a cell mean its photos' scatter does not explain (" +
      std::to_string(significant) + " of " + std::to_string(tested) + " cells of >= " +
      std::to_string(kStructureMinPhotos) + " photos";
  structure_line += significant ? "; the largest " + Significant(max_significant, 3) + " px at (" +
                                      Significant(max_u, 4) + ", " + Significant(max_v, 4) + ")"
                                : "";
  structure_line += "); grey: noise; blue line: where the points lie";
  json spec = Chart("Image residuals, zoom " + std::to_string(zoom) +
                        ": mean observed - predicted pixel per cell",
                    subtitle + "; " + structure_line);
  int w = 0, h = 0;
  ImageScales(&spec, cam.width, cam.height, &w, &h);
  spec["data"].push_back({{"name", "cells"}, {"values", values}});
  spec["data"].push_back({{"name", "arrows"},
                          {"source", "cells"},
                          {"transform", {{{"type", "filter"}, {"expr", "datum.n > 0"}}}}});
  spec["data"].push_back({{"name", "structure"},
                          {"source", "cells"},
                          {"transform", {{{"type", "filter"}, {"expr", "datum.structure"}}}}});
  spec["data"].push_back({{"name", "noise"},
                          {"source", "cells"},
                          {"transform", {{{"type", "filter"},
                                          {"expr", "datum.n > 0 && !datum.structure"}}}}});
  spec["scales"].push_back({{"name", "count"},
                            {"type", "sqrt"},
                            {"domain", {{"data", "cells"}, {"field", "n"}}},
                            {"zero", true},
                            {"range", {"#ffffff", "#dbe6f0"}}});
  json& marks = spec["marks"];
  const json tip = Tip({{"cell", "datum.i + ', ' + datum.j"},
                        {"points", "datum.n"},
                        {"mean du [px]", "format(datum.du, '.4f')"},
                        {"mean dv [px]", "format(datum.dv, '.4f')"},
                        {"T^2 of the mean", "format(datum.t2, '.1f')"}});
  marks.push_back(Mark("rect", "cells",
                       {{"x", Field("u", "u0")},
                        {"x2", Field("u", "u1")},
                        {"y", Field("v", "v0")},
                        {"y2", Field("v", "v1")},
                        {"fill", Field("count", "n")},
                        {"stroke", {{"value", "#e4e4e4"}}},
                        {"tooltip", tip}}));
  // The corner ninths of the image: the distortion needs points there.
  json ninths = json::array();
  for (int k = 1; k < 3; ++k) {
    ninths.push_back({{"u0", k * cam.width / 3.0 - 0.5},
                      {"u1", k * cam.width / 3.0 - 0.5},
                      {"v0", -0.5},
                      {"v1", cam.height - 0.5}});
    ninths.push_back({{"u0", -0.5},
                      {"u1", cam.width - 0.5},
                      {"v0", k * cam.height / 3.0 - 0.5},
                      {"v1", k * cam.height / 3.0 - 0.5}});
  }
  spec["data"].push_back({{"name", "ninths"}, {"values", ninths}});
  marks.push_back(Mark("rule", "ninths",
                       {{"x", Field("u", "u0")},
                        {"x2", Field("u", "u1")},
                        {"y", Field("v", "v0")},
                        {"y2", Field("v", "v1")},
                        {"stroke", {{"value", "#999"}}},
                        {"strokeDash", {{"value", {4, 4}}}}}));
  // Where the points lie (the camera's valid region, the convex hull of the
  // calibration's points): outside it the model is extrapolated.
  if (cam.valid_region.size() >= 3) {
    json hull = json::array();
    for (size_t k = 0; k <= cam.valid_region.size(); ++k) {
      const Eigen::Vector2d& q = cam.valid_region[k % cam.valid_region.size()];
      hull.push_back({{"k", k}, {"u", q.x()}, {"v", q.y()}});
    }
    spec["data"].push_back({{"name", "region"}, {"values", hull}});
    marks.push_back(Mark("line", "region",
                         {{"x", Field("u", "u")},
                          {"y", Field("v", "v")},
                          {"stroke", {{"value", "#2c7fb8"}}},
                          {"strokeWidth", {{"value", 1.5}}}}));
  }
  marks.push_back(Mark("text", "arrows",
                       {{"x", {{"scale", "u"}, {"field", "u0"}, {"offset", 2}}},
                        {"y", {{"scale", "v"}, {"field", "v1"}, {"offset", -2}}},
                        {"fontSize", {{"value", 8}}},
                        {"fill", {{"value", "#555"}}},
                        {"text", {{"field", "n"}}}}));
  Arrows(&marks, "noise", "#9a9a9a", tip);
  Arrows(&marks, "structure", "#c0392b", tip);
  ScaleBar(&marks, 0.9 * cell_w * w / cam.width, Significant(reference_px, 3) + " px", w);
  Figure f;
  f.name = "image_residuals_zoom" + std::to_string(zoom);
  f.section = "image";
  f.title = "Image residuals, zoom " + std::to_string(zoom);
  f.caption =
      "The fitted image observations of this zoom (image points and camera records; residual "
      "table, final model, boards at their estimated poses), binned over the image: each arrow is "
      "the mean observed-minus-predicted pixel of its cell, drawn at the scale the reference "
      "arrow states and cut at a cell's width; the number is the cell's points. Red arrows are "
      "structure: means that the scatter of the cell's photos does not explain (Hotelling's T^2 "
      "of the photos' means against chi-square with 2 degrees of freedom, 1 % over the cells of "
      "at least " +
      std::to_string(kStructureMinPhotos) +
      " photos): a lens term the model lacks, a bent board, a detector's bias there. Grey "
      "arrows are noise. The blue line encloses the points (the camera's valid region): the "
      "model is extrapolated outside it, and empty corner ninths (dashed) leave the distortion "
      "extrapolated at the image corners.";
  f.spec = spec;
  f.summary = {{"zoom", zoom},
               {"fitted_rows", n},
               {"camera_records", records},
               {"rms_px", rms},
               {"arrow_scale_px", reference_px},
               {"cells", {nx, ny}},
               {"cells_tested", tested},
               {"structure_cells", significant},
               {"structure_max_px", max_significant},
               {"structure_max_at", {max_u, max_v}}};
  return f;
}

// ---------------------------------------------------------------------------
// A photo with its corners and residual arrows.

// The part `box` of a photo (pixels at full resolution, then at most the
// panel's size: a photo's pixels beyond what is shown only make report.html
// heavier), as a data URI; *crop: the image part it shows.
std::string PhotoDataUri(const cv::Mat& photo, const ImageBox& box, ImageBox* crop) {
  const int x0 = std::clamp(static_cast<int>(std::floor(box.u0 + 0.5)), 0, photo.cols - 1);
  const int y0 = std::clamp(static_cast<int>(std::floor(box.v0 + 0.5)), 0, photo.rows - 1);
  const int x1 = std::clamp(static_cast<int>(std::ceil(box.u1 + 0.5)), x0 + 1, photo.cols);
  const int y1 = std::clamp(static_cast<int>(std::ceil(box.v1 + 0.5)), y0 + 1, photo.rows);
  *crop = {x0 - 0.5, x1 - 0.5, y0 - 0.5, y1 - 0.5};
  cv::Mat img = photo(cv::Rect(x0, y0, x1 - x0, y1 - y0));
  const double s = static_cast<double>(kImagePanel) / std::max(img.cols, img.rows);
  if (s < 1) cv::resize(img, img, cv::Size(), s, s, cv::INTER_AREA);
  std::vector<unsigned char> jpg;
  if (!cv::imencode(".jpg", img, jpg, {cv::IMWRITE_JPEG_QUALITY, 85})) return "";
  return "data:image/jpeg;base64," + Base64(jpg);
}

}  // namespace

Figure PhotoFigure(const std::string& shot, const std::vector<ObservationResidual>& rows,
                   const std::string& image, int width, int height) {
  const cv::Mat photo = image.empty() ? cv::Mat() : cv::imread(image, cv::IMREAD_COLOR);
  if (!photo.empty()) {
    width = photo.cols;
    height = photo.rows;
  }
  std::vector<double> sizes;
  double ss = 0;
  int zoom = rows.empty() ? 0 : rows.front().zoom, fitted = 0;
  for (const ObservationResidual& o : rows) {
    if (!Fitted(o)) continue;
    sizes.push_back(o.size);
    ss += o.size * o.size;
    ++fitted;
  }
  const double rms = fitted ? std::sqrt(ss / fitted) : 0;
  // The reference arrow: a round residual near the largest (95th
  // percentile) drawn 40 image pixels long per the panel's 640.
  const double reference_px = NiceAbove(Percentile(sizes, 0.95));
  // Zoomed to the corners (a fifth of their extent around them, at least a
  // third of the image, the image's aspect), so that arrows of a fraction of
  // a pixel are seen where they are.
  double u0 = INFINITY, u1 = -INFINITY, v0 = INFINITY, v1 = -INFINITY;
  for (const ObservationResidual& o : rows) {
    u0 = std::min(u0, o.u);
    u1 = std::max(u1, o.u);
    v0 = std::min(v0, o.v);
    v1 = std::max(v1, o.v);
  }
  const double aspect = double(height) / width;
  double half_u = std::max({0.6 * (u1 - u0), 0.6 * (v1 - v0) / aspect, width / 6.0});
  half_u = std::min(half_u, width / 2.0);
  const double half_v = half_u * aspect;
  const double cu = std::clamp(0.5 * (u0 + u1), half_u - 0.5, width - 0.5 - half_u);
  const double cv = std::clamp(0.5 * (v0 + v1), half_v - 0.5, height - 0.5 - half_v);
  const ImageBox box = rows.empty() ? ImageBox{-0.5, width - 0.5, -0.5, height - 0.5}
                                    : ImageBox{cu - half_u, cu + half_u, cv - half_v, cv + half_v};
  // The reference arrow is 40 display pixels long.
  const double drawn = 40.0 * std::max(box.u1 - box.u0, box.v1 - box.v0) / kImagePanel;
  const double gain = drawn / reference_px;
  json corners = json::array();
  for (const ObservationResidual& o : rows) {
    json c = {{"target", o.target},
              {"corner", o.corner},
              {"u", o.u},
              {"v", o.v},
              {"status", ResidualStatusName(o.status)},
              {"line", o.line}};
    if (o.valid) {
      c.update({{"du", o.delta.x()},
                {"dv", o.delta.y()},
                {"r", o.size},
                {"nr", o.normalised},
                {"tip_u", o.u + gain * o.delta.x()},
                {"tip_v", o.v + gain * o.delta.y()},
                {"angle", std::atan2(o.delta.x(), -o.delta.y()) * kDeg}});
    }
    corners.push_back(c);
  }
  json spec = Chart("Photo " + shot + " (zoom " + std::to_string(zoom) + "): corners and residuals",
                    std::to_string(fitted) + " fitted corners, rms " + Significant(rms, 3) +
                        " px; arrows from each observed corner along observed - predicted, " +
                        Significant(reference_px, 3) + " px residual = the red reference arrow" +
                        (photo.empty() ? "; photo not found, corners only" : ""));
  int w = 0, h = 0;
  ImageScales(&spec, box, &w, &h);
  ImageBox crop{};
  const std::string uri = photo.empty() ? "" : PhotoDataUri(photo, box, &crop);
  spec["data"].push_back({{"name", "corners"}, {"values", corners}});
  spec["data"].push_back(
      {{"name", "arrows"},
       {"source", "corners"},
       {"transform", {{{"type", "filter"}, {"expr", "datum.status == 'fitted'"}}}}});
  json& marks = spec["marks"];
  if (!uri.empty()) {
    json image = Mark("image", "",
                      {{"url", {{"value", uri}}},
                       {"x", {{"scale", "u"}, {"value", crop.u0}}},
                       {"y", {{"scale", "v"}, {"value", crop.v0}}},
                       {"x2", {{"scale", "u"}, {"value", crop.u1}}},
                       {"y2", {{"scale", "v"}, {"value", crop.v1}}},
                       {"aspect", {{"value", false}}},
                       {"opacity", {{"value", 0.85}}}});
    image["clip"] = true;  // the panel shows a part of the photo
    marks.push_back(image);
  }
  const json tip = Tip({{"shot", "'" + shot + "'"},
                        {"target", "datum.target"},
                        {"corner", "datum.corner"},
                        {"u, v [px]", "format(datum.u, '.2f') + ', ' + format(datum.v, '.2f')"},
                        {"du, dv [px]", "format(datum.du, '.3f') + ', ' + format(datum.dv, '.3f')"},
                        {"|r| / sigma", "format(datum.nr, '.2f')"},
                        {"status", "datum.status"},
                        {"pixels.csv line", "datum.line"}});
  marks.push_back(
      Mark("symbol", "corners",
           {{"x", Field("u", "u")},
            {"y", Field("v", "v")},
            {"shape", {{"value", "circle"}}},
            {"size", {{"value", 18}}},
            {"stroke", {{"signal", "datum.status == 'fitted' ? '#00e5ff' : '#ff00ff'"}}},
            {"strokeWidth", {{"value", 1.2}}},
            {"tooltip", tip}}));
  Arrows(&marks, "arrows", "#ff3b30", tip);
  ScaleBar(&marks, 40.0, Significant(reference_px, 3) + " px", w);
  Figure f;
  // A file name and an HTML id: shot ids are free text (shots.csv).
  f.name = "photo_";
  for (char ch : shot)
    f.name += std::isalnum(static_cast<unsigned char>(ch)) || ch == '-' || ch == '.' ? ch : '_';
  f.section = "photos";
  f.title = "Photo " + shot + ", zoom " + std::to_string(zoom);
  f.caption =
      "The photo with its detected corners (cyan: fitted, magenta: left out, see the tooltip) "
      "and each fitted corner's residual (observed minus predicted at the final model, the "
      "board at its estimated pose), scaled by the red reference arrow. Arrows that turn "
      "together across the board point at the board pose or the camera model, a single long "
      "one at a bad detection.";
  f.spec = spec;
  f.summary = {{"shot", shot},           {"zoom", zoom},  {"fitted_rows", fitted},
               {"rows", rows.size()},    {"rms_px", rms}, {"arrow_scale_px", reference_px},
               {"photo", !photo.empty()}};
  return f;
}

std::map<std::string, std::string> PhotoFiles(const PhotoSessionSummary& photos) {
  std::map<std::string, std::string> out;
  const fs::path base = fs::path(photos.shots_path).parent_path();
  for (const PhotoSessionSummary::Photo& p : photos.photos) {
    const fs::path img(p.image);
    out[p.shot] = (img.is_absolute() ? img : base / img).string();
  }
  return out;
}

namespace {

// ---------------------------------------------------------------------------
// Residuals against the variables the diagnosis tests.

// One variable: a new one is one entry here (and its column in the residual
// table).
struct Variable {
  std::string key, label;
  std::function<double(const ObservationResidual&)> value;  // NaN: not for this row
};

const std::vector<Variable>& Variables() {
  static const std::vector<Variable> vars = {
      {"phi", "phi [deg]",
       [](const ObservationResidual& o) {
         return std::fmod(std::fmod(o.phi * kDeg, 360.0) + 360.0, 360.0);
       }},
      {"theta", "zenith angle [deg]",
       [](const ObservationResidual& o) { return ZenithOf(o.theta) * kDeg; }},
      {"d", "distance d [m] (records)",
       [](const ObservationResidual& o) { return o.group == ObsGroup::kPixel ? NAN : o.d; }},
      {"target_distance", "camera to point [m] (image points)",
       [](const ObservationResidual& o) {
         return o.group == ObsGroup::kPixel ? o.target_distance : NAN;
       }},
      {"image_radius", "image radius [px]",
       [](const ObservationResidual& o) { return o.image_radius >= 0 ? o.image_radius : NAN; }},
  };
  return vars;
}

struct Component {
  std::string key, label;
  std::function<double(const ObservationResidual&)> value;
};

const std::vector<Component>& Components() {
  static const std::vector<Component> comps = {
      {"hz", "horizontal direction error [\"]",
       [](const ObservationResidual& o) { return o.hz * kArcsec; }},
      {"zenith", "zenith angle error [\"]",
       [](const ObservationResidual& o) { return o.zenith * kArcsec; }},
      {"along", "error along the ray [mm] (records)",
       [](const ObservationResidual& o) {
         return o.group == ObsGroup::kPixel ? NAN : o.along * 1e3;
       }},
  };
  return comps;
}

const char* SeriesName(ObsGroup g) {
  return g == ObsGroup::kEdm   ? "EDM points"
         : g == ObsGroup::kCam ? "camera points"
                               : "image points";
}

Figure VariablesFigure(const std::vector<ObservationResidual>& rows) {
  constexpr int kBins = 16;
  constexpr int kMinPerBin = 3;
  json spec = Chart("Residuals against the variables the diagnosis tests",
                    "fitted rows; per bin the mean residual (line) and its 2-sigma band (mean +- "
                    "2 std / sqrt(n)); a mean outside the band around zero is structure");
  const json series_domain = {SeriesName(ObsGroup::kEdm), SeriesName(ObsGroup::kCam),
                              SeriesName(ObsGroup::kPixel)};
  spec["scales"].push_back({{"name", "group"},
                            {"type", "ordinal"},
                            {"domain", series_domain},
                            {"range", {"#1f77b4", "#ff7f0e", "#2ca02c"}}});
  spec["legends"].push_back({{"stroke", "group"},
                             {"fill", "group"},
                             {"title", "observations"},
                             {"orient", "top"},
                             {"direction", "horizontal"}});
  // The binned means of every variable and component first: a variable
  // that does not vary in this session (phi and theta of a camera on a
  // bench: at most one bin in every component) and a component that no
  // variable has residuals of (along the ray without records) are not drawn;
  // report.json's summary lists every pair.
  const std::vector<Variable>& variables = Variables();
  const std::vector<Component>& components = Components();
  std::vector<std::vector<json>> binned(variables.size(), std::vector<json>(components.size()));
  std::vector<char> varies(variables.size(), 0), has_data(components.size(), 0);
  json summary = json::array();
  for (size_t vi = 0; vi < variables.size(); ++vi) {
    const Variable& var = variables[vi];
    for (size_t ci = 0; ci < components.size(); ++ci) {
      const Component& comp = components[ci];
      // Per group: the variable's range, then its bins.
      json values = json::array();
      for (ObsGroup g : {ObsGroup::kEdm, ObsGroup::kCam, ObsGroup::kPixel}) {
        double lo = INFINITY, hi = -INFINITY;
        for (const ObservationResidual& o : rows) {
          if (!Fitted(o) || o.group != g) continue;
          const double x = var.value(o), y = comp.value(o);
          if (!std::isfinite(x) || !std::isfinite(y)) continue;
          lo = std::min(lo, x);
          hi = std::max(hi, x);
        }
        if (!(hi >= lo)) continue;
        std::vector<double> sx(kBins), sy(kBins), syy(kBins);
        std::vector<int> n(kBins);
        const double width = hi > lo ? (hi - lo) / kBins : 1.0;
        for (const ObservationResidual& o : rows) {
          if (!Fitted(o) || o.group != g) continue;
          const double x = var.value(o), y = comp.value(o);
          if (!std::isfinite(x) || !std::isfinite(y)) continue;
          const int b = std::clamp(static_cast<int>((x - lo) / width), 0, kBins - 1);
          sx[b] += x;
          sy[b] += y;
          syy[b] += y * y;
          ++n[b];
        }
        int group_bins = 0;
        for (int b = 0; b < kBins; ++b) {
          if (n[b] < kMinPerBin) continue;
          if (++group_bins > 1) varies[vi] = 1;
          const double mean = sy[b] / n[b];
          const double var_y = std::max(0.0, syy[b] / n[b] - mean * mean) * n[b] / (n[b] - 1);
          const double se = std::sqrt(var_y / n[b]);
          values.push_back({{"group", SeriesName(g)},
                            {"x", sx[b] / n[b]},
                            {"mean", mean},
                            {"lo", mean - 2 * se},
                            {"hi", mean + 2 * se},
                            {"n", n[b]}});
        }
      }
      summary.push_back({{"variable", var.key}, {"component", comp.key}, {"bins", values.size()}});
      if (!values.empty()) has_data[ci] = 1;
      binned[vi][ci] = std::move(values);
    }
  }
  // Nothing varies or nothing has residuals: every panel, each saying so.
  if (std::count(varies.begin(), varies.end(), 1) == 0) std::fill(varies.begin(), varies.end(), 1);
  if (std::count(has_data.begin(), has_data.end(), 1) == 0) {
    std::fill(has_data.begin(), has_data.end(), 1);
  }
  spec["layout"] = Grid(std::count(has_data.begin(), has_data.end(), 1), 75, 95);
  for (size_t vi = 0; vi < variables.size(); ++vi) {
    const Variable& var = variables[vi];
    if (!varies[vi]) continue;
    for (size_t ci = 0; ci < components.size(); ++ci) {
      const Component& comp = components[ci];
      if (!has_data[ci]) continue;
      const json& values = binned[vi][ci];
      json group = {
          {"type", "group"},
          {"encode",
           {{"enter", {{"width", {{"value", kPanelW}}}, {"height", {{"value", kPanelH}}}}}}}};
      const std::string data = var.key + "_" + comp.key;
      if (values.empty()) {
        group["marks"] = {
            Mark("text", "",
                 {{"x", {{"value", kPanelW / 2}}},
                  {"y", {{"value", kPanelH / 2}}},
                  {"align", {{"value", "center"}}},
                  {"fill", {{"value", "#888"}}},
                  {"text", {{"value", "no " + comp.key + " residuals against " + var.key}}}})};
        group["title"] = {{"text", var.label}, {"fontSize", 10}};
        spec["marks"].push_back(group);
        continue;
      }
      group["data"] = {{{"name", data}, {"values", values}}};
      group["scales"] = {{{"name", "x"},
                          {"type", "linear"},
                          {"domain", {{"data", data}, {"field", "x"}}},
                          {"range", {0, kPanelW}},
                          {"zero", false},
                          {"nice", true}},
                         {{"name", "y"},
                          {"type", "linear"},
                          {"domain", {{"data", data}, {"fields", {"lo", "hi"}}}},
                          {"range", {kPanelH, 0}},
                          {"zero", true},
                          {"nice", true}}};
      json ay = Axis("left", "y", comp.label);
      ay["grid"] = true;
      ay["tickCount"] = 5;
      json ax = Axis("bottom", "x", var.label);
      ax["tickCount"] = 6;
      group["axes"] = {ax, ay};
      const json tip = Tip({{"observations", "datum.group"},
                            {var.key, "format(datum.x, '.4g')"},
                            {"mean", "format(datum.mean, '.3g')"},
                            {"2 sigma", "format(datum.hi - datum.mean, '.2g')"},
                            {"n", "datum.n"}});
      // The 2-sigma band under each series' line.
      const json band = json::array({Mark("area", "",
                                          {{"x", Field("x", "x")},
                                           {"y", Field("y", "lo")},
                                           {"y2", Field("y", "hi")},
                                           {"fill", Field("group", "group")},
                                           {"fillOpacity", {{"value", 0.18}}}})});
      group["marks"] = {SeriesLines(data, "group", "group", "x", "mean", 1.5, 14, tip, band),
                        Mark("rule", "",
                             {{"x", {{"value", 0}}},
                              {"x2", {{"value", kPanelW}}},
                              {"y", {{"scale", "y"}, {"value", 0}}},
                              {"stroke", {{"value", "#444"}}},
                              {"strokeDash", {{"value", {3, 3}}}}})};
      spec["marks"].push_back(group);
    }
  }
  Figure f;
  f.name = "residuals_vs_variables";
  f.section = "variables";
  f.title = "Residuals against the variables";
  f.caption =
      "Each row is one variable the diagnosis tests (phi, zenith angle, distance, camera-to-point "
      "distance, image radius), each column one residual component (horizontal direction and "
      "zenith angle in arcseconds for every observation kind, along the ray in millimetres for "
      "records). A once-per-turn wave against phi is an eccentricity or a wobble, a slope against "
      "distance a scale error, a trend against the image radius a distortion term the model "
      "lacks. A variable that does not vary in this session and a component without residuals "
      "are left out.";
  f.spec = spec;
  f.summary = {{"panels", summary}};
  return f;
}

// ---------------------------------------------------------------------------
// Histograms of the fitted residual coordinates against the fitted sigma.

Figure Histograms(const std::vector<ObservationResidual>& rows) {
  constexpr int kBins = 36;
  constexpr double kRange = 4.5;  // sigmas each side
  struct Series {
    ObsGroup group;
    std::string title, unit;
    double scale;
    std::vector<double> values;
    double sigma = 0;
  };
  std::vector<Series> all = {{ObsGroup::kEdm, "EDM points (x, y, z)", "mm", 1e3, {}, 0},
                             {ObsGroup::kCam, "camera points (x, y, z)", "mm", 1e3, {}, 0},
                             {ObsGroup::kPixel, "image points (u, v)", "px", 1.0, {}, 0}};
  for (const ObservationResidual& o : rows) {
    if (!Fitted(o)) continue;
    Series& s = all[static_cast<int>(o.group)];
    const int k = o.group == ObsGroup::kPixel ? 2 : 3;
    for (int i = 0; i < k; ++i) s.values.push_back(o.delta[i] * s.scale);
    // Pixels of several zooms: their sigmas' root mean square.
    s.sigma += o.sigma * o.sigma * s.scale * s.scale;
  }
  json spec = Chart("Residuals against the Gaussian of the fitted sigma (fitted rows)",
                    "bars: residual coordinates; red: the normal density of the fitted "
                    "(a-posteriori) sigma; counts beyond 4.5 sigma in the panel title");
  spec["layout"] = Grid(3, 60, 130);
  json summary = json::array();
  for (Series& s : all) {
    if (s.values.empty()) continue;
    const int rows_n = static_cast<int>(s.values.size()) / (s.group == ObsGroup::kPixel ? 2 : 3);
    s.sigma = std::sqrt(s.sigma / rows_n);
    if (!(s.sigma > 0)) continue;
    const double range = kRange * s.sigma, width = 2 * range / kBins;
    std::vector<int> counts(kBins);
    int outside = 0;
    double ss = 0;
    for (double v : s.values) {
      ss += v * v;
      if (std::abs(v) >= range) {
        ++outside;
        continue;
      }
      ++counts[std::clamp(static_cast<int>((v + range) / width), 0, kBins - 1)];
    }
    json bars = json::array(), curve = json::array();
    for (int b = 0; b < kBins; ++b) {
      bars.push_back(
          {{"x0", -range + b * width}, {"x1", -range + (b + 1) * width}, {"n", counts[b]}});
    }
    for (int k = 0; k <= 120; ++k) {
      const double x = -range + 2 * range * k / 120;
      curve.push_back(
          {{"x", x},
           {"y", s.values.size() * width * std::exp(-0.5 * x * x / (s.sigma * s.sigma)) /
                     (std::sqrt(2 * M_PI) * s.sigma)}});
    }
    const double rms = std::sqrt(ss / s.values.size());
    const std::string key = s.group == ObsGroup::kEdm   ? "edm"
                            : s.group == ObsGroup::kCam ? "cam"
                                                        : "pixels";
    json ax = Axis("bottom", "x", "residual [" + s.unit + "]");
    ax["tickCount"] = 6;
    json ay = Axis("left", "y", "count");
    ay["tickCount"] = 5;
    const json tip = Tip({{"from", "format(datum.x0, '.3g')"},
                          {"to", "format(datum.x1, '.3g')"},
                          {"count", "datum.n"}});
    spec["marks"].push_back(
        {{"type", "group"},
         {"title",
          {{"text", s.title},
           {"subtitle", "fitted sigma " + Significant(s.sigma, 3) + ", rms " + Significant(rms, 3) +
                            " " + s.unit + ", n " + std::to_string(s.values.size()) +
                            ", beyond 4.5 sigma: " + std::to_string(outside)},
           {"fontSize", 12},
           {"subtitleFontSize", 10}}},
         {"encode",
          {{"enter", {{"width", {{"value", kPanelW}}}, {"height", {{"value", kPanelH}}}}}}},
         {"data",
          {{{"name", key + "_bars"}, {"values", bars}},
           {{"name", key + "_curve"}, {"values", curve}}}},
         {"scales",
          {Linear("x", {-range, range}, {0, kPanelW}),
           {{"name", "y"},
            {"type", "linear"},
            {"domain",
             {{"fields",
               {{{"data", key + "_bars"}, {"field", "n"}},
                {{"data", key + "_curve"}, {"field", "y"}}}}}},
            {"range", {kPanelH, 0}},
            {"nice", true},
            {"zero", true}}}},
         {"axes", {ax, ay}},
         {"marks",
          {Mark("rect", key + "_bars",
                {{"x", Field("x", "x0")},
                 {"x2", Field("x", "x1")},
                 {"y", Field("y", "n")},
                 {"y2", {{"scale", "y"}, {"value", 0}}},
                 {"fill", {{"value", "#8cb4d8"}}},
                 {"stroke", {{"value", "#5079a0"}}},
                 {"tooltip", tip}}),
           Mark("line", key + "_curve",
                {{"x", Field("x", "x")},
                 {"y", Field("y", "y")},
                 {"stroke", {{"value", "#d62728"}}},
                 {"strokeWidth", {{"value", 2}}}})}}});
    summary.push_back({{"group", key},
                       {"values", s.values.size()},
                       {"sigma", s.sigma},
                       {"rms", rms},
                       {"unit", s.unit},
                       {"beyond_4_5_sigma", outside}});
  }
  Figure f;
  f.name = "residual_histograms";
  f.section = "histograms";
  f.title = "Residual histograms";
  f.caption =
      "Coordinates of observed minus model for the rows the fit uses; the red curve is the normal "
      "density with the fitted (a-posteriori) sigma of the group. Heavy tails point at outliers, a "
      "curve narrower than the bars at a missing effect or an optimistic sigma.";
  f.spec = spec;
  f.summary = {{"groups", summary}};
  return f;
}

// ---------------------------------------------------------------------------
// The ladder: error per observation group across rungs or runs.

struct Rung {
  std::string label;  // "step 1: +hz_eccentricity"
  double edm_mm = NAN, cam_mm = NAN, px = NAN;
};

Figure LadderFigure(const std::vector<Rung>& rungs, const std::string& name,
                    const std::string& title, const std::string& caption) {
  json mm = json::array(), px = json::array(), labels = json::array();
  for (const Rung& g : rungs) {
    labels.push_back(g.label);
    if (std::isfinite(g.edm_mm) && g.edm_mm > 0)
      mm.push_back({{"label", g.label}, {"series", "EDM points"}, {"value", g.edm_mm}});
    if (std::isfinite(g.cam_mm) && g.cam_mm > 0)
      mm.push_back({{"label", g.label}, {"series", "camera points"}, {"value", g.cam_mm}});
    if (std::isfinite(g.px) && g.px > 0)
      px.push_back({{"label", g.label}, {"series", "image points"}, {"value", g.px}});
  }
  json spec = Chart(title, "rms error of each observation group (log scale)");
  spec["layout"] = Grid(1, 120, 0);
  spec["scales"].push_back({{"name", "series"},
                            {"type", "ordinal"},
                            {"domain", {"EDM points", "camera points", "image points"}},
                            {"range", {"#1f77b4", "#ff7f0e", "#2ca02c"}}});
  spec["legends"].push_back({{"stroke", "series"}, {"fill", "series"}, {"orient", "right"}});
  const int width = std::max(420, 110 * static_cast<int>(rungs.size()));
  json summary = json::array();
  for (const auto& [data, unit] : {std::pair<json*, std::string>{&mm, "mm"}, {&px, "px"}}) {
    if (data->empty()) continue;
    const std::string d = unit == "mm" ? "mm" : "px";
    json ax = Axis("bottom", "x", "");
    ax["labelAngle"] = rungs.size() > 4 ? -20 : 0;
    ax["labelAlign"] = rungs.size() > 4 ? "right" : "center";
    ax["labelLimit"] = 220;
    json ay = Axis("left", "y", "rms error [" + unit + "] (log)");
    ay["grid"] = true;
    const json tip = Tip({{"rung", "datum.label"},
                          {"series", "datum.series"},
                          {"rms [" + unit + "]", "format(datum.value, '.4g')"}});
    spec["marks"].push_back(
        {{"type", "group"},
         {"encode", {{"enter", {{"width", {{"value", width}}}, {"height", {{"value", kPanelH}}}}}}},
         {"data", {{{"name", d}, {"values", *data}}}},
         {"scales",
          {{{"name", "x"},
            {"type", "point"},
            {"domain", labels},
            {"range", {0, width}},
            {"padding", 0.5}},
           {{"name", "y"},
            {"type", "log"},
            {"domain", {{"data", d}, {"field", "value"}}},
            {"range", {kPanelH, 0}},
            {"nice", true}}}},
         {"axes", {ax, ay}},
         {"marks", {SeriesLines(d, "series", "series", "label", "value", 2, 50, tip)}}});
    summary.push_back({{"unit", unit}, {"points", *data}});
  }
  Figure f;
  f.name = name;
  f.section = "ladder";
  f.title = title;
  f.caption = caption;
  f.spec = spec;
  f.summary = {{"rungs", labels}, {"series", summary}};
  return f;
}

// NAN is a float: json::value(key, NAN) would read the number as a float
// and draw 7 of its digits; std::nan("") keeps the double.
double JsonRms(const json& final, const char* tool) {
  if (!final.contains("records") || !final["records"].contains(tool)) return NAN;
  const json& t = final["records"][tool];
  return t.value("n", 0) > 0 ? t.value("rms_m", std::nan("")) * 1e3 : NAN;
}

std::string Added(const std::vector<std::string>& before, const std::vector<std::string>& after) {
  std::string out;
  for (const std::string& e : after) {
    if (std::find(before.begin(), before.end(), e) == before.end())
      out += (out.empty() ? "+" : " +") + e;
  }
  for (const std::string& e : before) {
    if (std::find(after.begin(), after.end(), e) == after.end())
      out += (out.empty() ? "-" : " -") + e;
  }
  return out;
}

// ---------------------------------------------------------------------------
// Heat maps over an image: cols x rows cells (row-major from the top-left),
// NaN: not predictable (grey); `inside` false: outside the valid region
// (faded, struck through); `hull`: the valid region's outline.
json HeatMapSpec(const std::string& title, const std::string& subtitle, int width, int height,
                 int cols, int rows, const std::vector<double>& value,
                 const std::vector<unsigned char>& inside, const std::string& legend,
                 const std::vector<Eigen::Vector2d>& hull) {
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
  spec["scales"].push_back({{"name", "colour"},
                            {"type", "linear"},
                            {"scheme", "viridis"},
                            {"domain", {{"data", "cells"}, {"field", "value"}}},
                            {"zero", true},
                            {"nice", true}});
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
  f.title = "Projection uncertainty, zoom " + std::to_string(m.zoom) + ", point at " +
            Significant(o.range_m, 3) + " m";
  f.spec = HeatMapSpec(
      f.title,
      "1 sigma, worst direction [px]: min " + Significant(m.min_px, 3) + ", median " +
          Significant(m.median_px, 3) + ", max " + Significant(m.max_px, 3) + "; pointing phi " +
          Significant(o.phi, 4) + ", theta " + Significant(o.theta, 4) + " rad; " +
          (full ? "full covariance" : "diagonal approximation (no full covariance)") +
          "; faded and struck through: outside the points' hull (white)",
      m.width, m.height, m.cols, m.rows, m.sigma_px,
      std::vector<unsigned char>(m.inside.begin(), m.inside.end()), "1-sigma [px]",
      cam.valid_region);
  f.caption =
      "How far (1 sigma, worst direction, pixels) the pixel where a point at " +
      Significant(o.range_m, 3) +
      " m is seen may lie from the model's prediction, from the uncertainty of this zoom's "
      "intrinsics, distortion and camera tool and of the kinematic chain (first order, J P J^T "
      "with the fit's full covariance). Cells outside the convex hull of the calibration's image "
      "points (white outline) are faded and struck through: there the distortion is extrapolated "
      "and the number is a lower bound at best.";
  f.summary = {{"zoom", m.zoom}, {"max_px", m.max_px}, {"median_px", m.median_px}};
  return f;
}

}  // namespace

Figure DifferenceFigure(const ZoomDifference& d) {
  Figure f;
  f.name = "compare_zoom" + std::to_string(d.zoom);
  f.section = "compare";
  f.title = "Projection difference, zoom " + std::to_string(d.zoom);
  f.spec = HeatMapSpec(f.title,
                       "RMS " + Significant(d.rms_px, 3) + ", max " + Significant(d.max_px, 3) +
                           " px; rotation removed " + Significant(d.rotation_rad * kArcsec, 3) +
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

Figure RunsLadderFigure(const json& history, const std::vector<std::string>& effects,
                        const json& final) {
  std::vector<Rung> rungs;
  std::vector<std::string> prev;
  auto add = [&](const std::string& run, const std::vector<std::string>& now, const json& f) {
    // The label names what changed against the run before, shown or not.
    const std::string added = rungs.empty() ? "" : Added(prev, now);
    Rung g;
    g.label = run + (added.empty() ? "" : ": " + added);
    g.edm_mm = JsonRms(f, "edm");
    g.cam_mm = JsonRms(f, "cam");
    if (f.contains("pixels") && f["pixels"].value("n", 0) > 0)
      g.px = f["pixels"].value("rms_px", std::nan(""));
    rungs.push_back(g);
    prev = now;
  };
  for (const json& h : history) {
    if (!h.is_object() || !h.contains("final")) continue;
    std::vector<std::string> now;
    if (h.contains("effects")) now = h["effects"].get<std::vector<std::string>>();
    add("run " + h.value("run", std::string("?")).substr(0, 3), now, h["final"]);
  }
  add("this run", effects, final);
  // A folder that has kept many runs would give a figure wider than any
  // screen (110 px per rung): the latest runs are the ones a user compares,
  // and report.html's history table lists every run.
  std::string title = "The ladder across runs (this output folder's history)";
  std::string caption =
      "Final error of every complete run kept in the output folder (all rows, SPEC 6 `final`), "
      "labelled with the effects added (+) or removed (-) relative to the run before";
  const size_t total = rungs.size();
  if (total > kLadderRunsShown) {
    rungs.erase(rungs.begin(), rungs.end() - kLadderRunsShown);
    const std::string latest =
        "the latest " + std::to_string(kLadderRunsShown) + " of " + std::to_string(total);
    title = "The ladder across runs (" + latest + " complete runs in this output folder)";
    caption += "; " + latest + " (the table of runs above lists every run)";
  }
  Figure f = LadderFigure(rungs, "ladder_runs", title, caption + ".");
  f.summary["runs"] = total;
  return f;
}

std::vector<Figure> MakeFigures(const PipelineResult& r, const json& history) {
  std::vector<Figure> figs;
  const CalibrationResult& c = r.calibration;
  const std::vector<ObservationResidual>& rows = c.residuals;

  // This run's stepwise ladder.
  if (c.ladder.size() > 1) {
    std::vector<Rung> rungs;
    for (size_t i = 0; i < c.ladder.size(); ++i) {
      const LadderStep& s = c.ladder[i];
      rungs.push_back(
          {"step " + std::to_string(i) + ": " + (s.added.empty() ? "start" : "+" + s.added),
           s.rms.edm_n ? s.rms.edm_m * 1e3 : NAN, s.rms.cam_n ? s.rms.cam_m * 1e3 : NAN,
           s.rms.pixels_n ? s.rms.pixels_px : NAN});
    }
    figs.push_back(LadderFigure(rungs, "ladder_stepwise",
                                "The ladder of this run (diagnose --auto)",
                                "Error of the fitted rows after each effect the forward stepwise "
                                "search added (rtscalib diagnose --auto)."));
  }
  // Across runs: earlier complete runs of this output folder, then this one.
  if (history.is_array() && !history.empty()) {
    const FinalErrors& e = c.final_errors;
    const json final = {{"records",
                         {{"edm", {{"rms_m", e.edm.rms_m}, {"n", e.edm.n}}},
                          {"cam", {{"rms_m", e.cam.rms_m}, {"n", e.cam.n}}}}},
                        {"pixels", {{"rms_px", e.pixels.rms_px}, {"n", e.pixels.n}}}};
    figs.push_back(RunsLadderFigure(history, c.model.effects.Names(), final));
  }

  // Maps per tool.
  std::set<int> faces, cam_zooms, pixel_zooms;
  bool edm = false;
  for (const ObservationResidual& o : rows) {
    if (!o.valid || o.status == ResidualStatus::kGrossError) continue;
    faces.insert(o.face);
    if (o.group == ObsGroup::kEdm) edm = true;
    if (o.group == ObsGroup::kCam) cam_zooms.insert(o.zoom);
    if (o.group == ObsGroup::kPixel && o.zoom < c.model.NumZooms()) pixel_zooms.insert(o.zoom);
  }
  std::set<int> pixel_zooms_mapped = pixel_zooms;
  const std::string model = KinematicsName(c.model.kinematics) + std::string(", effects: [") + [&] {
    std::string s;
    for (const std::string& n : c.model.effects.Names()) s += (s.empty() ? "" : ", ") + n;
    return s;
  }() + "]";
  // A camera-only calibration (kinematics none) has no pointings to map.
  if (c.model.kinematics == Kinematics::kNone) pixel_zooms_mapped.clear();
  if (edm) {
    figs.push_back(ErrorMap({"edm", "EDM points", "mm", 1e3, ObsGroup::kEdm, 0}, rows, faces,
                            c.fit_options, model));
  }
  for (int z : cam_zooms) {
    figs.push_back(
        ErrorMap({"cam_zoom" + std::to_string(z), "Camera points, zoom " + std::to_string(z), "mm",
                  1e3, ObsGroup::kCam, z},
                 rows, faces, c.fit_options, model));
  }
  for (int z : pixel_zooms_mapped) {
    figs.push_back(
        ErrorMap({"pixels_zoom" + std::to_string(z), "Image points, zoom " + std::to_string(z),
                  "px", 1.0, ObsGroup::kPixel, z},
                 rows, faces, c.fit_options, model));
  }

  // The image: binned residuals per zoom, then the worst photos.
  std::set<int> image_zooms = pixel_zooms;
  image_zooms.insert(cam_zooms.begin(), cam_zooms.end());
  for (int z : image_zooms) {
    if (z < c.model.NumZooms()) figs.push_back(ImageResiduals(z, c.model.cams[z], rows));
  }
  std::map<std::string, std::vector<ObservationResidual>> by_shot;
  for (const ObservationResidual& o : rows) {
    if (o.group == ObsGroup::kPixel && !o.shot.empty()) by_shot[o.shot].push_back(o);
  }
  std::map<int, std::vector<std::pair<double, std::string>>> worst;  // zoom -> (rms, shot)
  for (const auto& [shot, shot_rows] : by_shot) {
    double ss = 0;
    int n = 0;
    for (const ObservationResidual& o : shot_rows) {
      if (!Fitted(o)) continue;
      ss += o.size * o.size;
      ++n;
    }
    if (n > 0) worst[shot_rows.front().zoom].push_back({std::sqrt(ss / n), shot});
  }
  const std::map<std::string, std::string> files = PhotoFiles(r.photos);
  for (auto& [z, shots] : worst) {
    if (z >= c.model.NumZooms()) continue;
    std::sort(shots.rbegin(), shots.rend());
    for (size_t k = 0; k < shots.size() && k < kWorstPhotosPerZoom; ++k) {
      const auto file = files.find(shots[k].second);
      figs.push_back(PhotoFigure(shots[k].second, by_shot[shots[k].second],
                                 file == files.end() ? "" : file->second, c.model.cams[z].width,
                                 c.model.cams[z].height));
    }
  }
  figs.push_back(VariablesFigure(rows));
  figs.push_back(Histograms(rows));
  for (const UncertaintyMap& m : r.uncertainty_maps) {
    if (m.determined) {
      figs.push_back(
          UncertaintyFigure(m, r.uncertainty_options, c.model.cams[m.zoom], r.full_covariance));
    }
  }
  return figs;
}

std::vector<std::vector<std::string>> WriteFigureFiles(const std::vector<Figure>& figures,
                                                       const std::string& dir, std::string* note,
                                                       VegaRenderer* renderer) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw WriteError(dir, ec.message() + " (creating the folder)");
  std::vector<json> specs;
  for (const Figure& f : figures) specs.push_back(f.spec);
  // The specs go to node first; the .vg.json files are written while it
  // draws, and each figure's SVG and PNG as soon as its PNG is drawn: a
  // checked write waits for the disk (its fsync, about a millisecond a file
  // here), beside the drawing rather than after it.
  std::future<void> written_specs = std::async(std::launch::async, [&] {
    for (const Figure& f : figures) {
      WriteFileAtomic((fs::path(dir) / (f.name + ".vg.json")).string(), f.spec.dump() + "\n");
    }
  });
  const VegaRenderer::Drawn write = [&](size_t i, const RenderedFigure& fig) {
    WriteFileAtomic((fs::path(dir) / (figures[i].name + ".svg")).string(), fig.svg);
    WriteFileAtomic(
        (fs::path(dir) / (figures[i].name + ".png")).string(),
        std::string_view(reinterpret_cast<const char*>(fig.png.data()), fig.png.size()));
  };
  note->clear();
  const std::vector<RenderedFigure> drawn = renderer != nullptr
                                                ? renderer->Draw(specs, note, write)
                                                : RenderFigures(specs, note, write);
  written_specs.get();
  std::vector<std::vector<std::string>> written(figures.size());
  for (size_t i = 0; i < figures.size(); ++i) {
    written[i].push_back(figures[i].name + ".vg.json");
    if (i >= drawn.size()) continue;
    if (drawn[i].png.empty()) {
      *note += std::string(note->empty() ? "figures: " : "; ") + figures[i].name +
               " has no SVG or PNG (" + drawn[i].error + ")";
      continue;
    }
    written[i].push_back(figures[i].name + ".svg");
    written[i].push_back(figures[i].name + ".png");
  }
  return written;
}

}  // namespace rtscalib::app

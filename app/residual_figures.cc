#include "app/residual_figures.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <tuple>

#include "libcalib/diagnose/statistics.h"
#include "libcalib/text/number_text.h"

namespace rtscalib::app {

using nlohmann::json;

// ---------------------------------------------------------------------------
// Error maps: rms of |observed - model| per pointing and face.

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
    const double phi = std::fmod(std::fmod(o.phi * kDegPerRad, 360.0) + 360.0, 360.0);
    auto& c = cells[{o.face, phi, o.theta * kDegPerRad}];
    c.first += o.size * o.size;
    ++c.second;
    phis[o.face].insert(std::lround(phi * 100));
    thetas[o.face].insert(std::lround(o.theta * kDegPerRad * 100));
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
  const double zmin = fit.critical_region.min_zenith_rad * kDegPerRad;
  const double zmax = fit.critical_region.max_zenith_rad * kDegPerRad;
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

namespace {

// Photos a cell needs before its mean is tested (the 2 x 2 scatter of fewer
// is too rough for the chi-square below).
constexpr int kStructureMinPhotos = 10;
// Family-wise level of the cells' tests: "structure" is a cell mean that
// fewer than 1 % of noise-only images would show anywhere.
constexpr double kStructureLevel = 0.01;

}  // namespace

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
                     {"angle", std::atan2(du, -dv) * kDegPerRad},
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
         return std::fmod(std::fmod(o.phi * kDegPerRad, 360.0) + 360.0, 360.0);
       }},
      {"theta", "zenith angle [deg]",
       [](const ObservationResidual& o) { return ZenithOf(o.theta) * kDegPerRad; }},
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
       [](const ObservationResidual& o) { return o.hz * kArcsecPerRad; }},
      {"zenith", "zenith angle error [\"]",
       [](const ObservationResidual& o) { return o.zenith * kArcsecPerRad; }},
      {"along", "error along the ray [mm] (records)",
       [](const ObservationResidual& o) {
         return o.group == ObsGroup::kPixel ? NAN : o.along * 1e3;
       }},
      // A camera on its own has no horizontal direction or zenith angle
      // (ObservationResidual::hz): its residuals in pixels instead.
      {"du", "u error [px] (camera on its own)",
       [](const ObservationResidual& o) {
         return o.group == ObsGroup::kPixel && std::isnan(o.hz) ? o.image_delta.x() : NAN;
       }},
      {"dv", "v error [px] (camera on its own)",
       [](const ObservationResidual& o) {
         return o.group == ObsGroup::kPixel && std::isnan(o.hz) ? o.image_delta.y() : NAN;
       }},
  };
  return comps;
}

const char* SeriesName(ObsGroup g) {
  return g == ObsGroup::kEdm   ? "EDM points"
         : g == ObsGroup::kCam ? "camera points"
                               : "image points";
}

}  // namespace

Figure VariablesFigure(const std::vector<ObservationResidual>& rows) {
  constexpr int kBins = 16;
  constexpr int kMinPerBin = 3;
  json spec = Chart("Residuals against the variables the diagnosis tests",
                    "fitted rows; per bin the mean residual (line) and its 2-sigma band (mean +- "
                    "2 std / sqrt(n)); a mean outside the band around zero is structure");
  // The legend lists the kinds of observation the session has, each in its
  // own colour whichever others are there.
  json series_domain = json::array(), series_range = json::array();
  for (const auto& [g, colour] :
       {std::pair{ObsGroup::kEdm, "#1f77b4"}, std::pair{ObsGroup::kCam, "#ff7f0e"},
        std::pair{ObsGroup::kPixel, "#2ca02c"}}) {
    if (std::any_of(rows.begin(), rows.end(),
                    [g = g](const ObservationResidual& o) { return Fitted(o) && o.group == g; })) {
      series_domain.push_back(SeriesName(g));
      series_range.push_back(colour);
    }
  }
  spec["scales"].push_back(
      {{"name", "group"}, {"type", "ordinal"}, {"domain", series_domain}, {"range", series_range}});
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
      "records; u and v in pixels for a camera on its own, whose frame has no vertical). A "
      "once-per-turn wave against phi is an eccentricity or a wobble, a slope against "
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

}  // namespace rtscalib::app

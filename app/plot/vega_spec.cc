#include "app/plot/vega_spec.h"

#include <algorithm>

namespace rtscalib::app {

using nlohmann::json;

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

json Linear(const std::string& name, const json& domain, const json& range, bool nice, bool zero) {
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

json Mark(const std::string& type, const std::string& data, json enter) {
  json m = {{"type", type}, {"encode", {{"enter", std::move(enter)}}}};
  if (!data.empty()) m["from"] = {{"data", data}};
  return m;
}

json Grid(size_t columns, int row_padding, int column_padding) {
  return {{"columns", columns},
          {"align", "all"},
          {"bounds", "flush"},
          {"padding", {{"row", row_padding}, {"column", column_padding}}}};
}

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

json SeriesLines(const std::string& data, const std::string& by, const std::string& colour,
                 const std::string& x, const std::string& y, double width, double dot,
                 const json& tooltip, json extra_marks) {
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
void ImageScales(json* spec, int width, int height, int* w, int* h) {
  ImageScales(spec, {-0.5, width - 0.5, -0.5, height - 0.5}, w, h);
}

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

bool Fitted(const ObservationResidual& o) { return o.status == ResidualStatus::kFitted; }

}  // namespace rtscalib::app

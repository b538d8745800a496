// The figures' SVG drawn from their Vega specs in process (app/plot/vega_svg.h),
// in two parts.
//
// VegaSvg: small hand-written specs whose picture Vega's rules fix: d3's
// tick values and Vega's tick labels of linear axes, a nice domain, a linear
// scale's zero, a log scale's gradient legend, the symbol shapes, the text
// baselines, the grid layout of panels, the "pad" autosize, and the parts of
// Vega outside the drawn subset, which are refused by name. The expected
// values were computed by Vega itself (Debian's libjs-vega 5.22.1 in node
// 20, the runtime report.html inlines); VegaSvgAgainstVega.HandWrittenSpecs
// draws most of these specs with Vega again.
//
// VegaSvgAgainstVega: those specs and every figure of two real runs (a
// camera on a bench, configs/bench.yaml; a simulated instrument,
// configs/paper.yaml; each run twice so that the ladder of runs is drawn),
// drawn by Vega in node and by DrawSvg, then compared: the same texts (tick
// labels with their formats, legend labels, titles), the same number of
// drawn items of each kind of mark, and about the same size. Node and the
// Vega modules are a test dependency (scripts/install-deps.sh installs
// them): without them the comparison fails rather than skips, since
// otherwise a drawer that parts from Vega would go unnoticed.
#include "app/plot/vega_svg.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "app/commands.h"
#include "app/plot/vega.h"
#include "app/plot/vega_expression.h"
#include "tests/app/read_file.h"

namespace rtscalib::app {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing_files::ReadFile;

// ---------------------------------------------------------------------------
// Reading an SVG file back: its elements with their place and text.

// One element of an SVG file, as far as the tests look at it.
struct SvgElement {
  std::string name;                          // "text", "rect", "path", "circle", ...
  std::map<std::string, std::string> attrs;  // as written
  double x = 0, y = 0;                       // the translation of the <g> elements around it
  std::string mark;      // the class of the innermost <g class="mark-..."> around it (Vega's)
  bool in_defs = false;  // inside <defs>: a clip path's or a gradient's part, not drawn itself
  int depth = 0;         // the number of <g> elements around it
  std::vector<std::string> lines;  // <text>: its lines, entities decoded, trimmed
};

std::string TrimSpace(const std::string& s) {
  size_t a = 0, b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
  return s.substr(a, b - a);
}

// XML's entities (the five named ones and character references) decoded.
std::string DecodeXml(const std::string& s) {
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    const size_t end = s[i] == '&' ? s.find(';', i) : std::string::npos;
    if (end == std::string::npos) {
      out += s[i];
      continue;
    }
    const std::string name = s.substr(i + 1, end - i - 1);
    static const std::map<std::string, std::string> kNamed = {
        {"amp", "&"}, {"lt", "<"}, {"gt", ">"}, {"quot", "\""}, {"apos", "'"}};
    if (auto it = kNamed.find(name); it != kNamed.end()) {
      out += it->second;
    } else if (name.size() > 1 && name[0] == '#') {
      const unsigned long c = name[1] == 'x' ? std::stoul(name.substr(2), nullptr, 16)
                                             : std::stoul(name.substr(1), nullptr, 10);
      // UTF-8 of the code point.
      if (c < 0x80) {
        out += static_cast<char>(c);
      } else if (c < 0x800) {
        out += static_cast<char>(0xC0 | (c >> 6));
        out += static_cast<char>(0x80 | (c & 0x3F));
      } else if (c < 0x10000) {
        out += static_cast<char>(0xE0 | (c >> 12));
        out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
        out += static_cast<char>(0x80 | (c & 0x3F));
      } else {
        out += static_cast<char>(0xF0 | (c >> 18));
        out += static_cast<char>(0x80 | ((c >> 12) & 0x3F));
        out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
        out += static_cast<char>(0x80 | (c & 0x3F));
      }
    } else {
      out += s.substr(i, end - i + 1);
    }
    i = end;
  }
  return out;
}

// The first translate(x, y) of a transform attribute ({0, 0} without one).
std::pair<double, double> Translation(const std::string& transform) {
  const size_t at = transform.find("translate(");
  if (at == std::string::npos) return {0, 0};
  const char* p = transform.c_str() + at + 10;
  char* end = nullptr;
  const double x = std::strtod(p, &end);
  p = end;
  while (*p == ',' || *p == ' ') ++p;
  const double y = std::strtod(p, &end);
  return {x, end == p ? 0 : y};
}

double Attr(const SvgElement& e, const std::string& name) {
  auto it = e.attrs.find(name);
  return it == e.attrs.end() ? 0 : std::strtod(it->second.c_str(), nullptr);
}

// The elements of `svg` in document order (without the <g> elements, whose
// translations and Vega mark classes are given to what they hold). Enough
// XML for the files Vega and DrawSvg write: tags, quoted attributes,
// <text> whose content is text or <tspan> lines.
std::vector<SvgElement> ParseSvg(const std::string& svg) {
  struct Group {
    double x = 0, y = 0;
    std::string mark;
  };
  std::vector<Group> groups;
  std::vector<SvgElement> out;
  bool in_defs = false;
  size_t i = 0;
  while ((i = svg.find('<', i)) != std::string::npos) {
    if (svg.compare(i, 2, "</") == 0) {
      const size_t end = svg.find('>', i);
      const std::string name = TrimSpace(svg.substr(i + 2, end - i - 2));
      if (name == "g" && !groups.empty()) groups.pop_back();
      if (name == "defs") in_defs = false;
      i = end == std::string::npos ? svg.size() : end + 1;
      continue;
    }
    if (svg.compare(i, 2, "<!") == 0 || svg.compare(i, 2, "<?") == 0) {
      const size_t end = svg.find('>', i);
      i = end == std::string::npos ? svg.size() : end + 1;
      continue;
    }
    SvgElement e;
    size_t j = i + 1;
    while (j < svg.size() && !std::isspace(static_cast<unsigned char>(svg[j])) && svg[j] != '>' &&
           svg[j] != '/') {
      ++j;
    }
    e.name = svg.substr(i + 1, j - i - 1);
    bool closed = false;  // <name ... />
    while (j < svg.size()) {
      while (j < svg.size() && std::isspace(static_cast<unsigned char>(svg[j]))) ++j;
      if (j >= svg.size() || svg[j] == '>') break;
      if (svg[j] == '/') {
        closed = true;
        ++j;
        continue;
      }
      const size_t eq = svg.find('=', j);
      if (eq == std::string::npos) break;
      const std::string key = TrimSpace(svg.substr(j, eq - j));
      const char quote = svg[eq + 1];
      const size_t close = svg.find(quote, eq + 2);
      if (close == std::string::npos) break;
      e.attrs[key] = svg.substr(eq + 2, close - eq - 2);
      j = close + 1;
    }
    i = j + 1;
    const Group outer = groups.empty() ? Group() : groups.back();
    e.x = outer.x;
    e.y = outer.y;
    e.mark = outer.mark;
    e.in_defs = in_defs;
    e.depth = static_cast<int>(groups.size());
    if (e.name == "g") {
      if (closed) continue;
      Group g = outer;
      const auto [tx, ty] = Translation(e.attrs["transform"]);
      g.x += tx;
      g.y += ty;
      const std::string& cls = e.attrs["class"];
      if (cls.rfind("mark-", 0) == 0) g.mark = cls;
      groups.push_back(g);
      continue;
    }
    if (e.name == "defs" && !closed) in_defs = true;
    if (e.name == "text" && !closed) {
      const size_t end = svg.find("</text>", i);
      const std::string content = svg.substr(i, end - i);
      if (content.find("<tspan") == std::string::npos) {
        e.lines.push_back(TrimSpace(DecodeXml(content)));
      } else {
        // Vega writes each line of a multi-line text as a <tspan>.
        for (size_t t = content.find("<tspan"); t != std::string::npos;
             t = content.find("<tspan", t + 1)) {
          const size_t from = content.find('>', t) + 1;
          e.lines.push_back(
              TrimSpace(DecodeXml(content.substr(from, content.find("</tspan>", from) - from))));
        }
      }
      i = end == std::string::npos ? svg.size() : end + 7;
    }
    out.push_back(std::move(e));
  }
  return out;
}

// The lines of every <text> of a drawing, without the empty ones.
std::vector<std::string> TextLines(const std::vector<SvgElement>& elements) {
  std::vector<std::string> out;
  for (const SvgElement& e : elements) {
    for (const std::string& line : e.lines) {
      if (!line.empty()) out.push_back(line);
    }
  }
  return out;
}

std::vector<std::string> Sorted(std::vector<std::string> v) {
  std::sort(v.begin(), v.end());
  return v;
}

// The <text> whose one line is `text` (fails the test when there is none
// or more than one).
SvgElement TextNamed(const std::vector<SvgElement>& elements, const std::string& text) {
  const SvgElement* found = nullptr;
  int count = 0;
  for (const SvgElement& e : elements) {
    if (e.name == "text" && e.lines.size() == 1 && e.lines[0] == text) {
      found = &e;
      ++count;
    }
  }
  EXPECT_EQ(count, 1) << "texts '" << text << "'";
  return found ? *found : SvgElement();
}

// Where a <text> element's anchor is drawn (its baseline's point), in the
// drawing's frame: the groups' translations, its own and its x, y.
std::pair<double, double> TextAnchor(const SvgElement& e) {
  const auto it = e.attrs.find("transform");
  const auto [tx, ty] = Translation(it == e.attrs.end() ? "" : it->second);
  return {e.x + tx + Attr(e, "x"), e.y + ty + Attr(e, "y")};
}

// The drawing's size: the width and height attributes of <svg>.
std::pair<double, double> SvgSize(const std::vector<SvgElement>& elements) {
  for (const SvgElement& e : elements) {
    if (e.name == "svg") return {Attr(e, "width"), Attr(e, "height")};
  }
  ADD_FAILURE() << "no <svg> element";
  return {0, 0};
}

// The numbers of an SVG path's data, in order.
std::vector<double> PathNumbers(const std::string& d) {
  std::vector<double> out;
  const char* p = d.c_str();
  while (*p) {
    if (std::isdigit(static_cast<unsigned char>(*p)) || *p == '-' || *p == '.') {
      char* end = nullptr;
      out.push_back(std::strtod(p, &end));
      p = end;
    } else {
      ++p;
    }
  }
  return out;
}

// ---------------------------------------------------------------------------
// The hand-written specs.

// A 640 x 20 px plot with one bottom axis of `scale` (named "x", its range
// the width) and the axis properties `axis`.
json AxisPlot(json scale, const json& axis = json::object()) {
  scale["name"] = "x";
  scale["type"] = "linear";
  scale["range"] = "width";
  json a = {{"orient", "bottom"}, {"scale", "x"}};
  a.update(axis);
  return {{"width", 640},          {"height", 20},      {"padding", 5},
          {"background", "white"}, {"scales", {scale}}, {"axes", {a}}};
}

// A colour scale of type log over data from 0.03 to 18 (viridis) and its
// gradient legend; three rects with the scale's colours.
json LogLegendSpec() {
  return json::parse(R"({
    "width": 100, "height": 100, "padding": 5,
    "data": [{"name": "v", "values": [{"s": 0.03}, {"s": 0.5}, {"s": 18}]}],
    "scales": [{"name": "colour", "type": "log", "scheme": "viridis",
                "domain": {"data": "v", "field": "s"}}],
    "legends": [{"fill": "colour", "type": "gradient", "title": "sigma"}],
    "marks": [{"type": "rect", "from": {"data": "v"}, "encode": {"enter": {
      "x": {"value": 0}, "width": {"value": 10}, "y": {"field": "s"}, "height": {"value": 5},
      "fill": {"scale": "colour", "field": "s"}}}}]})");
}

// A circle, a square and a wedge turned by 30 degrees, each of size 64
// (px^2), at (20, 25), (60, 25) and (100, 25).
json SymbolsSpec() {
  return json::parse(R"({
    "width": 140, "height": 50, "padding": 5,
    "marks": [
      {"type": "symbol", "encode": {"enter": {"x": {"value": 20}, "y": {"value": 25},
        "size": {"value": 64}, "shape": {"value": "circle"}, "fill": {"value": "#ff0000"}}}},
      {"type": "symbol", "encode": {"enter": {"x": {"value": 60}, "y": {"value": 25},
        "size": {"value": 64}, "shape": {"value": "square"}, "fill": {"value": "#00ff00"}}}},
      {"type": "symbol", "encode": {"enter": {"x": {"value": 100}, "y": {"value": 25},
        "size": {"value": 64}, "shape": {"value": "wedge"}, "angle": {"value": 30},
        "fill": {"value": "#0000ff"}}}}]})");
}

// Texts of 20 px on the line y = 50, one per baseline.
json BaselinesSpec() {
  json marks = json::array();
  double x = 0;
  for (const char* baseline : {"top", "middle", "bottom", "alphabetic"}) {
    marks.push_back({{"type", "text"},
                     {"encode",
                      {{"enter",
                        {{"x", {{"value", x}}},
                         {"y", {{"value", 50}}},
                         {"fontSize", {{"value", 20}}},
                         {"baseline", {{"value", baseline}}},
                         {"text", {{"value", baseline}}}}}}}});
    x += 110;
  }
  return {{"width", 440}, {"height", 80}, {"padding", 5}, {"marks", marks}};
}

// Three panels of 260 x 170 px on a grid of two columns, each filled by a
// rect of its own colour, titled, the first with a bottom axis (which a
// "flush" layout leaves out of the cell's size). The axis's scale has the
// panel's width as a literal range, as the figures' panels do: "width"
// would be the spec's width (GroupRangeWidthSpec).
json GridSpec() {
  json panels = json::array();
  const char* colours[] = {"#ff0000", "#00ff00", "#0000ff"};
  for (int i = 0; i < 3; ++i) {
    json p = {{"type", "group"},
              {"title", {{"text", "panel " + std::to_string(i + 1)}}},
              {"encode", {{"enter", {{"width", {{"value", 260}}}, {"height", {{"value", 170}}}}}}},
              {"marks",
               {{{"type", "rect"},
                 {"encode",
                  {{"enter",
                    {{"x", {{"value", 0}}},
                     {"y", {{"value", 0}}},
                     {"width", {{"value", 260}}},
                     {"height", {{"value", 170}}},
                     {"fill", {{"value", colours[i]}}}}}}}}}}};
    if (i == 0) {
      p["scales"] = {{{"name", "x"}, {"type", "linear"}, {"domain", {0, 4}}, {"range", {0, 260}}}};
      p["axes"] = {{{"orient", "bottom"}, {"scale", "x"}, {"title", "x of panel 1"}}};
    }
    panels.push_back(p);
  }
  return {{"padding", 5},
          {"background", "white"},
          {"layout",
           {{"columns", 2},
            {"padding", {{"row", 60}, {"column", 130}}},
            {"bounds", "flush"},
            {"align", "all"}}},
          {"marks", panels}};
}

// A panel of 260 x 170 px in a spec 100 px wide, with a scale whose range
// is "width" and its bottom axis.
json GroupRangeWidthSpec() {
  return json::parse(R"({
    "width": 100, "height": 20, "padding": 5,
    "marks": [{"type": "group",
      "encode": {"enter": {"width": {"value": 260}, "height": {"value": 170}}},
      "scales": [{"name": "x", "type": "linear", "domain": [0, 4], "range": "width"}],
      "axes": [{"orient": "bottom", "scale": "x"}]}]})");
}

// A 100 x 50 px spec with 7 px of padding whose one rect reaches from
// x = x0 to x = x1 (beyond the spec's width on both sides).
json PadSpec(double x0, double x1) {
  return {{"width", 100},
          {"height", 50},
          {"padding", 7},
          {"background", "white"},
          {"marks",
           {{{"type", "rect"},
             {"encode",
              {{"enter",
                {{"x", {{"value", x0}}},
                 {"x2", {{"value", x1}}},
                 {"y", {{"value", 0}}},
                 {"y2", {{"value", 50}}},
                 {"fill", {{"value", "#4c78a8"}}}}}}}}}}};
}

// Every hand-written spec, named.
std::vector<std::pair<std::string, json>> HandWrittenSpecs() {
  return {
      {"axis_45_610_tickCount_8",
       AxisPlot({{"domain", {45, 610}}, {"zero", false}}, {{"tickCount", 8}})},
      {"axis_0_1", AxisPlot({{"domain", {0, 1}}})},
      {"axis_0_5000", AxisPlot({{"domain", {0, 5000}}})},
      {"axis_nice_13_87", AxisPlot({{"domain", {13, 87}}, {"zero", false}, {"nice", true}})},
      // The domain of the colour scale of configs/paper.yaml's error_map_edm.
      {"axis_nice_0_0139", AxisPlot({{"domain", {0, 0.13905163910268228}}, {"nice", true}})},
      {"axis_zero_default_45_610", AxisPlot({{"domain", {45, 610}}})},
      {"log_gradient_legend", LogLegendSpec()},
      {"symbols", SymbolsSpec()},
      {"baselines", BaselinesSpec()},
      {"grid_layout", GridSpec()},
      {"pad_whole", PadSpec(-10, 130)},
      {"pad_fractional", PadSpec(-10.5, 130.2)},
  };
}

json HandWritten(const std::string& name) {
  for (const auto& [n, spec] : HandWrittenSpecs()) {
    if (n == name) return spec;
  }
  ADD_FAILURE() << "no hand-written spec " << name;
  return json::object();
}

// The drawing of a hand-written spec, read back.
std::vector<SvgElement> Drawn(const std::string& name) {
  return ParseSvg(vega::DrawSvg(HandWritten(name)));
}

// The message of the SubsetError that drawing `spec` throws ("" when none is).
std::string RefusalOf(const json& spec) {
  try {
    vega::DrawSvg(spec);
  } catch (const vega::SubsetError& e) {
    return e.what();
  }
  return "";
}

// ---------------------------------------------------------------------------
// VegaSvg: the hand-written specs.

// Horizontal distance between the anchors of two tick labels.
double LabelDistance(const std::vector<SvgElement>& svg, const std::string& a,
                     const std::string& b) {
  return TextAnchor(TextNamed(svg, b)).first - TextAnchor(TextNamed(svg, a)).first;
}

// Positions are written with 3 decimals.
constexpr double kWritten = 1e-3;

TEST(VegaSvg, LinearAxisHasD3TicksWithLabelsAtTheStepsPrecision) {
  // d3's ticks(45, 610, 8): the step 565 / 8 = 70.6 becomes 50 (7.06 <
  // sqrt(50)); Vega's format ",.0f" (the step's precision).
  const std::vector<SvgElement> a = Drawn("axis_45_610_tickCount_8");
  EXPECT_EQ(TextLines(a), (std::vector<std::string>{"50", "100", "150", "200", "250", "300", "350",
                                                    "400", "450", "500", "550", "600"}));
  // Each tick where the scale puts it: 640 px for 565 units.
  EXPECT_NEAR(LabelDistance(a, "50", "600"), 640.0 * 550 / 565, kWritten);
  // [0, 1]: a step of 0.1, so one decimal on every label.
  EXPECT_EQ(TextLines(Drawn("axis_0_1")),
            (std::vector<std::string>{"0.0", "0.1", "0.2", "0.3", "0.4", "0.5", "0.6", "0.7", "0.8",
                                      "0.9", "1.0"}));
  // [0, 5000]: thousands separated by a comma (",").
  EXPECT_EQ(TextLines(Drawn("axis_0_5000")),
            (std::vector<std::string>{"0", "500", "1,000", "1,500", "2,000", "2,500", "3,000",
                                      "3,500", "4,000", "4,500", "5,000"}));
}

// A domain far from 0 for its width (nanosecond time stamps over a few
// seconds): its tick index r0 + 1 equals r0 in floating point, so ticks that
// counted by adding 1 would never end. The drawing ends, with finite ticks.
TEST(VegaSvg, ADomainFarFromZeroForItsWidthIsDrawn) {
  const json spec = json::parse(R"({
    "width": 300, "height": 10,
    "scales": [{"name": "x", "type": "linear", "zero": false, "range": [0, 300],
                "domain": [1.6e18, 1.6000000000000005e18]}],
    "axes": [{"orient": "bottom", "scale": "x", "tickCount": 5}]})");
  const std::string svg = vega::DrawSvg(spec);
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  EXPECT_EQ(svg.find("NaN"), std::string::npos);
}

TEST(VegaSvg, NiceDomainExtendsToTheTicksAroundIt) {
  // [13, 87] with nice: [10, 90] (d3's nice with 10 ticks: a step of 10),
  // so that 10 and 90 lie on the range's ends, 640 px apart.
  const std::vector<SvgElement> a = Drawn("axis_nice_13_87");
  EXPECT_EQ(TextLines(a),
            (std::vector<std::string>{"10", "20", "30", "40", "50", "60", "70", "80", "90"}));
  EXPECT_NEAR(LabelDistance(a, "10", "90"), 640, kWritten);
  // [0, 0.139...]: Vega's d3-scale (3.x, in libjs-vega 5.22.1) nices in two
  // passes: the step 0.01 makes [0, 0.14]; the second pass rounds again
  // with the step of [0, 0.14], 0.01 again, and floor(0.14 * -100) is -15
  // in floating point (0.14 * 100 = 14.000000000000002): [0, 0.15]. The
  // ticks are 0.02 apart, 0.14 the last, at 640 * 0.14 / 0.15 px.
  const std::vector<SvgElement> b = Drawn("axis_nice_0_0139");
  EXPECT_EQ(TextLines(b), (std::vector<std::string>{"0.00", "0.02", "0.04", "0.06", "0.08", "0.10",
                                                    "0.12", "0.14"}));
  EXPECT_NEAR(LabelDistance(b, "0.00", "0.14"), 640 * 0.14 / 0.15, kWritten);
}

TEST(VegaSvg, LinearScaleIncludesZeroUnlessTold) {
  // Vega's linear scales have zero: true by default, also for a literal
  // domain: [45, 610] is drawn as [0, 610].
  const std::vector<SvgElement> a = Drawn("axis_zero_default_45_610");
  EXPECT_EQ(TextLines(a), (std::vector<std::string>{"0", "50", "100", "150", "200", "250", "300",
                                                    "350", "400", "450", "500", "550", "600"}));
  EXPECT_NEAR(LabelDistance(a, "0", "600"), 640.0 * 600 / 610, kWritten);
}

TEST(VegaSvg, LogGradientLegendLabelsTheDecades) {
  // Vega labels a gradient of a log scale over [0.03, 18] at 0.1, 1 and 10
  // only (its label count and d3's log-label filter), under the title.
  const std::vector<SvgElement> l = Drawn("log_gradient_legend");
  EXPECT_EQ(Sorted(TextLines(l)), (std::vector<std::string>{"0.1", "1", "10", "sigma"}));
  // A decade is 200 px / log10(18 / 0.03) along the gradient, larger
  // values higher up.
  const double decade = 200 / std::log10(18 / 0.03);
  const double y01 = TextAnchor(TextNamed(l, "0.1")).second;
  const double y1 = TextAnchor(TextNamed(l, "1")).second;
  const double y10 = TextAnchor(TextNamed(l, "10")).second;
  EXPECT_NEAR(y01 - y1, decade, kWritten);
  EXPECT_NEAR(y1 - y10, decade, kWritten);
}

TEST(VegaSvg, SymbolShapesAreVegas) {
  const std::vector<SvgElement> s = Drawn("symbols");
  std::vector<const SvgElement*> circles, paths;
  for (const SvgElement& e : s) {
    if (e.name == "circle") circles.push_back(&e);
    if (e.name == "path") paths.push_back(&e);
  }
  // A circle of size 64 (its area in Vega's terms, of the square around
  // it): radius sqrt(64) / 2 = 4.
  ASSERT_EQ(circles.size(), 1u);
  EXPECT_EQ(Attr(*circles[0], "r"), 4);
  EXPECT_EQ(Attr(*circles[0], "cx"), 20);
  EXPECT_EQ(Attr(*circles[0], "cy"), 25);
  ASSERT_EQ(paths.size(), 2u);
  // The square: 8 px wide about its centre.
  EXPECT_EQ(paths[0]->attrs.at("transform"), "translate(60,25)");
  const std::vector<double> square = PathNumbers(paths[0]->attrs.at("d"));
  EXPECT_EQ(square, (std::vector<double>{-4, -4, 4, -4, 4, 4, -4, 4}));
  // The wedge: Vega's narrow triangle (tip at -h - o, base at h - o, half
  // width r / 4, h = sqrt(3) / 2 r, o = h - r tan 30), turned about its
  // centre by the angle.
  EXPECT_EQ(paths[1]->attrs.at("transform"), "translate(100,25) rotate(30)");
  const double r = 4, h = std::sqrt(3.0) / 2 * r, o = h - r * std::tan(M_PI / 6);
  const std::vector<double> wedge = PathNumbers(paths[1]->attrs.at("d"));
  const std::vector<double> expected = {0, -h - o, -r / 4, h - o, r / 4, h - o};
  ASSERT_EQ(wedge.size(), expected.size());
  for (size_t i = 0; i < wedge.size(); ++i) EXPECT_NEAR(wedge[i], expected[i], kWritten) << i;
}

TEST(VegaSvg, TextBaselinesAreVegasRoundedOffsets) {
  // Vega's offsets of a baseline below the anchor (vega-scenegraph's
  // textOffset, rounded to whole px): top 0.79 size, middle 0.30 size,
  // bottom -0.21 size; for 20 px 16, 6 and -4.
  const std::vector<SvgElement> t = Drawn("baselines");
  const double alphabetic = TextAnchor(TextNamed(t, "alphabetic")).second;
  EXPECT_EQ(TextAnchor(TextNamed(t, "top")).second - alphabetic, 16);
  EXPECT_EQ(TextAnchor(TextNamed(t, "middle")).second - alphabetic, 6);
  EXPECT_EQ(TextAnchor(TextNamed(t, "bottom")).second - alphabetic, -4);
}

TEST(VegaSvg, RangeWidthInAGroupIsTheSpecsWidth) {
  // A scale's range "width" is Vega's signal `width`, which a group mark
  // does not define: in a 260 px panel of a 100 px spec the range is
  // [0, 100], the labels 0.0 and 4.0 are 100 px apart. A drawing that
  // spans the panel's 260 px is not Vega's; a refusal naming it would do.
  const json spec = GroupRangeWidthSpec();
  const std::string refusal = RefusalOf(spec);
  if (!refusal.empty()) {
    EXPECT_NE(refusal.find("width"), std::string::npos) << refusal;
    return;
  }
  EXPECT_NEAR(LabelDistance(ParseSvg(vega::DrawSvg(spec)), "0.0", "4.0"), 100, kWritten);
}

TEST(VegaSvg, GridLayoutPlacesPanelsByTheirSizeAndPadding) {
  // Two columns, flush bounds: a cell is a panel's 260 x 170 px (its axis
  // left out), 130 px between columns and 60 px between rows.
  const std::vector<SvgElement> g = Drawn("grid_layout");
  std::map<std::string, std::pair<double, double>> at;  // each panel's rect, by colour
  for (const SvgElement& e : g) {
    if (e.name == "rect" && e.attrs.count("fill")) {
      at[e.attrs.at("fill")] = {e.x + Attr(e, "x"), e.y + Attr(e, "y")};
    }
  }
  ASSERT_EQ(at.count("#ff0000") + at.count("#00ff00") + at.count("#0000ff"), 3u);
  EXPECT_EQ(at["#00ff00"].first - at["#ff0000"].first, 260 + 130);
  EXPECT_EQ(at["#00ff00"].second - at["#ff0000"].second, 0);
  EXPECT_EQ(at["#0000ff"].first - at["#ff0000"].first, 0);
  EXPECT_EQ(at["#0000ff"].second - at["#ff0000"].second, 170 + 60);
}

TEST(VegaSvg, AutosizePadIsTheContentAndThePadding) {
  // The rect reaches 10 px left of the spec's 100 px and 30 px right of
  // it: 140 x 50 px of content and 7 px of padding around it.
  EXPECT_EQ(SvgSize(Drawn("pad_whole")), std::make_pair(154.0, 64.0));
  // Vega's "pad" (vega-view's viewSizeLayout) rounds what reaches beyond
  // the spec's width up on each side on its own: ceil(10.5) + 100 +
  // ceil(30.2) = 142 px of content, 156 px with the padding.
  EXPECT_EQ(SvgSize(Drawn("pad_fractional")), std::make_pair(156.0, 64.0));
  // A bottom axis reaches tick (5) + label padding (2) + the label's box
  // (10 px for 10 px labels) below the 20 px plot: 37 px, 47 with the
  // padding. Vega's box of a text (vega-scenegraph's text bound) starts
  // round(0.8 size) above the baseline, here 8 px, at the label's anchor
  // (its "top" baseline is round(0.79 size) = 8 px below it).
  EXPECT_EQ(SvgSize(Drawn("axis_0_1")).second, 47);
}

TEST(VegaSvg, RefusesWhatIsOutsideTheSubsetNamingIt) {
  const json base = PadSpec(0, 100);
  json signals = base;
  signals["signals"] = {{{"name", "hover"}, {"value", 1}}};
  EXPECT_NE(RefusalOf(signals).find("'signals'"), std::string::npos) << RefusalOf(signals);

  json aggregate = base;
  aggregate["data"] = {{{"name", "t"},
                        {"values", {{{"a", 1}}}},
                        {"transform", {{{"type", "aggregate"}, {"groupby", {"a"}}}}}}};
  EXPECT_NE(RefusalOf(aggregate).find("aggregate"), std::string::npos) << RefusalOf(aggregate);

  json arc = base;
  arc["marks"][0]["type"] = "arc";
  EXPECT_NE(RefusalOf(arc).find("mark type 'arc'"), std::string::npos) << RefusalOf(arc);

  json band = base;
  band["scales"] = {{{"name", "b"}, {"type", "band"}, {"domain", {"a", "b"}}, {"range", "width"}}};
  EXPECT_NE(RefusalOf(band).find("scale type 'band'"), std::string::npos) << RefusalOf(band);

  // An encoding channel outside the subset, and a property of a value
  // reference outside it.
  json corner = base;
  corner["marks"][0]["encode"]["enter"]["cornerRadius"] = {{"value", 3}};
  EXPECT_NE(RefusalOf(corner).find("'cornerRadius'"), std::string::npos) << RefusalOf(corner);
  json band_ref = base;
  band_ref["marks"][0]["encode"]["enter"]["x"] = {{"value", 0}, {"band", 0.5}};
  EXPECT_NE(RefusalOf(band_ref).find("'band'"), std::string::npos) << RefusalOf(band_ref);
}

// ---------------------------------------------------------------------------
// VegaSvgAgainstVega: the same specs drawn by Vega in node.

// Node's side: evaluates the runtime (vega.js, VegaRuntime()), then draws
// spec_<i>.json for i < count.txt into vega_<i>.svg (error_<i>.txt when
// Vega cannot). Vega measures text with a canvas, which node lacks: it
// would take each character as 0.8 em wide, about 1.4 times DejaVu Sans's
// mean, and lay out titles, legends and the autosize with those widths.
// widths.json gives it DejaVu Sans's advances, the widths DrawSvg lays
// out with (vega::TextWidth), so that both lay out the same extents and
// the comparison is of Vega's rules, not of two fonts.
constexpr const char* kNodeScript = R"js(
const fs = require('fs'), path = require('path');
const dir = process.argv[2];
(0, eval)(fs.readFileSync(path.join(dir, 'vega.js'), 'utf8'));
const widths = JSON.parse(fs.readFileSync(path.join(dir, 'widths.json'), 'utf8'));
vega.textMetrics.width = function(item, text) {
  const t = text == null ? '' : String(text).trim();
  const size = item.fontSize != null ? +item.fontSize || 0 : 11;
  const w = item.fontWeight;
  const table = w === 'bold' || w === 'bolder' || +w >= 600 ? widths.bold : widths.book;
  let units = 0;
  for (let i = 0; i < t.length; ++i) {
    const c = t.charCodeAt(i);
    units += c >= 32 && c < 127 ? table[c - 32] : table['0'.charCodeAt(0) - 32];
  }
  const width = units * size / 2048;
  return item.limit > 0 ? Math.min(width, +item.limit) : width;
};
(async () => {
  const count = Number(fs.readFileSync(path.join(dir, 'count.txt'), 'utf8'));
  for (let i = 0; i < count; ++i) {
    try {
      const spec = JSON.parse(fs.readFileSync(path.join(dir, 'spec_' + i + '.json'), 'utf8'));
      const view = new vega.View(vega.parse(spec), {renderer: 'none'});
      view.logLevel(vega.Error);
      await view.runAsync();
      fs.writeFileSync(path.join(dir, 'vega_' + i + '.svg'), await view.toSVG());
      view.finalize();
    } catch (e) {
      fs.writeFileSync(path.join(dir, 'error_' + i + '.txt'), String(e && e.stack || e));
    }
  }
})();
)js";

std::string ShellQuoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

void WriteText(const fs::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::binary);
  out << text;
}

// A new empty folder for one test's files.
fs::path FreshDir(const std::string& name) {
  const fs::path dir = fs::path(::testing::TempDir()) /
                       ("rtscalib_vega_svg_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// Vega's SVG of each spec, drawn by one node process in `dir` ("" for a
// spec Vega could not draw: a failure that names it). Fails the test and
// returns false when node or the Vega modules are missing.
bool DrawWithVega(const std::vector<std::pair<std::string, json>>& specs, const fs::path& dir,
                  std::vector<std::string>* svgs) {
  std::string missing;
  const std::string& runtime = VegaRuntime(&missing);
  if (runtime.empty()) {
    ADD_FAILURE() << "the Vega modules are missing (" << missing
                  << "): scripts/install-deps.sh installs them (libjs-vega)";
    return false;
  }
  if (std::system("command -v node > /dev/null 2>&1") != 0) {
    ADD_FAILURE() << "node is missing: scripts/install-deps.sh installs it (Debian's nodejs)";
    return false;
  }
  WriteText(dir / "vega.js", runtime);
  WriteText(dir / "draw.js", kNodeScript);
  json widths = {{"book", json::array()}, {"bold", json::array()}};
  for (int c = 32; c < 127; ++c) {
    const std::string ch(1, static_cast<char>(c));
    widths["book"].push_back(vega::TextWidth(ch, 2048, false));
    widths["bold"].push_back(vega::TextWidth(ch, 2048, true));
  }
  WriteText(dir / "widths.json", widths.dump());
  WriteText(dir / "count.txt", std::to_string(specs.size()));
  for (size_t i = 0; i < specs.size(); ++i) {
    WriteText(dir / ("spec_" + std::to_string(i) + ".json"), specs[i].second.dump());
  }
  const fs::path log = dir / "node.log";
  const std::string command = "node " + ShellQuoted((dir / "draw.js").string()) + " " +
                              ShellQuoted(dir.string()) + " > " + ShellQuoted(log.string()) +
                              " 2>&1";
  const int status = std::system(command.c_str());
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    ADD_FAILURE() << "node failed (" << command << "):\n" << ReadFile(log);
    return false;
  }
  svgs->clear();
  for (size_t i = 0; i < specs.size(); ++i) {
    const std::string error = ReadFile(dir / ("error_" + std::to_string(i) + ".txt"));
    if (!error.empty()) ADD_FAILURE() << specs[i].first << ": Vega cannot draw it: " << error;
    svgs->push_back(ReadFile(dir / ("vega_" + std::to_string(i) + ".svg")));
  }
  return true;
}

// How many items of each kind of mark a drawing has (its axes' and
// legends' included).
struct ItemCounts {
  int symbols = 0;  // symbol marks' items and legend symbols
  int rects = 0;    // rect marks' items, and a group mark's frame (its fill or stroke)
  int paths = 0;    // line and area marks: one path per line or area
  int lines = 0;    // rule marks' items, axis domains, ticks and grid lines
  int images = 0;
};

// Vega's SVG: each mark is a <g class="mark-<type> role-<role>"> whose
// items are its children.
ItemCounts VegaCounts(const std::vector<SvgElement>& svg) {
  ItemCounts n;
  auto of = [](const SvgElement& e, const char* prefix) { return e.mark.rfind(prefix, 0) == 0; };
  for (const SvgElement& e : svg) {
    const auto cls = e.attrs.find("class");
    const bool background = cls != e.attrs.end() && cls->second == "background";
    if (e.name == "path" && background) {
      // A group's fill or stroke: the panel's frame.
      const bool painted = (e.attrs.count("fill") && e.attrs.at("fill") != "none" &&
                            e.attrs.at("fill") != "transparent") ||
                           (e.attrs.count("stroke") && e.attrs.at("stroke") != "none" &&
                            e.attrs.at("stroke") != "transparent");
      if (painted && of(e, "mark-group role-scope")) ++n.rects;
      continue;
    }
    if (e.name == "path" && of(e, "mark-symbol ")) ++n.symbols;
    if (e.name == "path" && of(e, "mark-rect role-mark")) ++n.rects;
    if (e.name == "path" && (of(e, "mark-line ") || of(e, "mark-area "))) ++n.paths;
    if (e.name == "line" && of(e, "mark-rule ")) ++n.lines;
    if (e.name == "image") ++n.images;
  }
  return n;
}

// DrawSvg's SVG: symbols are <circle>s and <path>s placed by a transform,
// lines and areas <path>s without one; rects <rect>s, except the
// background (outside every group), clip paths (in <defs>) and the
// gradient legends' bars (filled by a gradient).
ItemCounts OurCounts(const std::vector<SvgElement>& svg) {
  ItemCounts n;
  for (const SvgElement& e : svg) {
    if (e.in_defs) continue;
    if (e.name == "circle") ++n.symbols;
    if (e.name == "path") ++(e.attrs.count("transform") ? n.symbols : n.paths);
    if (e.name == "rect" && e.depth > 0 &&
        (!e.attrs.count("fill") || e.attrs.at("fill").rfind("url(", 0) != 0)) {
      ++n.rects;
    }
    if (e.name == "line") ++n.lines;
    if (e.name == "image") ++n.images;
  }
  return n;
}

std::string Listed(const std::vector<std::string>& texts) {
  if (texts.empty()) return "(none)";
  std::string out;
  for (const std::string& t : texts) out += (out.empty() ? "'" : ", '") + t + "'";
  return out;
}

// The texts only in a and only in b (multisets), leaving out the labels
// one side cut with an ellipsis: Vega cuts a label longer than its limit by
// its own estimate of the width (0.8 em per character in node), DrawSvg by
// DejaVu Sans's widths, so the two cut different labels, or at different
// places. A cut label and the full label it was cut from are left out
// together.
void TextDifference(std::vector<std::string> a, std::vector<std::string> b,
                    std::vector<std::string>* only_a, std::vector<std::string>* only_b) {
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  only_a->clear();
  only_b->clear();
  std::set_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(*only_a));
  std::set_difference(b.begin(), b.end(), a.begin(), a.end(), std::back_inserter(*only_b));
  const std::string ellipsis = "\xE2\x80\xA6";
  auto drop_cut = [&](std::vector<std::string>* cut, std::vector<std::string>* other) {
    for (size_t i = 0; i < cut->size();) {
      const size_t at = (*cut)[i].find(ellipsis);
      if (at == std::string::npos) {
        ++i;
        continue;
      }
      const std::string prefix = (*cut)[i].substr(0, at);
      // The label it was cut from on the other side: the one that starts
      // as it does (either cut shorter than the other).
      for (size_t j = 0; j < other->size(); ++j) {
        const std::string& o = (*other)[j];
        const std::string o_prefix = o.substr(0, o.find(ellipsis));
        if (o.rfind(prefix, 0) == 0 || prefix.rfind(o_prefix, 0) == 0) {
          other->erase(other->begin() + static_cast<std::ptrdiff_t>(j));
          break;
        }
      }
      cut->erase(cut->begin() + static_cast<std::ptrdiff_t>(i));
    }
  };
  drop_cut(only_a, only_b);
  drop_cut(only_b, only_a);
}

// The size of a drawing may differ from Vega's by this fraction. The text
// widths are the same (kNodeScript), but the cut labels differ (Vega cuts
// by its estimate), and so do details of the guides' layout that this
// check is not about (the line height of a subtitle, the rows of a symbol
// legend; 5 % at most in the figures of the runs below). It finds a figure
// drawn at another scale, or with a part missing or added.
constexpr double kSizeTolerance = 0.15;

// `spec` drawn by DrawSvg against `vega_svg`, Vega's drawing of it.
void ExpectSameAsVega(const std::string& name, const json& spec, const std::string& vega_svg) {
  std::string ours;
  try {
    ours = vega::DrawSvg(spec);
  } catch (const vega::SubsetError& e) {
    ADD_FAILURE() << name << ": DrawSvg refuses it: " << e.what();
    return;
  }
  if (vega_svg.empty()) return;  // DrawWithVega failed for it
  const std::vector<SvgElement> vega_drawing = ParseSvg(vega_svg), our_drawing = ParseSvg(ours);

  std::vector<std::string> only_vega, only_ours;
  TextDifference(TextLines(vega_drawing), TextLines(our_drawing), &only_vega, &only_ours);
  EXPECT_TRUE(only_vega.empty() && only_ours.empty())
      << name << ": the texts differ\n  only in Vega's: " << Listed(only_vega)
      << "\n  only in DrawSvg's: " << Listed(only_ours);

  const ItemCounts vega_items = VegaCounts(vega_drawing), our_items = OurCounts(our_drawing);
  EXPECT_EQ(our_items.symbols, vega_items.symbols)
      << name << ": symbols (marks' items and legend symbols)";
  EXPECT_EQ(our_items.rects, vega_items.rects)
      << name << ": rects (rect marks' items and group frames)";
  EXPECT_EQ(our_items.paths, vega_items.paths) << name << ": lines and areas";
  EXPECT_EQ(our_items.lines, vega_items.lines)
      << name << ": rules (marks' items, axis domains, ticks, grid)";
  EXPECT_EQ(our_items.images, vega_items.images) << name << ": images";

  const auto [vw, vh] = SvgSize(vega_drawing);
  const auto [ow, oh] = SvgSize(our_drawing);
  EXPECT_NEAR(ow, vw, kSizeTolerance * vw) << name << ": width (Vega's " << vw << " px)";
  EXPECT_NEAR(oh, vh, kSizeTolerance * vh) << name << ": height (Vega's " << vh << " px)";
}

void ExpectAllSameAsVega(const std::vector<std::pair<std::string, json>>& specs,
                         const std::string& test) {
  const fs::path dir = FreshDir(test);
  std::vector<std::string> svgs;
  if (!DrawWithVega(specs, dir, &svgs)) return;
  for (size_t i = 0; i < specs.size(); ++i) {
    ExpectSameAsVega(specs[i].first, specs[i].second, svgs[i]);
  }
  if (::testing::Test::HasFailure()) {
    // Both drawings beside the spec, to look at.
    for (size_t i = 0; i < specs.size(); ++i) {
      try {
        WriteText(dir / ("ours_" + std::to_string(i) + ".svg"), vega::DrawSvg(specs[i].second));
      } catch (const vega::SubsetError&) {
      }
    }
    std::cerr << "spec_<i>.json, Vega's drawing vega_<i>.svg and DrawSvg's ours_<i>.svg are in "
              << dir << "\n";
  } else {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
}

// The figures of `config` run twice into `dir` (the second run draws the
// ladder of runs, the first has no earlier run), by name.
std::vector<std::pair<std::string, json>> FiguresOfRun(const std::string& config,
                                                       const fs::path& dir) {
  RunArgs args;
  args.config = std::string(RTSCALIB_SOURCE_DIR) + "/configs/" + config;
  args.output = (dir / "out").string();
  args.quiet = true;
  std::vector<std::pair<std::string, json>> out;
  for (int run = 0; run < 2; ++run) {
    if (RunCalibration(args) != 0) {
      ADD_FAILURE() << "rtscalib --config configs/" << config << " failed";
      return out;
    }
  }
  std::vector<fs::path> files;
  for (const fs::directory_entry& e : fs::directory_iterator(dir / "out" / "latest" / "figures")) {
    const std::string f = e.path().filename().string();
    if (f.size() > 8 && f.compare(f.size() - 8, 8, ".vg.json") == 0) files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  for (const fs::path& p : files) {
    const std::string f = p.filename().string();
    out.emplace_back(f.substr(0, f.size() - 8), json::parse(ReadFile(p)));
  }
  return out;
}

std::vector<std::string> Names(const std::vector<std::pair<std::string, json>>& specs) {
  std::vector<std::string> out;
  for (const auto& [name, spec] : specs) out.push_back(name);
  return out;
}

bool Has(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

TEST(VegaSvgAgainstVega, HandWrittenSpecs) {
  ExpectAllSameAsVega(HandWrittenSpecs(), "hand_written");
}

// OpenCV's sample photos of a camera on its own: photos with their
// residual arrows, image residuals, residuals against the variables,
// histograms, the uncertainty map and the ladder of runs.
TEST(VegaSvgAgainstVega, FiguresOfACameraOnABench) {
  const fs::path dir = FreshDir("bench_run");
  const std::vector<std::pair<std::string, json>> figures = FiguresOfRun("bench.yaml", dir);
  const std::vector<std::string> names = Names(figures);
  EXPECT_TRUE(Has(names, "ladder_runs")) << Listed(names);
  EXPECT_TRUE(Has(names, "uncertainty_zoom0")) << Listed(names);
  ExpectAllSameAsVega(figures, "bench_vega");
  if (!::testing::Test::HasFailure()) {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
}

// Klug's plan on a simulated instrument: besides the residual figures, the
// error maps over phi and theta with their gradient legends.
TEST(VegaSvgAgainstVega, FiguresOfASimulatedInstrument) {
  const fs::path dir = FreshDir("paper_run");
  const std::vector<std::pair<std::string, json>> figures = FiguresOfRun("paper.yaml", dir);
  const std::vector<std::string> names = Names(figures);
  EXPECT_TRUE(Has(names, "error_map_edm")) << Listed(names);
  EXPECT_TRUE(Has(names, "error_map_cam_zoom0")) << Listed(names);
  EXPECT_TRUE(Has(names, "ladder_runs")) << Listed(names);
  ExpectAllSameAsVega(figures, "paper_vega");
  if (!::testing::Test::HasFailure()) {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
}

// The specs of the figures in `dir` (a folder of figures/*.vg.json), by name.
std::vector<std::pair<std::string, json>> FiguresIn(const fs::path& dir) {
  std::vector<fs::path> files;
  for (const fs::directory_entry& e : fs::directory_iterator(dir)) {
    const std::string f = e.path().filename().string();
    if (f.size() > 8 && f.compare(f.size() - 8, 8, ".vg.json") == 0) files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  std::vector<std::pair<std::string, json>> out;
  for (const fs::path& p : files) {
    const std::string f = p.filename().string();
    out.emplace_back(f.substr(0, f.size() - 8), json::parse(ReadFile(p)));
  }
  return out;
}

// The figures of the other commands: `rtscalib plan` of an instrument (its
// readings per face, a legend of colours and one of shapes) and of a camera
// on its own (where to hold the board: outlines faceted per photo, clipped
// to the image), and `rtscalib compare`'s projection difference of two
// calibrations (a colour scale of zero width: two runs of one config).
TEST(VegaSvgAgainstVega, FiguresOfThePlanAndCompareCommands) {
  const fs::path dir = FreshDir("commands");
  std::vector<std::pair<std::string, json>> figures;
  for (const char* config : {"plan.yaml", "plan_camera.yaml"}) {
    PlanArgs args;
    args.config = std::string(RTSCALIB_SOURCE_DIR) + "/configs/" + config;
    args.output = (dir / config).string();
    args.quiet = true;
    ASSERT_EQ(RunPlan(args), 0) << config;
    for (auto& [name, spec] : FiguresIn(dir / config / "figures")) {
      figures.emplace_back(std::string(config) + "_" + name, std::move(spec));
    }
  }
  RunArgs run;
  run.config = std::string(RTSCALIB_SOURCE_DIR) + "/configs/bench.yaml";
  run.quiet = true;
  for (const char* out : {"a", "b"}) {
    run.output = (dir / out).string();
    ASSERT_EQ(RunCalibration(run), 0);
  }
  CompareArgs compare;
  compare.a = (dir / "a" / "latest" / "model.yaml").string();
  compare.b = (dir / "b" / "latest" / "model.yaml").string();
  compare.output = (dir / "compare").string();
  ASSERT_EQ(RunCompare(compare), 0);
  for (auto& [name, spec] : FiguresIn(dir / "compare" / "figures")) {
    figures.emplace_back("compare_" + name, std::move(spec));
  }
  const std::vector<std::string> names = Names(figures);
  EXPECT_TRUE(Has(names, "plan.yaml_plan")) << Listed(names);
  EXPECT_TRUE(Has(names, "plan_camera.yaml_plan")) << Listed(names);
  EXPECT_TRUE(Has(names, "compare_compare_zoom0")) << Listed(names);
  ExpectAllSameAsVega(figures, "commands_vega");
  if (!::testing::Test::HasFailure()) {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
}

}  // namespace
}  // namespace rtscalib::app

#include "app/ladder_figures.h"

#include <algorithm>

namespace rtscalib::app {

using nlohmann::json;

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

namespace {

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

}  // namespace

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

}  // namespace rtscalib::app

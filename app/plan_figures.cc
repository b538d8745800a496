#include "app/plan_figures.h"

#include <cmath>
#include <map>
#include <set>
#include <string>
#include <tuple>

#include "app/plot/vega_spec.h"
#include "libcalib/text/number_text.h"

namespace rtscalib::app {

using nlohmann::json;

namespace {

// A camera on its own: where the board is held for each photo, its outline
// in the image of its zoom (one panel per zoom), numbered in the order of
// plan.csv and coloured by what the photo determines most.
Figure BoardPosesFigure(const PlanResult& plan) {
  Figure f;
  f.name = "plan";
  f.section = "plan";
  f.title = "Where to hold the board: " + std::to_string(plan.shots.size()) + " photos";
  json spec = Chart(f.title,
                    "each outline: the board's printed pattern as the camera will see it "
                    "(the a-priori camera); number: the photo's row in plan.csv; colour: what "
                    "it determines most; the distance, turn and tilt are plan.csv's columns");
  spec["scales"] = json::array({{{"name", "colour"},
                                 {"type", "ordinal"},
                                 {"domain", {{"data", "outlines"}, {"field", "determines"}}},
                                 {"range", {{"scheme", "category10"}}}}});
  spec["legends"] = json::array({{{"stroke", "colour"}, {"title", "determines"}}});
  json outlines = json::array(), labels = json::array();
  // Photos of one place (turned or tilted alike far) share one label: "2, 3".
  std::map<std::tuple<int, long, long>, size_t> label_at;
  int order = 0;
  for (const PlanShot& s : plan.shots) {
    ++order;
    if (!s.board_pose) continue;
    const std::string determines = s.determines.empty() ? "-" : s.determines;
    const size_t n = s.board_outline.size();
    for (size_t k = 0; k <= n && n >= 3; ++k) {
      const Eigen::Vector2d& p = s.board_outline[k % n];
      outlines.push_back({{"order", order},
                          {"zoom", s.pointing.zoom},
                          {"k", k},
                          {"u", p.x()},
                          {"v", p.y()},
                          {"determines", determines}});
    }
    const std::tuple<int, long, long> at{s.pointing.zoom, std::lround(s.board.centre_px.x()),
                                         std::lround(s.board.centre_px.y())};
    if (const auto it = label_at.find(at); it != label_at.end()) {
      json& l = labels[it->second];
      l["text"] = l["text"].get<std::string>() + ", " + std::to_string(order);
      continue;
    }
    label_at[at] = labels.size();
    labels.push_back({{"text", std::to_string(order)},
                      {"zoom", s.pointing.zoom},
                      {"u", s.board.centre_px.x()},
                      {"v", s.board.centre_px.y()},
                      {"distance", s.board.distance_m},
                      {"determines", determines}});
  }
  spec["data"] = json::array(
      {{{"name", "outlines"}, {"values", outlines}}, {{"name", "labels"}, {"values", labels}}});
  spec["layout"] = Grid(plan.projection.size(), 20, 20);
  for (const PredictedProjection& z : plan.projection) {
    json panel = {{"type", "group"}, {"title", "zoom " + std::to_string(z.zoom)}};
    int w = 0, h = 0;
    ImageScales(&panel, z.width, z.height, &w, &h);
    panel["encode"] = {{"enter", {{"width", {{"value", w}}}, {"height", {{"value", h}}}}}};
    panel.erase("width");
    panel.erase("height");
    const std::string zoom = std::to_string(z.zoom);
    panel["data"] =
        json::array({{{"name", "outline_" + zoom},
                      {"source", "outlines"},
                      {"transform", {{{"type", "filter"}, {"expr", "datum.zoom == " + zoom}}}}},
                     {{"name", "label_" + zoom},
                      {"source", "labels"},
                      {"transform", {{{"type", "filter"}, {"expr", "datum.zoom == " + zoom}}}}}});
    // Each outline clipped to the image: a tag board may reach beyond it
    // (its photo shows part of it).
    auto parent = [](const char* size) { return json{{"field", {{"group", size}}}}; };
    json each = {
        {"type", "group"},
        {"from",
         {{"facet", {{"name", "one_" + zoom}, {"data", "outline_" + zoom}, {"groupby", "order"}}}}},
        {"clip", true},
        {"encode", {{"enter", {{"width", parent("width")}, {"height", parent("height")}}}}},
        {"marks", json::array({Mark("line", "one_" + zoom,
                                    {{"x", Field("u", "u")},
                                     {"y", Field("v", "v")},
                                     {"stroke", Field("colour", "determines")},
                                     {"strokeWidth", {{"value", 1.5}}}})})}};
    const json tip = Tip({{"photos", "datum.text"},
                          {"distance [m]", "format(datum.distance, '.2f')"},
                          {"determines", "datum.determines"}});
    panel["marks"] = json::array({each, Mark("text", "label_" + zoom,
                                             {{"x", Field("u", "u")},
                                              {"y", Field("v", "v")},
                                              {"text", {{"field", "text"}}},
                                              {"align", {{"value", "center"}}},
                                              {"baseline", {{"value", "middle"}}},
                                              {"fontSize", {{"value", 11}}},
                                              {"fill", Field("colour", "determines")},
                                              {"tooltip", tip}})});
    spec["marks"].push_back(panel);
  }
  f.spec = spec;
  f.caption =
      "Where to hold the board for each planned photo of a camera on its own (rtscalib plan, "
      "docs/plan.md): its outline as the camera will see it, numbered as the rows of plan.csv, "
      "coloured by the goal (or constant) whose predicted variance the photo lowers most.";
  f.summary = {{"shots", plan.shots.size()}};
  return f;
}

}  // namespace

Figure PlanFigure(const PlanResult& plan) {
  for (const PlanShot& s : plan.shots) {
    if (s.board_pose) return BoardPosesFigure(plan);
  }
  Figure f;
  f.name = "plan";
  f.section = "plan";
  f.title = "The planned shots: " + std::to_string(plan.shots.size()) + " photos";
  json values = json::array();
  std::set<int> faces;
  int order = 0;
  for (const PlanShot& s : plan.shots) {
    faces.insert(s.pointing.face);
    values.push_back({{"order", ++order},
                      {"phi", s.pointing.phi * 180.0 / M_PI},
                      {"theta", s.pointing.theta * 180.0 / M_PI},
                      {"face", s.pointing.face},
                      {"zoom", "zoom " + std::to_string(s.pointing.zoom)},
                      {"placement", s.pointing.placement},
                      {"determines", s.determines.empty() ? "-" : s.determines}});
  }
  if (faces.empty()) faces.insert(1);
  json spec = Chart(f.title,
                    "the readings of each photo, one panel per face: horizontal angle phi "
                    "against zenith angle theta (the zenith at the top); colour: what the shot "
                    "determines most; shape: zoom; grey line: the order of measuring, motor "
                    "travel " +
                        Significant(plan.motor_travel_rad * 180.0 / M_PI, 3) + " deg");
  spec["data"] = json::array({{{"name", "shots"}, {"values", values}}});
  spec["scales"] = json::array(
      {{{"name", "colour"},
        {"type", "ordinal"},
        {"domain", {{"data", "shots"}, {"field", "determines"}}},
        {"range", {{"scheme", "category20"}}}},
       {{"name", "shape"},
        {"type", "ordinal"},
        {"domain", {{"data", "shots"}, {"field", "zoom"}}},
        {"range",
         {"circle", "square", "triangle-up", "diamond", "cross", "triangle-down", "wedge"}}}});
  spec["legends"] = json::array(
      {{{"fill", "colour"}, {"title", "determines"}}, {{"shape", "shape"}, {"title", "zoom"}}});
  spec["layout"] = Grid(faces.size(), 20, 70);
  const json tip = Tip({{"shot", "datum.order"},
                        {"zoom", "datum.zoom"},
                        {"placement", "datum.placement"},
                        {"determines", "datum.determines"}});
  for (int face : faces) {
    // A face's readings: theta in [0, 180] in face 1, [180, 360] in face 2,
    // the zenith (0, or 360 in face 2) at the top either way.
    const std::string name = "face_" + std::to_string(face);
    json panel = {
        {"type", "group"},
        {"title", "face " + std::to_string(face)},
        {"encode", {{"enter", {{"width", {{"value", 420}}}, {"height", {{"value", 240}}}}}}},
        {"data",
         json::array(
             {{{"name", name},
               {"source", "shots"},
               {"transform",
                {{{"type", "filter"}, {"expr", "datum.face == " + std::to_string(face)}}}}}})},
        {"scales", json::array({Linear("x", {0, 360}, {0, 420}),
                                Linear("y", face == 2 ? json{360, 180} : json{0, 180}, {0, 240})})},
        {"axes",
         json::array({Axis("bottom", "x", "phi [deg]"), Axis("left", "y", "theta [deg]")})}};
    panel["marks"] = json::array({Mark("line", name,
                                       {{"x", Field("x", "phi")},
                                        {"y", Field("y", "theta")},
                                        {"stroke", {{"value", "#bbbbbb"}}},
                                        {"strokeWidth", {{"value", 1}}}}),
                                  Mark("symbol", name,
                                       {{"x", Field("x", "phi")},
                                        {"y", Field("y", "theta")},
                                        {"fill", Field("colour", "determines")},
                                        {"shape", Field("shape", "zoom")},
                                        {"size", {{"value", 70}}},
                                        {"opacity", {{"value", 0.85}}},
                                        {"tooltip", tip}})});
    spec["marks"].push_back(panel);
  }
  f.spec = spec;
  f.caption =
      "Where the planned photos point (rtscalib plan, docs/plan.md), one panel per face: each "
      "mark is one photo at its readings, coloured by the goal (or constant) whose predicted "
      "variance it lowers most, joined in the order of measuring.";
  f.summary = {{"shots", plan.shots.size()},
               {"motor_travel_deg", plan.motor_travel_rad * 180 / M_PI}};
  return f;
}

}  // namespace rtscalib::app

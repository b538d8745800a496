#include "app/plan_figures.h"

#include <cmath>
#include <string>

#include "app/vega_spec.h"
#include "libcalib/text/number_text.h"

namespace rtscalib::app {

using nlohmann::json;

Figure PlanFigure(const PlanResult& plan) {
  Figure f;
  f.name = "plan";
  f.section = "plan";
  f.title = "The planned shots: " + std::to_string(plan.shots.size()) + " photos";
  json values = json::array();
  int order = 0;
  for (const PlanShot& s : plan.shots) {
    const double phi_deg = s.pointing.phi * 180.0 / M_PI;
    values.push_back({{"order", ++order},
                      {"phi", phi_deg},
                      {"theta", s.pointing.theta * 180.0 / M_PI},
                      {"face", "face " + std::to_string(s.pointing.face)},
                      {"zoom", s.pointing.zoom},
                      {"placement", s.pointing.placement},
                      {"determines", s.determines.empty() ? "-" : s.determines}});
  }
  const int width = 640, height = 360;
  f.spec = {
      {"$schema", "https://vega.github.io/schema/vega/v5.json"},
      {"width", width},
      {"height", height},
      {"padding", 8},
      // The title block of every figure (a line per clause of the subtitle).
      {"title", Chart(f.title,
                      "horizontal angle phi against zenith angle theta (the readings of "
                      "each face); colour: what the shot determines most; size: zoom; grey "
                      "line: the order of measuring, motor travel " +
                          Significant(plan.motor_travel_rad * 180.0 / M_PI, 3) + " deg")["title"]},
      {"data", json::array({{{"name", "shots"}, {"values", values}}})},
      {"scales",
       json::array({{{"name", "x"}, {"type", "linear"}, {"domain", {0, 360}}, {"range", "width"}},
                    {{"name", "y"},
                     {"type", "linear"},
                     {"domain", {0, 360}},
                     {"range", "height"},
                     {"zero", false}},
                    {{"name", "colour"},
                     {"type", "ordinal"},
                     {"domain", {{"data", "shots"}, {"field", "determines"}}},
                     {"range", {{"scheme", "category20"}}}},
                    {{"name", "shape"},
                     {"type", "ordinal"},
                     {"domain", {"face 1", "face 2"}},
                     {"range", {"circle", "triangle-up"}}},
                    {{"name", "size"},
                     {"type", "linear"},
                     {"domain", {{"data", "shots"}, {"field", "zoom"}}},
                     {"range", {40, 200}},
                     {"zero", false}}})},
      {"axes", json::array({{{"orient", "bottom"}, {"scale", "x"}, {"title", "phi [deg]"}},
                            {{"orient", "left"}, {"scale", "y"}, {"title", "theta [deg]"}}})},
      {"legends", json::array({{{"fill", "colour"}, {"title", "determines"}},
                               {{"shape", "shape"}, {"title", "face"}}})},
      {"marks",
       json::array(
           {{{"type", "line"},
             {"from", {{"data", "shots"}}},
             {"encode",
              {{"enter",
                {{"x", {{"scale", "x"}, {"field", "phi"}}},
                 {"y", {{"scale", "y"}, {"field", "theta"}}},
                 {"stroke", {{"value", "#bbbbbb"}}},
                 {"strokeWidth", {{"value", 1}}}}}}}},
            {{"type", "symbol"},
             {"from", {{"data", "shots"}}},
             {"encode",
              {{"enter",
                {{"x", {{"scale", "x"}, {"field", "phi"}}},
                 {"y", {{"scale", "y"}, {"field", "theta"}}},
                 {"fill", {{"scale", "colour"}, {"field", "determines"}}},
                 {"shape", {{"scale", "shape"}, {"field", "face"}}},
                 {"size", {{"scale", "size"}, {"field", "zoom"}}},
                 {"opacity", {{"value", 0.8}}},
                 {"tooltip",
                  {{"signal",
                    "{'shot': datum.order, 'zoom': datum.zoom, 'face': datum.face, "
                    "'placement': datum.placement, 'determines': datum.determines}"}}}}}}}}})}};
  f.caption =
      "Where the planned photos point (rtscalib plan, docs/plan.md): each mark is one photo, "
      "coloured by the goal (or constant) whose predicted variance it lowers most.";
  f.summary = {{"shots", plan.shots.size()},
               {"motor_travel_deg", plan.motor_travel_rad * 180 / M_PI}};
  return f;
}

}  // namespace rtscalib::app

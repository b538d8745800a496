#include "libcalib/plan/settings.h"

#include <filesystem>

#include "libcalib/text/number_text.h"

namespace rtscalib {

PlanSettings ReadPlanSettings(const YamlNode& section, const std::string& config_dir) {
  PlanSettings s;
  s.present = true;
  PlanOptions& o = s.options;
  if (const std::optional<YamlNode> goal = section.Find("goal")) {
    if (const std::optional<YamlNode> sigmas = goal->Find("sigmas")) {
      for (const YamlNode::Entry& e : sigmas->Entries()) {
        const double v = e.value.AsDouble();
        if (!(v > 0)) e.value.Fail("a sigma > 0 in the constant's report unit");
        o.goal.sigmas.push_back({e.key.AsString(), v});
      }
    }
    goal->Read("projection_px", &o.goal.projection_px);
    if (o.goal.projection_px < 0) goal->Require("projection_px").Fail("a number >= 0 (pixels)");
  }
  if (section.Read("faces", &o.faces)) {
    for (int f : o.faces) {
      if (f != 1 && f != 2) section.Require("faces").Fail("a list of faces 1 and/or 2");
    }
    if (o.faces.empty()) section.Require("faces").Fail("a list of faces 1 and/or 2");
  }
  if (section.Read("zooms", &o.zooms)) {
    for (int z : o.zooms) {
      if (z < 0) section.Require("zooms").Fail("a list of zoom levels >= 0");
    }
  }
  if (section.Read("max_shots", &o.max_shots) && o.max_shots < 1)
    section.Require("max_shots").Fail("an integer >= 1");
  if (section.Read("candidates_per_board", &o.candidates_per_board) && o.candidates_per_board < 1)
    section.Require("candidates_per_board").Fail("an integer >= 1");
  if (section.Read("fill", &o.fill) && !(o.fill > 0 && o.fill <= 1))
    section.Require("fill").Fail("a number in (0, 1]");
  section.Read("exchange", &o.exchange);
  if (const std::optional<YamlNode> n = section.Find("board_poses")) {
    const std::string v = n->AsString();
    if (v != "known" && v != "unknown") n->FailChoice({"known", "unknown"});
    s.board_poses_known = v == "known";
  }
  auto read_path = [&](const char* key, std::string* out) {
    std::string text;
    if (!section.Read(key, &text) || text.empty()) return;
    const std::filesystem::path path(text);
    *out = (path.is_absolute() ? path : std::filesystem::path(config_dir) / path)
               .lexically_normal()
               .string();
  };
  read_path("prior_model", &s.prior_model);
  read_path("board", &s.board);
  return s;
}

YAML::Node PlanSettingsYaml(const PlanSettings& s) {
  const PlanOptions& o = s.options;
  YAML::Node n(YAML::NodeType::Map);
  YAML::Node goal(YAML::NodeType::Map);
  YAML::Node sigmas(YAML::NodeType::Map);
  for (const auto& [name, sigma] : o.goal.sigmas) sigmas[name] = YamlDouble(sigma, true);
  goal["sigmas"] = sigmas;
  goal["projection_px"] = YamlDouble(o.goal.projection_px, true);
  n["goal"] = goal;
  n["faces"] = o.faces;
  n["zooms"] = o.zooms;
  n["max_shots"] = o.max_shots;
  n["candidates_per_board"] = o.candidates_per_board;
  n["fill"] = YamlDouble(o.fill, true);
  n["exchange"] = o.exchange;
  if (s.board_poses_known) n["board_poses"] = *s.board_poses_known ? "known" : "unknown";
  if (!s.prior_model.empty()) n["prior_model"] = s.prior_model;
  if (!s.board.empty()) n["board"] = s.board;
  return n;
}

ConfigSection PlanConfigSection(PlanSettings* settings, const std::string& config_dir) {
  return {
      "plan",
      [settings, config_dir](const YamlNode& n) { *settings = ReadPlanSettings(n, config_dir); },
      [settings] { return settings->present ? PlanSettingsYaml(*settings) : YAML::Node(); }};
}

}  // namespace rtscalib

#include "render/settings.h"

#include <functional>
#include <vector>

#include "libcalib/text/number_text.h"

namespace rtscalib::render {
namespace {

// One rule per checked key: the key, whether the value is valid, what a
// valid value is. Check() and the reader share them.
struct Rule {
  const char* key;
  std::function<bool(const RenderSettings&)> ok;
  const char* expected;
};

const std::vector<Rule>& Rules() {
  static const std::vector<Rule> kRules = {
      {"jobs", [](const RenderSettings& s) { return s.jobs >= 1; }, "an integer >= 1"},
      {"supersample", [](const RenderSettings& s) { return s.supersample >= 1; },
       "an integer >= 1"},
      {"noise_sigma", [](const RenderSettings& s) { return s.noise_sigma >= 0; },
       "a number >= 0 (grey levels)"},
      {"blur_sigma", [](const RenderSettings& s) { return s.blur_sigma >= 0; },
       "a number >= 0 (pixels)"},
      {"exposure", [](const RenderSettings& s) { return s.exposure > 0; }, "a number > 0"},
      {"family", [](const RenderSettings& s) { return !s.family.empty(); },
       "an AprilTag family name such as tag36h11"},
  };
  return kRules;
}

}  // namespace

std::string RenderSettings::Check() const {
  for (const Rule& rule : Rules()) {
    if (!rule.ok(*this)) return std::string("render.") + rule.key + ": expected " + rule.expected;
  }
  return "";
}

RenderSettings ReadRenderSettings(const YamlNode& section) {
  RenderSettings s;
  s.enabled = true;
  section.Read("enabled", &s.enabled);
  section.Read("jobs", &s.jobs);
  section.Read("supersample", &s.supersample);
  section.Read("noise_sigma", &s.noise_sigma);
  section.Read("blur_sigma", &s.blur_sigma);
  section.Read("exposure", &s.exposure);
  section.Read("family", &s.family);
  if (const std::optional<YamlNode> n = section.Find("board_poses")) {
    const std::string v = n->AsString();
    if (v != "known" && v != "unknown") n->FailChoice({"known", "unknown"});
    s.board_poses_known = v == "known";
  }
  for (const Rule& rule : Rules()) {
    // A default always passes, so a failing rule has its key in the file.
    if (!rule.ok(s)) section.Require(rule.key).Fail(rule.expected);
  }
  return s;
}

YAML::Node RenderSettingsYaml(const RenderSettings& s) {
  YAML::Node n(YAML::NodeType::Map);
  n["enabled"] = s.enabled;
  n["jobs"] = s.jobs;
  n["supersample"] = s.supersample;
  // Shortest round-trip text, as DumpConfig writes every other number.
  n["noise_sigma"] = YamlDouble(s.noise_sigma, /*shortest=*/true);
  n["blur_sigma"] = YamlDouble(s.blur_sigma, /*shortest=*/true);
  n["exposure"] = YamlDouble(s.exposure, /*shortest=*/true);
  n["family"] = s.family;
  n["board_poses"] = s.board_poses_known ? "known" : "unknown";
  return n;
}

ConfigSection RenderConfigSection(RenderSettings* settings) {
  return {"render", [settings](const YamlNode& n) { *settings = ReadRenderSettings(n); },
          [settings] { return settings->enabled ? RenderSettingsYaml(*settings) : YAML::Node(); }};
}

}  // namespace rtscalib::render

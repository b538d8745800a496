// Sessions of the example configs for the planner's tests.
#pragma once

#include <string>

#include "libcalib/config/config.h"
#include "libcalib/plan/session.h"
#include "libcalib/plan/settings.h"
#include "render/settings.h"

namespace rtscalib::testing_plan {

struct LoadedSession {
  RunConfig config;
  PlanSettings settings;
  PlanSession session;
};

// configs/<name>, its `render` and `plan` sections read by their modules.
inline LoadedSession LoadSession(const std::string& name) {
  LoadedSession s;
  render::RenderSettings render;
  const std::string dir = std::string(RTSCALIB_SOURCE_DIR) + "/configs";
  s.config = LoadConfig(dir + "/" + name, {render::RenderConfigSection(&render),
                                           PlanConfigSection(&s.settings, dir)});
  s.session = SessionFromConfig(s.config, s.settings);
  return s;
}

}  // namespace rtscalib::testing_plan

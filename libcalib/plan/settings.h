// The config's `plan` section (SPEC 8, docs/plan.md): the goal, faces,
// zooms and budget of `rtscalib plan`. The plan module reads and checks its
// own section; the config loader (libcalib/io/config.h) hands it over through
// a ConfigSection, so an unknown or bad key inside `plan:` is an error naming
// key path, file and line.
//
//   plan:
//     goal:
//       sigmas: {hz_eccentricity.e: 0.5, cam[0].fx: 0.2}  # report units
//       projection_px: 0.05
//     faces: [1, 2]
//     zooms: [0, 1, 2]
//     max_shots: 400
//     candidates_per_board: 16   # pointings per board, zoom and face
//     fill: 0.7                  # how much of the view the pattern spans
//     exchange: true             # drop shots the goal does not need
//     board_poses: known         # known | unknown (default: unknown with
//                                # simulate.placements, known with simulate.targets)
//     prior_model: model.yaml    # a previous calibration (default: simulate.truth)
//     board: targets.yaml        # a camera on its own: the board to hold, the first
//                                # of this targets.yaml (default: simulate's first)
#pragma once

#include <yaml-cpp/yaml.h>

#include <optional>
#include <string>

#include "libcalib/io/config_section.h"
#include "libcalib/io/yaml_reader.h"
#include "libcalib/plan/planner.h"

namespace rtscalib {

struct PlanSettings {
  bool present = false;  // the config has a `plan` section
  PlanOptions options;
  std::optional<bool> board_poses_known;  // unset: from the simulate section
  std::string prior_model;                // absolute path, "" = simulate.truth
  std::string board;                      // absolute path of a targets.yaml, "" = simulate's
};

// Reads the `plan` section at `section`; relative paths are relative to
// `config_dir`. Throws InputError for a bad value.
PlanSettings ReadPlanSettings(const YamlNode& section, const std::string& config_dir);

// The section with every key written out (for DumpConfig).
YAML::Node PlanSettingsYaml(const PlanSettings& settings);

// The ConfigSection that reads `plan` into *settings.
ConfigSection PlanConfigSection(PlanSettings* settings, const std::string& config_dir);

}  // namespace rtscalib

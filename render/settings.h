// The config's `render` section (docs/config.md): how the run renders the
// simulated shots and detects the AprilTags in them (app/render_stage.h).
// The render module reads and checks its own section; the config loader
// (libcalib/config/config.h) hands it over through a ConfigSection
// (libcalib/io/config_section.h), so an unknown or bad key inside `render:`
// is an error naming key path, file and line, whether or not the run renders. No VTK here: the binary reads the section
// even when built without the renderer.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>

#include "libcalib/io/config_section.h"
#include "libcalib/io/yaml_reader.h"

namespace rtscalib::render {

struct RenderSettings {
  bool enabled = false;             // true as soon as the config has a `render` section
  int jobs = 2;                     // worker processes
  int supersample = 2;              // render at k x the size, then k x k box average
  double noise_sigma = 1.0;         // Gaussian sensor noise [grey levels]
  double blur_sigma = 0.0;          // Gaussian optical blur [px]
  double exposure = 1.0;            // gain on all grey levels before the noise
  std::string family = "tag36h11";  // AprilTag family searched for
  // Whether the targets.yaml of the written photo session gives the boards'
  // poses (`known`, as if surveyed) or leaves them out (`unknown`, as a user
  // without a tracker has them: estimated with everything else, SPEC 7).
  // The truth poses are always written to truth_targets.yaml for tests.
  bool board_poses_known = false;
  // Empty if valid, else "render.<key>: expected ...".
  std::string Check() const;
};

// Reads the `render` section at `section` (its node carries file, key path
// and line for messages): keys absent keep the defaults, `enabled` defaults
// to true. Throws InputError for a bad value; keys it does not know are left
// for the document's unknown-key check.
RenderSettings ReadRenderSettings(const YamlNode& section);

// The section with every key written out (for DumpConfig).
YAML::Node RenderSettingsYaml(const RenderSettings& settings);

// The ConfigSection that reads `render` into *settings (left at its defaults,
// enabled = false, when the config has no such section) and dumps it back.
ConfigSection RenderConfigSection(RenderSettings* settings);

}  // namespace rtscalib::render

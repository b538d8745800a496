// A section of the run config (docs/config.md) that a module reads itself:
// the module (render/settings.h for `render`) owns its keys, their defaults
// and their checks; the config loader (libcalib/config/config.h) finds the
// section, hands its node over and checks what is left.
//
// `read` gets the section's node before unknown keys are checked: every key
// it does not ask for is an error naming key path, file and line, like
// everywhere else in the config (YamlDocument::CheckAllKeysUsed). `dump`
// gives the section as the module read it (every default written out), or a
// null node to leave it out of the effective config.
#pragma once

#include <yaml-cpp/yaml.h>

#include <functional>
#include <string>

#include "libcalib/io/yaml_reader.h"

namespace rtscalib {

struct ConfigSection {
  std::string key;  // the top-level key
  std::function<void(const YamlNode&)> read;
  std::function<YAML::Node()> dump;
};

}  // namespace rtscalib

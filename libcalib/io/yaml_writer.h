// Helpers for the YAML files rtscalib writes (model.yaml, the effective config).
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>

namespace rtscalib {

// Writes free text (a path, a label, metadata) so that it reads back
// unchanged: yaml-cpp writes a text with a carriage return or another control
// character as a plain scalar, and "a\r" before the line break then reads back
// as "a"; such texts are written double-quoted (escaped), all others as before.
void EmitYamlText(YAML::Emitter& e, const std::string& text);

}  // namespace rtscalib

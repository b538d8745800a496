// Helpers for the YAML files rtscalib writes (model.yaml, the effective config).
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <string>

namespace rtscalib {

// Writes free text (a path, a label, metadata) so that it reads back
// unchanged: yaml-cpp writes a text with a carriage return or another control
// character as a plain scalar, and "a\r" before the line break then reads back
// as "a"; such texts are written double-quoted (escaped), all others as before.
void EmitYamlText(YAML::Emitter& e, const std::string& text);

// [x0, x1, ...] in flow style, each number as YamlDouble(x, shortest) rather
// than the emitter's own double output (which writes 1e-05 as
// 1.0000000000000001e-05): shortest for files people read and edit (the
// effective config), %.17g for model.yaml.
void EmitNumbers(YAML::Emitter& e, const double* x, size_t n, bool shortest);

}  // namespace rtscalib

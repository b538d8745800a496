#include "libcalib/io/yaml_writer.h"

#include "libcalib/text/number_text.h"

namespace rtscalib {

void EmitYamlText(YAML::Emitter& e, const std::string& text) {
  for (unsigned char c : text) {
    if (c < 0x20 || c == 0x7f) {
      e << YAML::DoubleQuoted << text;
      return;
    }
  }
  e << text;
}

void EmitNumbers(YAML::Emitter& e, const double* x, size_t n, bool shortest) {
  e << YAML::Flow << YAML::BeginSeq;
  for (size_t i = 0; i < n; ++i) e << YamlDouble(x[i], shortest);
  e << YAML::EndSeq;
}

}  // namespace rtscalib

#include "libcalib/io/yaml_writer.h"

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

}  // namespace rtscalib

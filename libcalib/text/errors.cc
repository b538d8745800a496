#include "libcalib/text/errors.h"

#include <cassert>

namespace rtscalib {

std::string InputError::Format() const {
  std::string out = file;
  if (line > 0) {
    out += ":" + std::to_string(line);
    if (position > 0) out += ":" + std::to_string(position);
  }
  if (!column.empty()) {
    out += ": column '" + column + "'";
  } else if (!key.empty()) {
    out += ": key '" + key + "'";
  } else if (!subject.empty()) {
    out += ": " + subject;
  }
  out += ": expected " + expected + ", got '" + got + "'";
  return out;
}

InputError InputError::Make(InputError fields) {
  InputError out(fields.Format());
  out.file = std::move(fields.file);
  out.line = fields.line;
  out.position = fields.position;
  out.column = std::move(fields.column);
  out.key = std::move(fields.key);
  out.subject = std::move(fields.subject);
  out.expected = std::move(fields.expected);
  out.got = std::move(fields.got);
  return out;
}

InputError InputError::Cell(const std::string& file, int line, const std::string& column,
                            const std::string& expected, const std::string& got) {
  InputError e("");
  e.file = file;
  e.line = line;
  e.column = column;
  e.expected = expected;
  e.got = got;
  return Make(std::move(e));
}

InputError InputError::Key(const std::string& file, const std::string& key, int line, int position,
                           const std::string& expected, const std::string& got) {
  InputError e("");
  e.file = file;
  e.key = key;
  e.line = line;
  e.position = position;
  e.expected = expected;
  e.got = got;
  return Make(std::move(e));
}

InputError InputError::File(const std::string& file, int line, const std::string& subject,
                            const std::string& expected, const std::string& got, int position) {
  InputError e("");
  e.file = file;
  e.line = line;
  e.position = position;
  e.subject = subject;
  e.expected = expected;
  e.got = got;
  return Make(std::move(e));
}

InputError InputError::Combine(const std::vector<InputError>& errors) {
  assert(!errors.empty());
  std::string message = errors.front().what();
  for (size_t i = 1; i < errors.size(); ++i) message += std::string("\n") + errors[i].what();
  InputError out(message);
  const InputError& first = errors.front();
  out.file = first.file;
  out.line = first.line;
  out.position = first.position;
  out.column = first.column;
  out.key = first.key;
  out.subject = first.subject;
  out.expected = first.expected;
  out.got = first.got;
  return out;
}

}  // namespace rtscalib

// Bad user input: an exception that says where (file, line, CSV column or
// YAML key path), what was expected and what came, so that a user can fix the
// file without reading code (architecture.md; Kalibr-style messages).
//
// what() formats, by what is known:
//   records.csv:12: column 'face': expected 1 or 2, got '3'
//   run.yaml:4:3: key 'model.efects': expected a known key ..., got 'efects'
//   run.yaml: key 'model.effects[2]': expected ..., got '...'
//   records.csv:1: no rows: expected ..., got '...'
// Programmer errors are not InputErrors; they may abort.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace rtscalib {

struct InputError : std::runtime_error {
  std::string file;
  int line = 0;         // 1-based; 0 = not tied to a line
  int position = 0;     // 1-based character column within the line (YAML); 0 = unknown
  std::string column;   // CSV column name, if the error is in one cell
  std::string key;      // YAML key path such as "model.effects[2]"
  std::string subject;  // what was wrong when neither column nor key applies ("header", "no rows")
  std::string expected;
  std::string got;

  // A CSV cell (or a whole CSV column when line is the header line).
  static InputError Cell(const std::string& file, int line, const std::string& column,
                         const std::string& expected, const std::string& got);
  // A YAML value; line/position are 1-based, 0 when unknown.
  static InputError Key(const std::string& file, const std::string& key, int line, int position,
                        const std::string& expected, const std::string& got);
  // Anything else about a file (cannot open, no rows, bad header).
  static InputError File(const std::string& file, int line, const std::string& subject,
                         const std::string& expected, const std::string& got, int position = 0);
  // One error carrying several: the first one's fields, every message in
  // what() (one per line), so a user sees all typos of a config at once.
  static InputError Combine(const std::vector<InputError>& errors);

  // The one-line message of these fields (what() of a non-combined error).
  std::string Format() const;

 private:
  explicit InputError(const std::string& message) : std::runtime_error(message) {}
  static InputError Make(InputError fields);
};

}  // namespace rtscalib

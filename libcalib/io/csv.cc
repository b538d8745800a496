#include "libcalib/io/csv.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <set>
#include <stdexcept>

#include "libcalib/text/errors.h"
#include "libcalib/text/number_text.h"

namespace rtscalib {
namespace {

bool IsSpace(char c) { return c == ' ' || c == '\t'; }

std::string Trim(const std::string& s) {
  size_t b = 0, e = s.size();
  while (b < e && IsSpace(s[b])) ++b;
  while (e > b && IsSpace(s[e - 1])) --e;
  return s.substr(b, e - b);
}

// Splits one line into trimmed fields; quoted fields keep their inner text
// verbatim.
std::vector<std::string> SplitFields(const std::string& line, const std::string& file,
                                     int line_no) {
  std::vector<std::string> fields;
  size_t i = 0;
  while (true) {
    while (i < line.size() && IsSpace(line[i])) ++i;
    std::string field;
    if (i < line.size() && line[i] == '"') {
      ++i;
      bool closed = false;
      while (i < line.size()) {
        if (line[i] == '"') {
          if (i + 1 < line.size() && line[i + 1] == '"') {
            field += '"';
            i += 2;
            continue;
          }
          closed = true;
          ++i;
          break;
        }
        field += line[i++];
      }
      if (!closed) {
        throw InputError::File(file, line_no, "field " + std::to_string(fields.size() + 1),
                               "a closing '\"' on the same line", line);
      }
      while (i < line.size() && IsSpace(line[i])) ++i;
      if (i < line.size() && line[i] != ',') {
        throw InputError::File(file, line_no, "field " + std::to_string(fields.size() + 1),
                               "a ',' after a quoted field", line);
      }
    } else {
      const size_t comma = line.find(',', i);
      field = Trim(line.substr(i, comma == std::string::npos ? std::string::npos : comma - i));
      i = comma == std::string::npos ? line.size() : comma;
    }
    fields.push_back(field);
    if (i >= line.size()) break;
    ++i;  // the comma
  }
  return fields;
}

// The encoding of a file that is not UTF-8 (or ASCII): by its byte-order mark
// on the first line, by NUL bytes (UTF-16/32 without a mark) on any line; ""
// when neither is seen. Such a file would otherwise read as one odd field.
std::string WideEncoding(const std::string& line, bool first) {
  if (first) {
    if (line.compare(0, 4, std::string("\xFF\xFE\0\0", 4)) == 0)
      return "UTF-32 (little-endian BOM)";
    if (line.compare(0, 4, std::string("\0\0\xFE\xFF", 4)) == 0) return "UTF-32 (big-endian BOM)";
    if (line.compare(0, 2, "\xFF\xFE") == 0) return "UTF-16 (little-endian BOM)";
    if (line.compare(0, 2, "\xFE\xFF") == 0) return "UTF-16 (big-endian BOM)";
  }
  if (line.find('\0') != std::string::npos) return "UTF-16 or UTF-32 (NUL bytes)";
  return "";
}

bool IsSkipped(const std::string& line) {
  for (char c : line) {
    if (IsSpace(c)) continue;
    return c == '#';
  }
  return true;  // blank
}

}  // namespace

CsvTable CsvTable::Read(const std::string& path, const Columns& columns) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw InputError::File(path, 0, "cannot open file", "a readable CSV file",
                           std::strerror(errno));
  }
  return Parse(in, path, columns);
}

CsvTable CsvTable::Parse(std::istream& in, const std::string& name, const Columns& columns) {
  CsvTable table;
  table.file_ = name;
  std::string line;
  int line_no = 0;
  bool have_header = false;
  int header_line = 0;
  size_t num_columns = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line_no == 1 && line.compare(0, 3, "\xEF\xBB\xBF") == 0) line.erase(0, 3);
    const std::string wide = WideEncoding(line, line_no == 1);
    if (!wide.empty()) {
      throw InputError::File(name, line_no, "encoding", "a UTF-8 text file (save it as UTF-8)",
                             "file is " + wide);
    }
    if (IsSkipped(line)) continue;
    std::vector<std::string> fields = SplitFields(line, name, line_no);
    if (!have_header) {
      have_header = true;
      header_line = line_no;
      num_columns = fields.size();
      for (size_t c = 0; c < fields.size(); ++c) {
        if (fields[c].empty()) {
          throw InputError::File(name, line_no, "header",
                                 "a column name in field " + std::to_string(c + 1), "");
        }
        if (!table.index_.emplace(fields[c], static_cast<int>(c)).second) {
          throw InputError::Cell(name, line_no, fields[c], "each column name once in the header",
                                 line);
        }
      }
      continue;
    }
    if (fields.size() != num_columns) {
      throw InputError::File(name, line_no, "row",
                             std::to_string(num_columns) + " fields like the header on line " +
                                 std::to_string(header_line),
                             std::to_string(fields.size()) + " fields");
    }
    table.rows_.push_back({line_no, std::move(fields)});
  }
  if (!have_header) {
    throw InputError::File(name, 0, "no rows", "a header row and at least one data row",
                           "an empty file");
  }
  std::vector<std::string> missing;
  for (const std::string& required : columns.required) {
    if (!table.Has(required)) missing.push_back(required);
  }
  if (!missing.empty()) {
    std::vector<std::string> present(num_columns);
    for (const auto& [column_name, index] : table.index_) present[index] = column_name;
    std::string expected = "a column named '" + missing.front() + "' in the header (required";
    if (missing.size() > 1) {
      expected +=
          "; also missing: " + Join(std::vector<std::string>(missing.begin() + 1, missing.end()));
    }
    throw InputError::Cell(name, header_line, missing.front(), expected + ")", Join(present));
  }
  std::vector<std::string> ignored;
  const std::set<std::string> known = [&] {
    std::set<std::string> s(columns.required.begin(), columns.required.end());
    s.insert(columns.optional.begin(), columns.optional.end());
    return s;
  }();
  // Extra columns in header order; numeric ones may be kept as covariates.
  std::vector<std::pair<int, std::string>> extra;
  for (const auto& [column_name, index] : table.index_) {
    if (!known.count(column_name)) extra.emplace_back(index, column_name);
  }
  std::sort(extra.begin(), extra.end());
  for (const auto& [index, column_name] : extra) {
    bool numeric = columns.covariates, any = false;
    for (size_t r = 0; numeric && r < table.rows_.size(); ++r) {
      const std::string& cell = table.rows_[r].cells[index];
      if (cell.empty()) continue;
      any = true;
      numeric = ParseFiniteDouble(cell).has_value();
    }
    if (numeric && any) {
      table.covariates_.push_back(column_name);
    } else {
      ignored.push_back(column_name);
    }
  }
  if (!table.covariates_.empty()) {
    table.notes_.push_back(name + ":" + std::to_string(header_line) + ": column" +
                           (table.covariates_.size() > 1 ? "s " : " ") +
                           Join(table.covariates_) +
                           " kept as covariate" + (table.covariates_.size() > 1 ? "s" : "") +
                           " (numbers; the diagnosis tests the residuals against them)");
  }
  std::sort(ignored.begin(), ignored.end());
  if (!ignored.empty()) {
    table.notes_.push_back(name + ":" + std::to_string(header_line) + ": ignored column" +
                           (ignored.size() > 1 ? "s " : " ") + Join(ignored) +
                           " (not part of this file's format)");
  }
  if (table.rows_.empty()) {
    throw InputError::File(name, header_line, "no rows", "at least one data row after the header",
                           "header only");
  }
  return table;
}

const std::string& CsvTable::Text(int row, const std::string& column) const {
  static const std::string kEmpty;
  const auto it = index_.find(column);
  if (it == index_.end()) return kEmpty;
  return rows_[row].cells[it->second];
}

double CsvTable::Covariate(int row, int k) const {
  const std::string& text = Text(row, covariates_.at(k));
  if (text.empty()) return std::numeric_limits<double>::quiet_NaN();
  return Number(row, covariates_[k]);
}

double CsvTable::Number(int row, const std::string& column) const {
  const std::string& text = Text(row, column);
  const std::optional<double> value = ParseFiniteDouble(text);
  if (!value) Fail(row, column, "a finite number");
  return *value;
}

long long CsvTable::Integer(int row, const std::string& column) const {
  const std::string& text = Text(row, column);
  const std::optional<long long> value = ParseInteger(text);
  if (!value) Fail(row, column, "an integer");
  return *value;
}

bool CsvTable::OptionalReading(int row, AngleUnit unit, double* phi, double* theta) const {
  const bool no_phi = Empty(row, "phi"), no_theta = Empty(row, "theta");
  if (no_phi && no_theta) {
    *phi = 0;
    *theta = M_PI / 2;
    return false;
  }
  if (no_phi != no_theta) {
    Fail(row, no_phi ? "phi" : "theta",
         std::string("a reading beside ") + (no_phi ? "theta" : "phi") +
             " (both phi and theta, or neither for a camera-only calibration)");
  }
  *phi = Angle(row, "phi", unit);
  *theta = Angle(row, "theta", unit);
  return true;
}

void CsvTable::Fail(int row, const std::string& column, const std::string& expected) const {
  throw InputError::Cell(file_, rows_[row].line, column, expected, Text(row, column));
}

// ---------------------------------------------------------------------------

namespace {
std::string Quote(const std::string& field) {
  // A leading '#' would make the reader take the line for a comment.
  const bool needs_quotes =
      field.find_first_of(",\"") != std::string::npos ||
      (!field.empty() && (IsSpace(field.front()) || IsSpace(field.back()) || field.front() == '#'));
  if (!needs_quotes) return field;
  std::string out = "\"";
  for (char c : field) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}
}  // namespace

CsvWriter::CsvWriter(const std::string& path, const std::vector<std::string>& header)
    : path_(path), num_columns_(header.size()) {
  file_ = std::fopen(path.c_str(), "wb");
  if (!file_) {
    throw std::runtime_error("cannot create " + path + ": " + std::strerror(errno));
  }
  Row(header);
}

CsvWriter::~CsvWriter() {
  if (file_) std::fclose(file_);
}

void CsvWriter::Row(const std::vector<std::string>& fields) {
  if (fields.size() != num_columns_) {
    throw std::logic_error("CsvWriter::Row: " + std::to_string(fields.size()) + " fields for " +
                           std::to_string(num_columns_) + " columns in " + path_);
  }
  std::string line;
  for (size_t i = 0; i < fields.size(); ++i) {
    if (fields[i].find_first_of("\r\n") != std::string::npos) {
      throw std::invalid_argument("CSV field with a line break cannot be written to " + path_ +
                                  ": '" + fields[i] + "'");
    }
    if (i) line += ',';
    line += Quote(fields[i]);
  }
  line += '\n';
  std::fwrite(line.data(), 1, line.size(), file_);
}

void CsvWriter::Close() {
  if (!file_) return;
  const bool failed = std::ferror(file_) != 0;
  const bool close_failed = std::fclose(file_) != 0;
  file_ = nullptr;
  if (failed || close_failed) throw std::runtime_error("error writing " + path_);
}

}  // namespace rtscalib

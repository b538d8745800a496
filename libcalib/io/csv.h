// A small, strict CSV reader and a full-precision writer for the interchange
// files of SPEC 3 (records.csv, pixels.csv).
//
// Reading rules (chosen so that hand-edited and spreadsheet-exported files
// work, but nothing is silently dropped):
//   - the first non-comment, non-blank line is the header; columns may come in
//     any order; names are case-sensitive;
//   - lines whose first non-space character is '#', and blank lines, are
//     skipped everywhere;
//   - fields are comma separated and trimmed of spaces and tabs; a field may
//     be double-quoted (RFC 4180, "" = one quote) to hold commas, but never a
//     line break;
//   - every data row has exactly as many fields as the header;
//   - a file needs at least one data row ("no rows" otherwise);
//   - required columns missing -> InputError naming the column; columns that
//     are neither required nor optional are ignored and listed in notes(),
//     except, for a reader that keeps covariates (Columns::covariates), the
//     ones whose every non-empty cell is a finite number: those are kept as
//     named covariates (temperature, time, ...; covariates(), Covariate());
//   - CRLF line ends and a UTF-8 byte-order mark are accepted; a UTF-16 or
//     UTF-32 file (byte-order mark or NUL bytes) is an error.
// Numbers must be finite decimal numbers (NaN/Inf are errors), integers must
// have an integral value ("2" and "2.0" are both the integer 2).
#pragma once

#include <cstdio>
#include <istream>
#include <map>
#include <string>
#include <vector>

#include "libcalib/model/angle_unit.h"

namespace rtscalib {

class CsvTable {
 public:
  struct Columns {
    std::vector<std::string> required;
    std::vector<std::string> optional;
    bool covariates = false;  // keep numeric extra columns as covariates
  };

  // Reads `path`; messages name the file by `path`.
  static CsvTable Read(const std::string& path, const Columns& columns);
  // Reads a stream; messages name it `name`.
  static CsvTable Parse(std::istream& in, const std::string& name, const Columns& columns);

  const std::string& file() const { return file_; }
  int NumRows() const { return static_cast<int>(rows_.size()); }
  int Line(int row) const { return rows_[row].line; }
  // Whether the header has this column (optional columns may be absent).
  bool Has(const std::string& column) const { return index_.count(column) > 0; }
  // The trimmed text of a cell; "" when the column is absent.
  const std::string& Text(int row, const std::string& column) const;
  bool Empty(int row, const std::string& column) const { return Text(row, column).empty(); }
  // A finite number; InputError naming file, line and column otherwise.
  double Number(int row, const std::string& column) const;
  // A reading phi or theta given in `unit`, in radians: the one place where
  // a file's angles become radians (libcalib/model/angle_unit.h).
  double Angle(int row, const std::string& column, AngleUnit unit) const {
    return ReadingToRadians(Number(row, column), unit);
  }
  // The reading phi, theta of a row whose readings may be left empty (a
  // camera-only session, SPEC 7.1): false when both cells are empty (then
  // *phi = 0, *theta = pi/2, the horizontal pointing of face 1, which the
  // kinematics never read: the row says it has no reading), true with both
  // read as Angle() otherwise; InputError when only one of them is empty.
  bool OptionalReading(int row, AngleUnit unit, double* phi, double* theta) const;
  // An integral value (see above); InputError otherwise.
  long long Integer(int row, const std::string& column) const;
  // Notes about the file for the run log (ignored columns, covariates kept).
  const std::vector<std::string>& notes() const { return notes_; }
  // The extra numeric columns kept as covariates, in header order.
  const std::vector<std::string>& covariates() const { return covariates_; }
  // Covariate k of a row: its number, NaN when the cell is empty.
  double Covariate(int row, int k) const;
  // An InputError pointing at one cell, for checks done by the caller.
  [[noreturn]] void Fail(int row, const std::string& column, const std::string& expected) const;

 private:
  struct Row {
    int line = 0;
    std::vector<std::string> cells;
  };
  std::string file_;
  std::map<std::string, int> index_;
  std::vector<Row> rows_;
  std::vector<std::string> notes_;
  std::vector<std::string> covariates_;
};

// Writes a CSV file row by row. Numbers are written with %.17g so that reading
// them back gives the same doubles bit for bit.
class CsvWriter {
 public:
  // Throws std::runtime_error if the file cannot be created.
  CsvWriter(const std::string& path, const std::vector<std::string>& header);
  ~CsvWriter();
  CsvWriter(const CsvWriter&) = delete;
  CsvWriter& operator=(const CsvWriter&) = delete;

  // Fields are quoted when they contain a comma, a quote or leading/trailing
  // spaces, so that the reader gives back the same text.
  void Row(const std::vector<std::string>& fields);
  // Flushes and closes; throws std::runtime_error on a write error (disk full).
  void Close();

 private:
  std::string path_;
  size_t num_columns_;
  std::FILE* file_ = nullptr;
};

}  // namespace rtscalib

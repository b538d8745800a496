// Numbers as text, the same way in every file rtscalib reads or writes.
//
// Parsing is locale independent (std::from_chars), accepts an optional
// leading '+', and rejects anything that is not completely a decimal number:
// NaN, Inf, hexadecimal, trailing text. Writing uses %.17g, which reads back
// to the same double bit for bit.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "libcalib/model/angle_unit.h"

namespace rtscalib {

// A finite double, or nullopt.
std::optional<double> ParseFiniteDouble(std::string_view text);
// Like ParseFiniteDouble, but also accepts nan/inf spellings (for sigmas,
// which are NaN when a covariance could not be computed).
std::optional<double> ParseDouble(std::string_view text);
// An integer written as an integer or as an integral decimal ("2", "2.0",
// "2e0"), in the range of long long; nullopt otherwise.
std::optional<long long> ParseInteger(std::string_view text);
// %.17g: what the data files and model.yaml use.
std::string FormatDouble(double x);
// A reading of `rad` radians written in `unit` (%.17g), chosen so that
// reading it back in `unit` (ReadingToRadians) gives `rad` exactly whenever
// such a number lies within a few ulps of rad / pi * HalfTurn(unit): a file read
// in degrees and written back keeps its readings.
std::string FormatReading(double rad, AngleUnit unit);
// The shortest text that reads back to the same double ("1e-05" rather than
// "1.0000000000000001e-05"): for files that people read, such as configs.
std::string FormatShortestDouble(double x);
// A YAML scalar for x: FormatDouble or FormatShortestDouble, and YAML's own
// .nan/.inf/-.inf for the non-finite values.
std::string YamlDouble(double x, bool shortest = false);
// One number through a printf format ("%.3g", "%+.2f"): messages and reports.
std::string Fmt(const char* printf_format, double x);
// x to `digits` significant digits (%g): magnitudes in messages, where 17
// digits would hide the point.
std::string Significant(double x, int digits = 6);
// Appends Significant(x, digits) to `out` (1 <= digits <= 17): the same
// text as printf's %.*g, written by std::to_chars without a format string
// or a locale, for tables of many thousand numbers.
void AppendSignificant(std::string* out, double x, int digits);
// "a, b, c": names listed in a message.
std::string Join(const std::vector<std::string>& items);

}  // namespace rtscalib

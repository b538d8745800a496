#include "libcalib/text/number_text.h"

#include <charconv>
#include <cmath>
#include <cstdio>

namespace rtscalib {

std::optional<double> ParseDouble(std::string_view text) {
  // from_chars rejects a leading '+', which people and other tools write.
  if (!text.empty() && text.front() == '+') {
    text.remove_prefix(1);
    if (!text.empty() && text.front() == '-') return std::nullopt;  // "+-1"
  }
  double value = 0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc() || ptr != end) return std::nullopt;
  return value;
}

std::optional<double> ParseFiniteDouble(std::string_view text) {
  const std::optional<double> value = ParseDouble(text);
  if (!value || !std::isfinite(*value)) return std::nullopt;
  return value;
}

std::optional<long long> ParseInteger(std::string_view text) {
  const std::optional<double> value = ParseFiniteDouble(text);
  // 2^63 is the first double outside long long.
  if (!value || std::trunc(*value) != *value || std::fabs(*value) >= 9.2233720368547758e18) {
    return std::nullopt;
  }
  // Integers too large for a double to hold exactly are parsed as integers.
  long long exact = 0;
  std::string_view t = text;
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);  // "+-1" was rejected above
  const char* end = t.data() + t.size();
  const auto [ptr, ec] = std::from_chars(t.data(), end, exact);
  if (ec == std::errc() && ptr == end) return exact;
  return static_cast<long long>(*value);
}

std::string FormatDouble(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.17g", x);
  return buffer;
}

std::string FormatReading(double rad, AngleUnit unit) {
  if (unit == AngleUnit::kRad) return FormatDouble(rad);
  double best = rad / M_PI * HalfTurn(unit), up = best, down = best;
  for (int step = 0; step < 4 && ReadingToRadians(best, unit) != rad; ++step) {
    up = std::nextafter(up, INFINITY);
    down = std::nextafter(down, -INFINITY);
    if (ReadingToRadians(up, unit) == rad) best = up;
    if (ReadingToRadians(down, unit) == rad) best = down;
  }
  return FormatDouble(best);
}

std::string FormatShortestDouble(double x) {
  char buffer[32];
  const auto [ptr, ec] = std::to_chars(buffer, buffer + sizeof(buffer), x);
  if (ec != std::errc()) return FormatDouble(x);
  return std::string(buffer, ptr);
}

std::string YamlDouble(double x, bool shortest) {
  if (std::isnan(x)) return ".nan";
  if (std::isinf(x)) return x > 0 ? ".inf" : "-.inf";
  return shortest ? FormatShortestDouble(x) : FormatDouble(x);
}

std::string Join(const std::vector<std::string>& items) {
  std::string out;
  for (const std::string& s : items) out += (out.empty() ? "" : ", ") + s;
  return out;
}

std::string Fmt(const char* printf_format, double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, printf_format, x);
  return buf;
}

std::string Significant(double x, int digits) {
  std::string out;
  AppendSignificant(&out, x, digits);
  return out;
}

void AppendSignificant(std::string* out, double x, int digits) {
  // C++17 [utility.to.chars]: chars_format::general with a precision is
  // printf's %.*g in the "C" locale, "inf" and "nan" as printf spells them.
  char buf[40];
  const auto [ptr, ec] =
      std::to_chars(buf, buf + sizeof buf, x, std::chars_format::general, digits);
  if (ec != std::errc()) {
    std::snprintf(buf, sizeof buf, "%.*g", digits, x);
    out->append(buf);
    return;
  }
  out->append(buf, ptr);
}

}  // namespace rtscalib

#include "app/plot/vega_expression.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

namespace rtscalib::app::vega {
// A named namespace: app/ builds as unity batches, where an anonymous namespace is shared by
// the batch's files (vega_svg.cc among them) and its names must not meet theirs.
namespace expression_impl {
namespace {

using Json = nlohmann::json;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// ---------------------------------------------------------------------------------------------
// Text: the expressions and the data are UTF-8, JavaScript's strings UTF-16. Lengths, string
// order and a format's width count UTF-16 units as JavaScript does.

// The code point at s[*i], advancing *i past it; a malformed byte reads as U+FFFD.
char32_t DecodeUtf8(std::string_view s, size_t* i) {
  const auto b0 = static_cast<unsigned char>(s[*i]);
  if (b0 < 0x80) {
    ++*i;
    return b0;
  }
  int extra = 0;
  char32_t cp = 0;
  if (b0 >= 0xC2 && b0 < 0xE0) {
    extra = 1, cp = b0 & 0x1F;
  } else if (b0 >= 0xE0 && b0 < 0xF0) {
    extra = 2, cp = b0 & 0x0F;
  } else if (b0 >= 0xF0 && b0 < 0xF5) {
    extra = 3, cp = b0 & 0x07;
  } else {
    ++*i;
    return 0xFFFD;
  }
  for (int k = 1; k <= extra; ++k) {
    if (*i + k >= s.size() || (static_cast<unsigned char>(s[*i + k]) & 0xC0) != 0x80) {
      ++*i;
      return 0xFFFD;
    }
    cp = (cp << 6) | (static_cast<unsigned char>(s[*i + k]) & 0x3F);
  }
  *i += 1 + extra;
  return cp;
}

void AppendUtf8(char32_t cp, std::string* out) {
  if (cp >= 0xD800 && cp < 0xE000) cp = 0xFFFD;  // a lone surrogate has no UTF-8
  if (cp < 0x80) {
    out->push_back(static_cast<char>(cp));
  } else if (cp < 0x800) {
    out->push_back(static_cast<char>(0xC0 | (cp >> 6)));
    out->push_back(static_cast<char>(0x80 | (cp & 0x3F)));
  } else if (cp < 0x10000) {
    out->push_back(static_cast<char>(0xE0 | (cp >> 12)));
    out->push_back(static_cast<char>(0x80 | ((cp >> 6) & 0x3F)));
    out->push_back(static_cast<char>(0x80 | (cp & 0x3F)));
  } else {
    out->push_back(static_cast<char>(0xF0 | (cp >> 18)));
    out->push_back(static_cast<char>(0x80 | ((cp >> 12) & 0x3F)));
    out->push_back(static_cast<char>(0x80 | ((cp >> 6) & 0x3F)));
    out->push_back(static_cast<char>(0x80 | (cp & 0x3F)));
  }
}

bool IsAscii(std::string_view s) {
  return std::all_of(s.begin(), s.end(),
                     [](char c) { return static_cast<unsigned char>(c) < 0x80; });
}

// JavaScript's s.length.
size_t Utf16Length(std::string_view s) {
  if (IsAscii(s)) return s.size();
  size_t n = 0;
  for (size_t i = 0; i < s.size();) n += DecodeUtf8(s, &i) > 0xFFFF ? 2 : 1;
  return n;
}

// JavaScript's a < b (-1), a == b (0), a > b (1) on strings: UTF-16 code unit order, which is
// UTF-8's byte order except between U+E000..U+FFFF and the astral planes (surrogates sort
// below the former).
int CompareStrings(std::string_view a, std::string_view b) {
  size_t i = 0;
  while (i < a.size() && i < b.size() && a[i] == b[i]) ++i;
  if (i == a.size() || i == b.size()) return a.size() == b.size() ? 0 : i == a.size() ? -1 : 1;
  while (i > 0 && (static_cast<unsigned char>(a[i]) & 0xC0) == 0x80) --i;  // to the character
  size_t ia = i, ib = i;
  char32_t ca = DecodeUtf8(a, &ia), cb = DecodeUtf8(b, &ib);
  auto first_unit = [](char32_t cp) { return cp > 0xFFFF ? 0xD800 + ((cp - 0x10000) >> 10) : cp; };
  if ((ca > 0xFFFF) != (cb > 0xFFFF)) ca = first_unit(ca), cb = first_unit(cb);
  return ca < cb ? -1 : 1;
}

// JavaScript's s[index]: one UTF-16 unit (half of an astral character reads as U+FFFD).
std::optional<std::string> Utf16Unit(std::string_view s, size_t index) {
  size_t unit = 0;
  for (size_t i = 0; i < s.size();) {
    const char32_t cp = DecodeUtf8(s, &i);
    const size_t units = cp > 0xFFFF ? 2 : 1;
    if (index < unit + units) {
      std::string out;
      AppendUtf8(units == 2 ? 0xFFFD : cp, &out);
      return out;
    }
    unit += units;
  }
  return std::nullopt;
}

// JavaScript's whitespace and line terminators (String.prototype.trim, Number("  1 ")).
bool IsJsSpace(char32_t cp) {
  return cp == ' ' || (cp >= 0x09 && cp <= 0x0D) || cp == 0xA0 || cp == 0x1680 ||
         (cp >= 0x2000 && cp <= 0x200A) || cp == 0x2028 || cp == 0x2029 || cp == 0x202F ||
         cp == 0x205F || cp == 0x3000 || cp == 0xFEFF;
}

std::string_view TrimJsSpace(std::string_view s) {
  size_t begin = 0;
  while (begin < s.size()) {
    size_t next = begin;
    if (!IsJsSpace(DecodeUtf8(s, &next))) break;
    begin = next;
  }
  size_t end = begin, last = begin;  // `last`: the end of the last non-space character
  while (end < s.size()) {
    if (!IsJsSpace(DecodeUtf8(s, &end))) last = end;
  }
  return s.substr(begin, last - begin);
}

bool IsDigit(char c) { return c >= '0' && c <= '9'; }

// ---------------------------------------------------------------------------------------------
// Numbers as JavaScript writes and reads them.

// 10^0 .. 10^22: every one an exact double.
constexpr double kPow10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                             1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

// A positive number's decimal digits: digits[0].digits[1..] x 10^exponent.
struct Decimal {
  std::string digits;
  int exponent = 0;
};

// The digits and exponent of printf's or to_chars' "d.ddde[+-]xx".
Decimal ParseScientific(std::string_view s) {
  Decimal d;
  const size_t e = s.find_first_of("eE");
  for (size_t k = 0; k < e; ++k) {
    if (IsDigit(s[k])) d.digits.push_back(s[k]);
  }
  size_t k = e + 1;
  const bool negative = s[k] == '-';
  if (s[k] == '+' || s[k] == '-') ++k;
  for (; k < s.size(); ++k) d.exponent = d.exponent * 10 + (s[k] - '0');
  if (negative) d.exponent = -d.exponent;
  return d;
}

// The shortest digits that read back as x (> 0, finite), the closest of them to x: the
// choice of JavaScript's Number::toString (ECMA-262 6.1.6.1.20), and of to_chars.
Decimal ShortestDigits(double x) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, x, std::chars_format::scientific);
  return ParseScientific(std::string_view(buf, r.ptr - buf));
}

// Whether x (> 0) is an odd multiple of 5 x 10^q: its exact decimal expansion ends in a 5 at
// the 10^q place, so that rounding it at the 10^(q+1) place is a tie.
bool EndsInFiveAt(double x, int q) {
  if (q < 0) {
    // x = (2N+1) 5^(q+1) 2^q; for x to be binary 5^(-q-1) must divide 2N+1, so this holds
    // exactly when x 2^-q is an odd integer (ldexp is exact; an overflow is no tie).
    if (q < -1100) return false;
    const double y = std::ldexp(x, -q);
    return std::isfinite(y) && std::fmod(y, 2.0) == 1.0;
  }
  // 5^(q+1) divides x's odd 53-bit mantissa only for q + 1 <= 22, where 10^(q+1) and
  // 5 x 10^q are exact doubles (and fmod is exact).
  if (q > 21) return false;
  return std::fmod(x, kPow10[q + 1]) == 5 * kPow10[q];
}

// Adds one unit in the last place of d's digits.
void RoundUp(Decimal* d) {
  for (size_t k = d->digits.size(); k-- > 0;) {
    if (d->digits[k] != '9') {
      ++d->digits[k];
      return;
    }
    d->digits[k] = '0';
  }
  d->digits.front() = '1';  // 9.99 -> 10.0: one digit more to the left, one fewer right
  ++d->exponent;
}

// x (> 0, finite) to n >= 1 significant digits as toExponential and toPrecision round: to the
// nearest, a tie to the larger (ECMA-262 Number.prototype.toExponential, step 10). printf
// rounds a tie to even, so ties are found here and rounded up.
Decimal RoundedDigits(double x, int n) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*e", n, x);  // one digit more, exact when it is a tie
  Decimal longer = ParseScientific(buf);
  if (longer.digits.back() == '5' && EndsInFiveAt(x, longer.exponent - n)) {
    longer.digits.pop_back();
    RoundUp(&longer);
    return longer;
  }
  std::snprintf(buf, sizeof buf, "%.*e", n - 1, x);
  return ParseScientific(buf);
}

std::string ExponentText(int e) { return (e < 0 ? "e-" : "e+") + std::to_string(std::abs(e)); }

// Number.prototype.toExponential(f) of x >= 0 (f < 0: toExponential() with no argument).
std::string JsToExponential(double x, int f) {
  if (std::isnan(x)) return "NaN";
  if (std::isinf(x)) return "Infinity";
  Decimal d;
  if (f < 0) {
    d = x == 0 ? Decimal{"0", 0} : ShortestDigits(x);
  } else {
    d = x == 0 ? Decimal{std::string(f + 1, '0'), 0} : RoundedDigits(x, f + 1);
  }
  std::string s(1, d.digits[0]);
  if (d.digits.size() > 1) s += "." + d.digits.substr(1);
  return s + ExponentText(d.exponent);
}

// Number.prototype.toPrecision(p) of x >= 0.
std::string JsToPrecision(double x, int p) {
  if (std::isnan(x)) return "NaN";
  if (std::isinf(x)) return "Infinity";
  const Decimal d = x == 0 ? Decimal{std::string(p, '0'), 0} : RoundedDigits(x, p);
  const int e = d.exponent;
  if (e < -6 || e >= p) {
    std::string s(1, d.digits[0]);
    if (p > 1) s += "." + d.digits.substr(1);
    return s + ExponentText(e);
  }
  if (e == p - 1) return d.digits;
  if (e >= 0) return d.digits.substr(0, e + 1) + "." + d.digits.substr(e + 1);
  return "0." + std::string(-(e + 1), '0') + d.digits;
}

// Number.prototype.toFixed(f) of x >= 0: the same rounding as RoundedDigits.
std::string JsToFixed(double x, int f) {
  if (std::isnan(x)) return "NaN";
  if (x >= 1e21) return JsNumber(x);  // also Infinity
  char buf[80];                       // 21 digits, the point, 21 decimals
  std::snprintf(buf, sizeof buf, "%.*f", f + 1, x);
  std::string s = buf;
  if (s.back() == '5' && EndsInFiveAt(x, -(f + 1))) {
    s.pop_back();
    if (f == 0) s.pop_back();  // the point
    for (size_t k = s.size(); k-- > 0;) {
      if (s[k] == '.') continue;
      if (s[k] != '9') {
        ++s[k];
        return s;
      }
      s[k] = '0';
    }
    return "1" + s;
  }
  std::snprintf(buf, sizeof buf, "%.*f", f, x);
  return buf;
}

// Math.round: the nearest integer, halves up (-2.5 -> -2), the sign of a zero kept.
double JsRound(double x) {
  if (!std::isfinite(x) || x == 0) return x;
  if (x > 0 && x < 0.5) return 0.0;
  if (x < 0 && x >= -0.5) return -0.0;
  double r = std::floor(x);
  if (x - r >= 0.5) r += 1;  // exact: x - floor(x) is x's fraction
  return r;
}

// Number.prototype.toString(radix) of an integer x >= 0 (Math.round's) for radix 2, 8, 16:
// exact at any size, as the digits are groups of the binary digits.
std::string JsRadix(double x, int radix) {
  if (std::isinf(x)) return "Infinity";
  if (x < 0x1p64) {
    char buf[80];
    const auto r = std::to_chars(buf, buf + sizeof buf, static_cast<uint64_t>(x), radix);
    return std::string(buf, r.ptr);
  }
  int exp = 0;
  const double m = std::frexp(x, &exp);  // x = m 2^exp, m in [0.5, 1)
  const auto mantissa = static_cast<uint64_t>(std::ldexp(m, 53));
  std::string bits;
  for (int k = 52; k >= 0; --k) bits.push_back((mantissa >> k) & 1 ? '1' : '0');
  bits.append(exp - 53, '0');
  const int width = radix == 2 ? 1 : radix == 8 ? 3 : 4;
  std::string out;
  for (size_t end = bits.size(); end > 0;) {
    const size_t begin = end >= static_cast<size_t>(width) ? end - width : 0;
    int digit = 0;
    for (size_t k = begin; k < end; ++k) digit = digit * 2 + (bits[k] - '0');
    out.push_back("0123456789abcdef"[digit]);
    end = begin;
  }
  while (out.size() > 1 && out.back() == '0') out.pop_back();  // leading zeros, reversed
  std::reverse(out.begin(), out.end());
  return out;
}

// JavaScript's StringToNumber (Number(s), +s): blanks are 0, "Infinity", 0x/0o/0b integers,
// decimal literals with an optional sign; anything else NaN.
double JsStringToNumber(std::string_view text) {
  const std::string_view s = TrimJsSpace(text);
  if (s.empty()) return 0;
  if (s == "Infinity" || s == "+Infinity") return kInf;
  if (s == "-Infinity") return -kInf;
  if (s.size() > 2 && s[0] == '0' &&
      std::string_view("xXoObB").find(s[1]) != std::string_view::npos) {
    const int radix = (s[1] | 0x20) == 'x' ? 16 : (s[1] | 0x20) == 'o' ? 8 : 2;
    double value = 0;
    for (size_t k = 2; k < s.size(); ++k) {
      const char c = static_cast<char>(s[k] | 0x20);
      const int digit = IsDigit(c) ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : 99;
      if (digit >= radix) return kNaN;
      value = value * radix + digit;
    }
    return value;
  }
  // [+-] (digits [. digits] | . digits) [e [+-] digits], the whole of it.
  size_t k = 0;
  const bool negative = s[0] == '-';
  if (s[0] == '+' || s[0] == '-') ++k;
  const size_t mantissa_begin = k;
  size_t digits = 0, first_nonzero = std::string_view::npos, point = std::string_view::npos;
  for (; k < s.size() && (IsDigit(s[k]) || (s[k] == '.' && point == std::string_view::npos)); ++k) {
    if (s[k] == '.') {
      point = k;
      continue;
    }
    if (s[k] != '0' && first_nonzero == std::string_view::npos) first_nonzero = k;
    ++digits;
  }
  if (digits == 0) return kNaN;
  const size_t mantissa_end = k;
  int exponent = 0;
  if (k < s.size() && (s[k] == 'e' || s[k] == 'E')) {
    ++k;
    const bool negative_exponent = k < s.size() && s[k] == '-';
    if (k < s.size() && (s[k] == '+' || s[k] == '-')) ++k;
    if (k == s.size()) return kNaN;
    for (; k < s.size() && IsDigit(s[k]); ++k)
      exponent = std::min(exponent * 10 + (s[k] - '0'), 100000);
    if (negative_exponent) exponent = -exponent;
  }
  if (k != s.size()) return kNaN;
  if (first_nonzero == std::string_view::npos) return negative ? -0.0 : 0.0;
  // from_chars reads no '+' and wants a digit before the point.
  std::string canonical = "0" + std::string(s.substr(mantissa_begin));
  double value = 0;
  const auto r = std::from_chars(canonical.data(), canonical.data() + canonical.size(), value);
  if (r.ec == std::errc::result_out_of_range) {
    // Too large or too small for a double: which one by the first digit's place.
    const size_t point_at = point == std::string_view::npos ? mantissa_end : point;
    const long place = first_nonzero < point_at ? static_cast<long>(point_at - first_nonzero)
                                                : -static_cast<long>(first_nonzero - point_at) + 1;
    value = place + exponent > 0 ? kInf : 0.0;
  }
  return negative ? -value : value;
}

// ---------------------------------------------------------------------------------------------
// JavaScript's conversions and operators on JSON values (null stands for undefined too).

bool IsStructured(const Json& v) { return v.is_array() || v.is_object(); }

// ToPrimitive of an array or object: its string (Array.prototype.toString, "[object Object]").
std::string StructuredString(const Json& v);

std::string ToJsString(const Json& v) {
  switch (v.type()) {
    case Json::value_t::null:
      return "null";
    case Json::value_t::boolean:
      return v.get<bool>() ? "true" : "false";
    case Json::value_t::number_integer:
    case Json::value_t::number_unsigned:
    case Json::value_t::number_float:
      return JsNumber(v.get<double>());
    case Json::value_t::string:
      return v.get_ref<const std::string&>();
    case Json::value_t::array:
    case Json::value_t::object:
      return StructuredString(v);
    default:
      return "undefined";  // discarded and binary values: no JavaScript counterpart
  }
}

std::string StructuredString(const Json& v) {
  if (v.is_object()) return "[object Object]";
  std::string out;
  for (size_t k = 0; k < v.size(); ++k) {
    if (k) out += ',';
    if (!v[k].is_null()) out += ToJsString(v[k]);
  }
  return out;
}

double ToJsNumber(const Json& v) {
  switch (v.type()) {
    case Json::value_t::null:
      return 0;
    case Json::value_t::boolean:
      return v.get<bool>() ? 1 : 0;
    case Json::value_t::number_integer:
    case Json::value_t::number_unsigned:
    case Json::value_t::number_float:
      return v.get<double>();
    case Json::value_t::string:
      return JsStringToNumber(v.get_ref<const std::string&>());
    case Json::value_t::array:
      return JsStringToNumber(StructuredString(v));
    default:
      return kNaN;
  }
}

bool IsTruthy(const Json& v) {
  switch (v.type()) {
    case Json::value_t::boolean:
      return v.get<bool>();
    case Json::value_t::number_integer:
    case Json::value_t::number_unsigned:
    case Json::value_t::number_float: {
      const double x = v.get<double>();
      return x == x && x != 0;
    }
    case Json::value_t::string:
      return !v.get_ref<const std::string&>().empty();
    case Json::value_t::array:
    case Json::value_t::object:
    case Json::value_t::binary:
      return true;
    default:
      return false;  // null, discarded
  }
}

// Arrays and objects are one JavaScript type ("object").
bool SameJsType(const Json& a, const Json& b) {
  if (a.is_number() && b.is_number()) return true;
  if (IsStructured(a) && IsStructured(b)) return true;
  return a.type() == b.type();
}

// ===: numbers by value (NaN unequal to itself, 0 equal to -0); arrays and objects by value
// where JavaScript compares references, the same answer for a datum's own members.
bool StrictEquals(const Json& a, const Json& b) {
  if (!SameJsType(a, b)) return false;
  if (a.is_number()) return a.get<double>() == b.get<double>();
  return a == b;
}

// == (ECMA-262 IsLooselyEqual).
bool LooseEquals(const Json& a, const Json& b) {
  if (SameJsType(a, b)) return StrictEquals(a, b);
  if (a.is_null() || b.is_null()) return false;  // null == undefined only
  if (a.is_number() && b.is_string()) return a.get<double>() == ToJsNumber(b);
  if (a.is_string() && b.is_number()) return ToJsNumber(a) == b.get<double>();
  if (a.is_boolean()) return LooseEquals(Json(a.get<bool>() ? 1.0 : 0.0), b);
  if (b.is_boolean()) return LooseEquals(a, Json(b.get<bool>() ? 1.0 : 0.0));
  if (IsStructured(b) && (a.is_number() || a.is_string())) {
    return LooseEquals(a, Json(StructuredString(b)));
  }
  if (IsStructured(a) && (b.is_number() || b.is_string())) {
    return LooseEquals(Json(StructuredString(a)), b);
  }
  return false;
}

}  // namespace

// The tree's types have a name outside the file (Expression::Node holds the tree; a type of
// an anonymous namespace there would be -Wsubobject-linkage's in a unity batch).
enum class BinaryOp : uint8_t {
  kMul,
  kDiv,
  kMod,
  kAdd,
  kSub,
  kLess,
  kGreater,
  kLessEqual,
  kGreaterEqual,
  kEqual,
  kNotEqual,
  kStrictEqual,
  kStrictNotEqual,
};

namespace {

// < > <= >= (ECMA-262 IsLessThan): two strings by code units, anything else as numbers, where
// a NaN makes every comparison false.
bool Compare(BinaryOp op, const Json& a, const Json& b) {
  const bool a_text = a.is_string() || IsStructured(a), b_text = b.is_string() || IsStructured(b);
  int order = 0;
  if (a_text && b_text) {
    if (a.is_string() && b.is_string()) {
      order = CompareStrings(a.get_ref<const std::string&>(), b.get_ref<const std::string&>());
    } else {
      order = CompareStrings(ToJsString(a), ToJsString(b));
    }
  } else {
    const double x = ToJsNumber(a), y = ToJsNumber(b);
    if (std::isnan(x) || std::isnan(y)) return false;
    order = x < y ? -1 : x > y ? 1 : 0;
  }
  switch (op) {
    case BinaryOp::kLess:
      return order < 0;
    case BinaryOp::kGreater:
      return order > 0;
    case BinaryOp::kLessEqual:
      return order <= 0;
    default:
      return order >= 0;
  }
}

Json Binary(BinaryOp op, const Json& a, const Json& b) {
  switch (op) {
    case BinaryOp::kAdd:
      if (a.is_number() && b.is_number()) return a.get<double>() + b.get<double>();
      // ToPrimitive turns arrays and objects into strings: then + joins.
      if (a.is_string() || b.is_string() || IsStructured(a) || IsStructured(b)) {
        return ToJsString(a) + ToJsString(b);
      }
      return ToJsNumber(a) + ToJsNumber(b);
    case BinaryOp::kSub:
      return ToJsNumber(a) - ToJsNumber(b);
    case BinaryOp::kMul:
      return ToJsNumber(a) * ToJsNumber(b);
    case BinaryOp::kDiv:
      return ToJsNumber(a) / ToJsNumber(b);
    case BinaryOp::kMod:
      return std::fmod(ToJsNumber(a), ToJsNumber(b));  // JavaScript's % truncates as fmod
    case BinaryOp::kEqual:
      return LooseEquals(a, b);
    case BinaryOp::kNotEqual:
      return !LooseEquals(a, b);
    case BinaryOp::kStrictEqual:
      return StrictEquals(a, b);
    case BinaryOp::kStrictNotEqual:
      return !StrictEquals(a, b);
    default:
      return Compare(op, a, b);
  }
}

// ---------------------------------------------------------------------------------------------
// d3-format, as the vega-format module of the Vega rtscalib runs bundles it (d3-format 1.4.5:
// formatDecimal, formatRounded, formatPrefixAuto, formatTrim, formatGroup).

bool IsAlign(char c) { return c == '<' || c == '>' || c == '=' || c == '^'; }

// formatTypes' keys; others ("", "E", "z", ...) are d3's ".12~g".
bool IsFormatType(char c) {
  return c != 0 && std::string_view("%bcdefgoprsxX").find(c) != std::string_view::npos;
}

// formatTrim: removes the insignificant zeros of the decimals, 1.2000k -> 1.2k, 1.0 -> 1.
std::string TrimInsignificantZeros(const std::string& s) {
  long i0 = -1, i1 = 0;
  for (long i = 1, n = static_cast<long>(s.size()); i < n; ++i) {
    const char c = s[i];
    if (c == '.') {
      i0 = i1 = i;
    } else if (c == '0') {
      if (i0 == 0) i0 = i;
      i1 = i;
    } else if (i0 > 0) {
      if (c < '1' || c > '9') break;  // d3: !+s[i], the end of the decimals
      i0 = 0;
    }
  }
  return i0 > 0 ? s.substr(0, i0) + s.substr(i1 + 1) : s;
}

// formatDecimalParts: the digits of x (>= 0) to p significant digits (p 0: the shortest);
// nullopt for NaN and Infinity.
std::optional<Decimal> DecimalParts(double x, int p) {
  if (!std::isfinite(x)) return std::nullopt;
  if (p == 0) return x == 0 ? Decimal{"0", 0} : ShortestDigits(x);
  return x == 0 ? Decimal{std::string(p, '0'), 0} : RoundedDigits(x, p);
}

// formatRounded ('r', and 'p' of x * 100): p significant digits, never an exponent.
std::string FormatRounded(double x, int p) {
  const auto d = DecimalParts(x, p);
  if (!d) return JsNumber(x);
  const std::string& c = d->digits;
  const int e = d->exponent;
  if (e < 0) return "0." + std::string(-e - 1, '0') + c;
  if (static_cast<int>(c.size()) > e + 1) return c.substr(0, e + 1) + "." + c.substr(e + 1);
  return c + std::string(e - c.size() + 1, '0');
}

// formatPrefixAuto ('s'): p significant digits before an SI prefix; *si its power of ten.
std::string FormatPrefixAuto(double x, int p, int* si) {
  const auto d = DecimalParts(x, p);
  if (!d) return JsNumber(x);
  const std::string& c = d->digits;
  const int e = d->exponent;
  const int e3 = e >= 0 ? e / 3 : -((-e + 2) / 3);  // Math.floor(e / 3)
  *si = std::clamp(e3, -8, 8) * 3;
  const int i = e - *si + 1, n = static_cast<int>(c.size());
  if (i == n) return c;
  if (i > n) return c + std::string(i - n, '0');
  if (i > 0) return c.substr(0, i) + "." + c.substr(i);
  // Below 1y: more digits after the point (d3's "less than 1y!").
  return "0." + std::string(-i, '0') + DecimalParts(x, std::max(0, p + i - 1))->digits;
}

std::string SiPrefix(int si) {
  static const char* const kPrefixes[] = {"y", "z", "a", "f", "p", "n", "\xC2\xB5", "m", "",
                                          "k", "M", "G", "T", "P", "E", "Z",        "Y"};
  return kPrefixes[8 + si / 3];
}

// formatGroup with en-US's grouping [3] and thousands ",": at most `width` characters when the
// zeros of a zero fill are grouped with the digits.
std::string Group(const std::string& value, long width) {
  std::vector<std::string> parts;
  long i = static_cast<long>(value.size()), length = 0, g = 3;
  while (i > 0 && g > 0) {
    if (length + g + 1 > width) g = std::max(1L, width - length);
    i -= g;
    parts.push_back(value.substr(std::max(i, 0L), g + std::min(i, 0L)));
    if ((length += g + 1) > width) break;
    g = 3;
  }
  std::string out;
  for (size_t k = parts.size(); k-- > 0;) {
    out += parts[k];
    if (k) out += ',';
  }
  return out;
}

constexpr long kUnlimitedWidth = 1L << 40;
constexpr int kMaxWidth = 4096;  // d3 has no limit; a wider field is a broken spec

}  // namespace
}  // namespace expression_impl

bool Truthy(const nlohmann::json& v) { return expression_impl::IsTruthy(v); }

std::string JsString(const nlohmann::json& v) { return expression_impl::ToJsString(v); }

double JsToNumber(const nlohmann::json& v) { return expression_impl::ToJsNumber(v); }

std::string JsNumber(double x) {
  if (std::isnan(x)) return "NaN";
  if (x == 0) return "0";
  if (x < 0) return "-" + JsNumber(-x);
  if (std::isinf(x)) return "Infinity";
  // ECMA-262 Number::toString: k shortest digits, the value 0.digits x 10^n.
  const expression_impl::Decimal d = expression_impl::ShortestDigits(x);
  const int k = static_cast<int>(d.digits.size()), n = d.exponent + 1;
  if (k <= n && n <= 21) return d.digits + std::string(n - k, '0');
  if (0 < n && n <= 21) return d.digits.substr(0, n) + "." + d.digits.substr(n);
  if (-6 < n && n <= 0) return "0." + std::string(-n, '0') + d.digits;
  std::string s(1, d.digits[0]);
  if (k > 1) s += "." + d.digits.substr(1);
  return s + expression_impl::ExponentText(n - 1);
}

NumberFormat::NumberFormat(const std::string& specifier, std::string_view minus) : minus_(minus) {
  auto invalid = [&](const std::string& why) {
    return SubsetError("invalid d3 format specifier \"" + specifier + "\": " + why);
  };
  const std::string& s = specifier;
  const size_t n = s.size();
  size_t i = 0;
  // [[fill]align]: the fill is one UTF-16 unit but a line terminator (the regular
  // expression's `.`); an align character can stand nowhere else, so no backtracking.
  char align = 0;
  if (n > 0) {
    size_t after = 0;
    const char32_t cp = expression_impl::DecodeUtf8(s, &after);
    const bool fill_ok = cp <= 0xFFFF && cp != '\n' && cp != '\r' && cp != 0x2028 && cp != 0x2029;
    if (fill_ok && after < n && expression_impl::IsAlign(s[after])) {
      fill_ = s.substr(0, after);
      align = s[after];
      i = after + 1;
    } else if (expression_impl::IsAlign(s[0])) {
      align = s[0];
      i = 1;
    }
  }
  if (align) align_ = align;
  if (i < n && s[i] != 0 && std::string_view("+-( ").find(s[i]) != std::string_view::npos) {
    sign_ = s[i++];
  }
  char symbol = 0;
  if (i < n && (s[i] == '$' || s[i] == '#')) symbol = s[i++];
  bool zero = false;
  if (i < n && s[i] == '0') zero = true, ++i;
  auto digits = [&](long limit) {
    long value = 0;
    for (; i < n && expression_impl::IsDigit(s[i]); ++i)
      value = std::min(value * 10 + (s[i] - '0'), limit);
    return value;
  };
  if (i < n && expression_impl::IsDigit(s[i])) {
    const long width = digits(expression_impl::kMaxWidth + 1L);
    if (width > expression_impl::kMaxWidth) {
      throw invalid("a width over " + std::to_string(expression_impl::kMaxWidth));
    }
    width_ = static_cast<int>(width);
  }
  if (i < n && s[i] == ',') comma_ = true, ++i;
  std::optional<int> precision;
  if (i < n && s[i] == '.') {
    ++i;
    if (i == n || !expression_impl::IsDigit(s[i]))
      throw invalid("a '.' without the precision's digits");
    precision = static_cast<int>(digits(1000));
  }
  if (i < n && s[i] == '~') trim_ = true, ++i;
  char type = 0;
  if (i < n && (s[i] == '%' || std::isalpha(static_cast<unsigned char>(s[i])))) type = s[i++];
  if (i != n) throw invalid("unexpected '" + s.substr(i) + "'");

  if (type == 'n') {  // ",g"
    comma_ = true, type = 'g';
  } else if (!expression_impl::IsFormatType(type)) {  // "" and unknown types: ".12~g"
    if (!precision) precision = 12;
    trim_ = true, type = 'g';
  }
  type_ = type;
  // Zero fill pads between the sign and the digits.
  if (zero || (fill_ == "0" && align_ == '=')) zero_ = true, fill_ = "0", align_ = '=';
  if (symbol == '$') {
    prefix_ = "$";  // en-US's currency ["$", ""]: a '$' format has no '%' either (d3)
  } else {
    if (symbol == '#' && std::string_view("boxX").find(type_) != std::string_view::npos) {
      prefix_ = std::string("0") + static_cast<char>(type_ | 0x20);
    }
    if (type_ == '%' || type_ == 'p') suffix_ = "%";
  }
  maybe_suffix_ = std::string_view("defgprs%").find(type_) != std::string_view::npos;
  if (!precision) {
    precision_ = 6;
  } else if (std::string_view("gprs").find(type_) != std::string_view::npos) {
    precision_ = std::clamp(*precision, 1, 21);
  } else {
    precision_ = std::clamp(*precision, 0, 20);
  }
}

std::string NumberFormat::operator()(double x) const {
  if (type_ == 'c') return Finish(prefix_, "", JsNumber(x) + suffix_);
  // d3-format 1.4.5: value < 0, so -0 has no sign (v3 drops it too unless the sign is '+').
  bool negative = x < 0;
  int si = 0;
  std::string value;
  const double a = std::fabs(x);
  switch (std::isnan(x) ? 0 : type_) {
    case 0:  // d3 writes its locale's "NaN" without calling the type's function
      value = "NaN";
      break;
    case '%':
      value = expression_impl::JsToFixed(a * 100, precision_);
      break;
    case 'b':
      value = expression_impl::JsRadix(expression_impl::JsRound(a), 2);
      break;
    case 'o':
      value = expression_impl::JsRadix(expression_impl::JsRound(a), 8);
      break;
    case 'x':
    case 'X':
      value = expression_impl::JsRadix(expression_impl::JsRound(a), 16);
      if (type_ == 'X') {
        std::transform(value.begin(), value.end(), value.begin(),
                       [](char c) { return c >= 'a' && c <= 'z' ? c - 'a' + 'A' : c; });
      }
      break;
    case 'd':
      value = JsNumber(expression_impl::JsRound(a));
      break;
    case 'e':
      value = expression_impl::JsToExponential(a, precision_);
      break;
    case 'f':
      value = expression_impl::JsToFixed(a, precision_);
      break;
    case 'p':
      value = expression_impl::FormatRounded(a * 100, precision_);
      break;
    case 'r':
      value = expression_impl::FormatRounded(a, precision_);
      break;
    case 's':
      value = expression_impl::FormatPrefixAuto(a, precision_, &si);
      break;
    default:  // 'g'
      value = expression_impl::JsToPrecision(a, precision_);
      break;
  }
  if (trim_) value = expression_impl::TrimInsignificantZeros(value);
  // A negative number that rounds to zero is written without its sign.
  if (negative && expression_impl::JsStringToNumber(value) == 0) negative = false;
  std::string prefix = negative ? (sign_ == '(' ? "(" : minus_)
                                : (sign_ == '-' || sign_ == '(' ? "" : std::string(1, sign_));
  prefix += prefix_;
  // d3 writes NaN's and Infinity's 's' with the prefix of the number formatted before them
  // (module state); none here.
  std::string suffix =
      (type_ == 's' && std::isfinite(x) ? expression_impl::SiPrefix(si) : "") + suffix_;
  if (negative && sign_ == '(') suffix += ")";
  // Only the integer digits are grouped: the point, decimals and exponent join the suffix.
  if (maybe_suffix_) {
    for (size_t k = 0; k < value.size(); ++k) {
      if (!expression_impl::IsDigit(value[k])) {
        suffix = value.substr(k) + suffix;
        value.resize(k);
        break;
      }
    }
  }
  return Finish(std::move(prefix), std::move(value), std::move(suffix));
}

std::string NumberFormat::FormatValue(const nlohmann::json& value) const {
  if (type_ == 'c') return Finish(prefix_, "", expression_impl::ToJsString(value) + suffix_);
  return (*this)(expression_impl::ToJsNumber(value));
}

std::string NumberFormat::Finish(std::string prefix, std::string value, std::string suffix) const {
  // A fill other than zeros is grouped before the padding, zeros with it.
  if (comma_ && !zero_) value = expression_impl::Group(value, expression_impl::kUnlimitedWidth);
  const long length =
      static_cast<long>(expression_impl::Utf16Length(prefix) + expression_impl::Utf16Length(value) +
                        expression_impl::Utf16Length(suffix));
  long padding = width_ >= 0 && length < width_ ? width_ - length : 0;
  if (comma_ && zero_) {
    value = expression_impl::Group(
        std::string(padding, '0') + value,
        padding ? width_ - static_cast<long>(expression_impl::Utf16Length(suffix))
                : expression_impl::kUnlimitedWidth);
    padding = 0;
  }
  auto pad = [&](long count) {
    std::string out;
    for (long k = 0; k < count; ++k) out += fill_;
    return out;
  };
  switch (align_) {
    case '<':
      return prefix + value + suffix + pad(padding);
    case '=':
      return prefix + pad(padding) + value + suffix;
    case '^':
      return pad(padding / 2) + prefix + value + suffix + pad(padding - padding / 2);
    default:
      return pad(padding) + prefix + value + suffix;
  }
}

std::string Format(double x, const std::string& specifier) { return NumberFormat(specifier)(x); }

std::string Format(double x, const std::string& specifier, std::string_view minus) {
  return NumberFormat(specifier, minus)(x);
}

// ---------------------------------------------------------------------------------------------
// Expressions: a recursive-descent parser into a tree, evaluated per datum.

namespace expression_impl {

enum class Kind : uint8_t {
  kLiteral,
  kDatum,
  kMember,  // kids[0].name
  kIndex,   // kids[0][kids[1]]
  kNot,
  kNegate,
  kPlus,
  kBinary,
  kAnd,
  kOr,
  kConditional,
  kArray,
  kObject,  // keys[i]: kids[i]
  kCall,
};

enum class Fn : uint8_t {
  kScale,
  kFormat,
  kAbs,
  kSqrt,
  kRound,
  kFloor,
  kCeil,
  kMin,
  kMax,
  kPow,
  kLog,
  kExp,
  kClamp,
  kIsNaN,
  kIsFinite,
  kIsValid,
  kIsNumber,
  kIsString,
  kToString,
  kToNumber,
  kLength,
  kJoin,
  kUpper,
  kLower,
  kIf,
};

struct Ast {
  Kind kind = Kind::kLiteral;
  BinaryOp op = BinaryOp::kAdd;
  Fn fn = Fn::kAbs;
  nlohmann::json literal;         // kLiteral
  std::string name;               // kMember: the property; kCall: the function
  std::vector<std::string> keys;  // kObject
  std::vector<std::unique_ptr<Ast>> kids;
  std::optional<NumberFormat> format;  // kCall of format() with a literal specifier
};
using AstPtr = std::unique_ptr<Ast>;

namespace {

struct FunctionInfo {
  const char* name;
  Fn fn;
  int min_args;
  int max_args;  // -1: any
};

constexpr FunctionInfo kFunctions[] = {
    {"scale", Fn::kScale, 2, 2},       {"format", Fn::kFormat, 2, 2},
    {"abs", Fn::kAbs, 1, 1},           {"sqrt", Fn::kSqrt, 1, 1},
    {"round", Fn::kRound, 1, 1},       {"floor", Fn::kFloor, 1, 1},
    {"ceil", Fn::kCeil, 1, 1},         {"min", Fn::kMin, 0, -1},
    {"max", Fn::kMax, 0, -1},          {"pow", Fn::kPow, 2, 2},
    {"log", Fn::kLog, 1, 1},           {"exp", Fn::kExp, 1, 1},
    {"clamp", Fn::kClamp, 3, 3},
    {"isNaN", Fn::kIsNaN, 1, 1},       {"isFinite", Fn::kIsFinite, 1, 1},
    {"isValid", Fn::kIsValid, 1, 1},   {"isNumber", Fn::kIsNumber, 1, 1},
    {"isString", Fn::kIsString, 1, 1}, {"toString", Fn::kToString, 1, 1},
    {"toNumber", Fn::kToNumber, 1, 1}, {"length", Fn::kLength, 1, 1},
    {"join", Fn::kJoin, 1, 2},         {"upper", Fn::kUpper, 1, 1},
    {"lower", Fn::kLower, 1, 1},       {"if", Fn::kIf, 3, 3},
};

// Vega's constants (vega-expression's Constants).
struct ConstantInfo {
  const char* name;
  double value;
};
const ConstantInfo kConstants[] = {
    {"NaN", kNaN},
    {"E", M_E},
    {"LN2", M_LN2},
    {"LN10", M_LN10},
    {"LOG2E", M_LOG2E},
    {"LOG10E", M_LOG10E},
    {"PI", M_PI},
    {"SQRT1_2", M_SQRT1_2},
    {"SQRT2", M_SQRT2},
    {"MIN_VALUE", std::numeric_limits<double>::denorm_min()},
    {"MAX_VALUE", std::numeric_limits<double>::max()},
};

std::string FunctionNames() {
  std::string out;
  for (const auto& f : kFunctions) out += std::string(out.empty() ? "" : ", ") + f.name;
  return out;
}

AstPtr MakeAst(Kind kind) {
  auto n = std::make_unique<Ast>();
  n->kind = kind;
  return n;
}

enum class Tok : uint8_t { kEnd, kNumber, kString, kName, kPunct };

struct Token {
  Tok kind = Tok::kEnd;
  std::string text;  // a name, a punctuator, a string's value
  double number = 0;
  size_t begin = 0, end = 0;  // bytes of the text
};

// The punctuators JavaScript has, longest first; the parser says which are outside the
// subset.
constexpr std::string_view kPunctuators[] = {
    ">>>=", "===", "!==", ">>>", "<<=", ">>=", "**=", "...", "&&=", "||=", "?\?=", "=>",
    "==",   "!=",  "<=",  ">=",  "&&",  "||",  "??",  "?.",  "++",  "--",  "+=",   "-=",
    "*=",   "/=",  "%=",  "&=",  "|=",  "^=",  "<<",  ">>",  "**",  "{",   "}",    "(",
    ")",    "[",   "]",   ";",   ",",   "<",   ">",   "+",   "-",   "*",   "/",    "%",
    "&",    "|",   "^",   "!",   "~",   "?",   ":",   "=",   ".",   "@",   "#",
};

bool IsNameStart(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_' || c == '$' ||
         static_cast<unsigned char>(c) >= 0x80;
}
bool IsNamePart(char c) { return IsNameStart(c) || IsDigit(c); }

class Parser {
 public:
  explicit Parser(const std::string& text) : text_(text) { tok_ = Lex(0); }

  AstPtr ParseAll() {
    AstPtr e = ParseConditional();
    if (tok_.kind != Tok::kEnd) Unexpected(tok_);
    return e;
  }

  [[noreturn]] void Fail(size_t at, const std::string& what) const {
    throw SubsetError("Vega expression \"" + text_ + "\", at character " + std::to_string(at + 1) +
                      ": " + what);
  }

 private:
  // ---- lexing
  size_t SkipSpaceAndComments(size_t i) const {
    for (;;) {
      while (i < text_.size()) {
        size_t next = i;
        if (!IsJsSpace(DecodeUtf8(text_, &next))) break;
        i = next;
      }
      if (text_.compare(i, 2, "//") == 0) {
        while (i < text_.size() && text_[i] != '\n' && text_[i] != '\r') ++i;
      } else if (text_.compare(i, 2, "/*") == 0) {
        const size_t close = text_.find("*/", i + 2);
        if (close == std::string::npos) Fail(i, "unterminated comment");
        i = close + 2;
      } else {
        return i;
      }
    }
  }

  Token Lex(size_t from) const {
    Token t;
    size_t i = SkipSpaceAndComments(from);
    t.begin = i;
    if (i == text_.size()) {
      t.end = i;
      return t;
    }
    const char c = text_[i];
    if (IsNameStart(c)) {
      while (i < text_.size() && IsNamePart(text_[i])) ++i;
      t.kind = Tok::kName;
      t.text = text_.substr(t.begin, i - t.begin);
    } else if (c == '\\') {
      Fail(i, "identifiers with escapes are not supported");
    } else if (IsDigit(c) || (c == '.' && i + 1 < text_.size() && IsDigit(text_[i + 1]))) {
      i = LexNumber(i, &t);
    } else if (c == '\'' || c == '"') {
      i = LexString(i, &t);
    } else if (c == '`') {
      Fail(i, "template literals (`...`) are not supported");
    } else {
      for (const std::string_view p : kPunctuators) {
        if (text_.compare(i, p.size(), p) != 0) continue;
        // a?.5:1 is a conditional, not optional chaining.
        if (p == "?." && i + 2 < text_.size() && IsDigit(text_[i + 2])) continue;
        t.kind = Tok::kPunct;
        t.text = std::string(p);
        i += p.size();
        break;
      }
      if (t.kind != Tok::kPunct) {
        size_t next = i;
        std::string character;
        AppendUtf8(DecodeUtf8(text_, &next), &character);
        Fail(i, "unexpected character '" + character + "'");
      }
    }
    t.end = i;
    return t;
  }

  size_t LexNumber(size_t i, Token* t) const {
    const size_t begin = i;
    t->kind = Tok::kNumber;
    if (text_[i] == '0' && i + 1 < text_.size() && (text_[i + 1] | 0x20) == 'x') {
      i += 2;
      double value = 0;
      const size_t digits_begin = i;
      for (; i < text_.size() && std::isxdigit(static_cast<unsigned char>(text_[i])); ++i) {
        const char d = static_cast<char>(text_[i] | 0x20);
        value = value * 16 + (IsDigit(d) ? d - '0' : d - 'a' + 10);
      }
      if (i == digits_begin) Fail(begin, "a hexadecimal number without digits");
      t->number = value;
    } else {
      if (text_[i] == '0' && i + 1 < text_.size() && IsDigit(text_[i + 1])) {
        Fail(begin, "numbers with a leading zero (legacy octal) are not supported");
      }
      while (i < text_.size() && IsDigit(text_[i])) ++i;
      if (i < text_.size() && text_[i] == '.') {
        ++i;
        while (i < text_.size() && IsDigit(text_[i])) ++i;
      }
      if (i < text_.size() && (text_[i] == 'e' || text_[i] == 'E')) {
        ++i;
        if (i < text_.size() && (text_[i] == '+' || text_[i] == '-')) ++i;
        if (i == text_.size() || !IsDigit(text_[i]))
          Fail(begin, "a number's exponent has no digits");
        while (i < text_.size() && IsDigit(text_[i])) ++i;
      }
      t->number = JsStringToNumber(std::string_view(text_).substr(begin, i - begin));
    }
    if (i < text_.size() && IsNamePart(text_[i])) Fail(i, "a name right after a number");
    return i;
  }

  // A string literal with JavaScript's escapes: \n \t \r \b \f \v \0, octal \ddd, \xhh,
  // \uhhhh (surrogate pairs joined), \u{h...}, a backslash before a line break continuing
  // the line, any other escaped character standing for itself.
  size_t LexString(size_t i, Token* t) const {
    const size_t begin = i;
    const char quote = text_[i++];
    t->kind = Tok::kString;
    std::string& out = t->text;
    auto unterminated = [&] { Fail(begin, "unterminated string literal"); };
    auto hex = [&](size_t from, size_t count) -> char32_t {
      if (from + count > text_.size()) Fail(from, "an incomplete escape");
      char32_t v = 0;
      for (size_t k = from; k < from + count; ++k) {
        const char d = static_cast<char>(text_[k] | 0x20);
        if (!std::isxdigit(static_cast<unsigned char>(text_[k]))) Fail(k, "an invalid escape");
        v = v * 16 + (IsDigit(d) ? d - '0' : d - 'a' + 10);
      }
      return v;
    };
    // A \uD8xx waiting for its \uDCxx; a lone surrogate becomes U+FFFD (UTF-8 has none).
    char32_t high_surrogate = 0;
    auto emit = [&](char32_t cp) {
      if (high_surrogate && cp >= 0xDC00 && cp < 0xE000) {
        AppendUtf8(0x10000 + ((high_surrogate - 0xD800) << 10) + (cp - 0xDC00), &out);
        high_surrogate = 0;
        return;
      }
      if (high_surrogate) AppendUtf8(0xFFFD, &out);
      high_surrogate = cp >= 0xD800 && cp < 0xDC00 ? cp : 0;
      if (!high_surrogate) AppendUtf8(cp, &out);
    };
    for (;;) {
      if (i == text_.size()) unterminated();
      const char c = text_[i];
      if (c == quote) {
        if (high_surrogate) AppendUtf8(0xFFFD, &out);
        return i + 1;
      }
      if (c == '\n' || c == '\r') unterminated();
      if (c != '\\') {
        const size_t from = i;
        emit(DecodeUtf8(text_, &i));
        if (i == from) ++i;
        continue;
      }
      ++i;
      if (i == text_.size()) unterminated();
      const char e = text_[i++];
      switch (e) {
        case 'n':
          emit('\n');
          break;
        case 't':
          emit('\t');
          break;
        case 'r':
          emit('\r');
          break;
        case 'b':
          emit('\b');
          break;
        case 'f':
          emit('\f');
          break;
        case 'v':
          emit('\v');
          break;
        case 'x':
          emit(hex(i, 2));
          i += 2;
          break;
        case 'u':
          if (i < text_.size() && text_[i] == '{') {
            const size_t close = text_.find('}', i);
            if (close == std::string::npos || close == i + 1 || close - i - 1 > 6) {
              Fail(i, "an invalid \\u{...} escape");
            }
            const char32_t cp = hex(i + 1, close - i - 1);
            if (cp > 0x10FFFF) Fail(i, "an invalid \\u{...} escape");
            emit(cp);
            i = close + 1;
          } else {
            emit(hex(i, 4));
            i += 4;
          }
          break;
        case '\r':
          if (i < text_.size() && text_[i] == '\n') ++i;
          break;
        case '\n':
          break;
        default:
          if (e >= '0' && e <= '7') {  // \0 and legacy octal escapes, as Vega's lexer reads them
            char32_t v = e - '0';
            if (i < text_.size() && text_[i] >= '0' && text_[i] <= '7') {
              v = v * 8 + (text_[i++] - '0');
              if (e <= '3' && i < text_.size() && text_[i] >= '0' && text_[i] <= '7') {
                v = v * 8 + (text_[i++] - '0');
              }
            }
            emit(v);
          } else {
            --i;
            const size_t from = i;
            emit(DecodeUtf8(text_, &i));
            if (i == from) ++i;
          }
          break;
      }
    }
  }

  // ---- parsing
  void Advance() { tok_ = Lex(tok_.end); }

  bool IsPunct(const Token& t, std::string_view p) const {
    return t.kind == Tok::kPunct && t.text == p;
  }

  void Expect(std::string_view p, const char* where) {
    if (!IsPunct(tok_, p)) {
      Fail(tok_.begin, "expected '" + std::string(p) + "' " + where + ", found " + Describe(tok_));
    }
    Advance();
  }

  // The token as the messages name it: "'foo'", "number 2", "the end of the expression".
  std::string Describe(const Token& t) const {
    switch (t.kind) {
      case Tok::kEnd:
        return "the end of the expression";
      case Tok::kNumber:
        return "number " + text_.substr(t.begin, t.end - t.begin);
      case Tok::kString:
        return "string " + text_.substr(t.begin, t.end - t.begin);
      default:
        return "'" + t.text + "'";
    }
  }

  [[noreturn]] void Unexpected(const Token& t) const {
    if (t.kind == Tok::kPunct) {
      const std::string& p = t.text;
      if (p == "=" || (p.size() >= 2 && p.back() == '=' && p != "==" && p != "!=" && p != "<=" &&
                       p != ">=" && p != "===" && p != "!==")) {
        Fail(t.begin, "assignment ('" + p + "') is not supported");
      }
      if (p == "++" || p == "--") Fail(t.begin, "'" + p + "' is not supported");
      if (p == ",") Fail(t.begin, "the comma operator is not supported");
      if (p == ";") Fail(t.begin, "statements (';') are not supported");
      if (p == "?.") Fail(t.begin, "optional chaining ('?.') is not supported");
      if (p == "=>") Fail(t.begin, "arrow functions are not supported");
      if (p == "&" || p == "|" || p == "^" || p == "~" || p == "<<" || p == ">>" || p == ">>>" ||
          p == "**" || p == "??") {
        Fail(t.begin, "the operator '" + p + "' is not supported");
      }
    }
    if (t.kind == Tok::kName && (t.text == "in" || t.text == "instanceof")) {
      Fail(t.begin, "the operator '" + t.text + "' is not supported");
    }
    Fail(t.begin, "unexpected " + Describe(t));
  }

  AstPtr ParseConditional() {
    AstPtr test = ParseBinary(1);
    if (!IsPunct(tok_, "?")) return test;
    Advance();
    auto n = MakeAst(Kind::kConditional);
    n->kids.push_back(std::move(test));
    n->kids.push_back(ParseConditional());
    Expect(":", "in a conditional (a ? b : c)");
    n->kids.push_back(ParseConditional());
    return n;
  }

  // JavaScript's precedence: || 1, && 2, equality 3, relational 4, additive 5,
  // multiplicative 6; 0 ends the operand (or fails on an operator outside the subset).
  int Precedence(const Token& t, BinaryOp* op) const {
    if (t.kind == Tok::kName && (t.text == "in" || t.text == "instanceof")) Unexpected(t);
    if (t.kind != Tok::kPunct) return 0;
    static const struct {
      std::string_view text;
      int precedence;
      BinaryOp op;
    } kOps[] = {
        {"||", 1, BinaryOp::kAdd},          {"&&", 2, BinaryOp::kAdd},
        {"==", 3, BinaryOp::kEqual},        {"!=", 3, BinaryOp::kNotEqual},
        {"===", 3, BinaryOp::kStrictEqual}, {"!==", 3, BinaryOp::kStrictNotEqual},
        {"<", 4, BinaryOp::kLess},          {">", 4, BinaryOp::kGreater},
        {"<=", 4, BinaryOp::kLessEqual},    {">=", 4, BinaryOp::kGreaterEqual},
        {"+", 5, BinaryOp::kAdd},           {"-", 5, BinaryOp::kSub},
        {"*", 6, BinaryOp::kMul},           {"/", 6, BinaryOp::kDiv},
        {"%", 6, BinaryOp::kMod},
    };
    for (const auto& o : kOps) {
      if (t.text == o.text) {
        *op = o.op;
        return o.precedence;
      }
    }
    if (t.text == "?" || t.text == ":" || t.text == ")" || t.text == "]" || t.text == "}" ||
        t.text == ",") {
      return 0;
    }
    Unexpected(t);
  }

  AstPtr ParseBinary(int min_precedence) {
    AstPtr left = ParseUnary();
    for (;;) {
      BinaryOp op{};
      const int precedence = Precedence(tok_, &op);
      if (precedence == 0 || precedence < min_precedence) return left;
      const std::string text = tok_.text;
      Advance();
      AstPtr right = ParseBinary(precedence + 1);
      AstPtr n = MakeAst(text == "||" ? Kind::kOr : text == "&&" ? Kind::kAnd : Kind::kBinary);
      n->op = op;
      n->kids.push_back(std::move(left));
      n->kids.push_back(std::move(right));
      left = std::move(n);
    }
  }

  AstPtr ParseUnary() {
    if (tok_.kind == Tok::kPunct && (tok_.text == "!" || tok_.text == "-" || tok_.text == "+")) {
      const Kind kind = tok_.text == "!"   ? Kind::kNot
                        : tok_.text == "-" ? Kind::kNegate
                                           : Kind::kPlus;
      Advance();
      AstPtr n = MakeAst(kind);
      n->kids.push_back(ParseUnary());
      return n;
    }
    if (tok_.kind == Tok::kPunct && (tok_.text == "~" || tok_.text == "++" || tok_.text == "--")) {
      Unexpected(tok_);
    }
    if (tok_.kind == Tok::kName &&
        (tok_.text == "typeof" || tok_.text == "void" || tok_.text == "delete" ||
         tok_.text == "new" || tok_.text == "await")) {
      Fail(tok_.begin, "'" + tok_.text + "' is not supported");
    }
    return ParsePostfix();
  }

  AstPtr ParsePostfix() {
    AstPtr e = ParsePrimary();
    for (;;) {
      if (IsPunct(tok_, ".")) {
        Advance();
        if (tok_.kind != Tok::kName) Fail(tok_.begin, "expected a member name after '.'");
        AstPtr n = MakeAst(Kind::kMember);
        n->name = tok_.text;
        n->kids.push_back(std::move(e));
        e = std::move(n);
        Advance();
      } else if (IsPunct(tok_, "[")) {
        Advance();
        AstPtr n = MakeAst(Kind::kIndex);
        n->kids.push_back(std::move(e));
        n->kids.push_back(ParseConditional());
        Expect("]", "after a member");
        e = std::move(n);
      } else if (IsPunct(tok_, "(")) {
        Fail(tok_.begin,
             "only the functions of the subset can be called (" + FunctionNames() + ")");
      } else if (IsPunct(tok_, "++") || IsPunct(tok_, "--") || IsPunct(tok_, "?.")) {
        Unexpected(tok_);
      } else {
        return e;
      }
    }
  }

  AstPtr ParsePrimary() {
    const Token t = tok_;
    switch (t.kind) {
      case Tok::kEnd:
        Fail(t.begin, "the expression ends early");
      case Tok::kNumber: {
        Advance();
        AstPtr n = MakeAst(Kind::kLiteral);
        n->literal = t.number;
        return n;
      }
      case Tok::kString: {
        Advance();
        AstPtr n = MakeAst(Kind::kLiteral);
        n->literal = t.text;
        return n;
      }
      case Tok::kName:
        return ParseName();
      case Tok::kPunct:
        break;
    }
    if (t.text == "(") {
      Advance();
      AstPtr e = ParseConditional();
      Expect(")", "to close '('");
      return e;
    }
    if (t.text == "[") return ParseArray();
    if (t.text == "{") return ParseObject();
    if (t.text == "/" || t.text == "/=") {
      Fail(t.begin, "regular expression literals are not supported");
    }
    Unexpected(t);
  }

  AstPtr ParseArray() {
    Advance();  // [
    AstPtr n = MakeAst(Kind::kArray);
    while (!IsPunct(tok_, "]")) {
      if (IsPunct(tok_, ",")) Fail(tok_.begin, "arrays with holes ([a, , b]) are not supported");
      n->kids.push_back(ParseConditional());
      if (IsPunct(tok_, "]")) break;
      Expect(",", "between array elements");
    }
    Advance();
    return n;
  }

  AstPtr ParseObject() {
    Advance();  // {
    AstPtr n = MakeAst(Kind::kObject);
    while (!IsPunct(tok_, "}")) {
      std::string key;
      if (tok_.kind == Tok::kString || tok_.kind == Tok::kName) {
        key = tok_.text;
      } else if (tok_.kind == Tok::kNumber) {
        key = JsNumber(tok_.number);
      } else {
        Fail(tok_.begin, "expected an object key, found " + Describe(tok_));
      }
      const size_t key_at = tok_.begin;
      Advance();
      if (!IsPunct(tok_, ":")) Fail(key_at, "object keys need a value ({key: value})");
      Advance();
      n->keys.push_back(std::move(key));
      n->kids.push_back(ParseConditional());
      if (IsPunct(tok_, "}")) break;
      Expect(",", "between object members");
    }
    Advance();
    return n;
  }

  AstPtr ParseName() {
    const Token t = tok_;
    const std::string& name = t.text;
    Advance();
    if (IsPunct(tok_, "(")) return ParseCall(t);
    if (name == "true" || name == "false" || name == "null") {
      AstPtr n = MakeAst(Kind::kLiteral);
      n->literal = name == "null" ? Json() : Json(name == "true");
      return n;
    }
    if (name == "datum") return MakeAst(Kind::kDatum);
    for (const auto& c : kConstants) {
      if (name == c.name) {
        AstPtr n = MakeAst(Kind::kLiteral);
        n->literal = c.value;
        return n;
      }
    }
    if (name == "this") Fail(t.begin, "'this' is not supported");
    if (name == "function") Fail(t.begin, "function expressions are not supported");
    Fail(t.begin, "the identifier '" + name +
                      "' is not supported: the subset reads only datum (no signals, event, "
                      "item, parent or globals)");
  }

  AstPtr ParseCall(const Token& callee) {
    const FunctionInfo* info = nullptr;
    for (const auto& f : kFunctions) {
      if (callee.text == f.name) info = &f;
    }
    if (!info) {
      Fail(callee.begin, "unknown function '" + callee.text +
                             "' (the subset's functions: " + FunctionNames() + ")");
    }
    Advance();  // (
    AstPtr n = MakeAst(Kind::kCall);
    n->fn = info->fn;
    n->name = info->name;
    while (!IsPunct(tok_, ")")) {
      n->kids.push_back(ParseConditional());
      if (IsPunct(tok_, ")")) break;
      Expect(",", "between arguments");
    }
    Advance();
    const int count = static_cast<int>(n->kids.size());
    if (count < info->min_args || (info->max_args >= 0 && count > info->max_args)) {
      const std::string wanted =
          info->min_args == info->max_args
              ? std::to_string(info->min_args)
              : std::to_string(info->min_args) + " or " + std::to_string(info->max_args);
      Fail(callee.begin, callee.text + "() takes " + wanted + " argument" +
                             (wanted == "1" ? "" : "s") + ", not " + std::to_string(count));
    }
    // A literal specifier (the usual case) is parsed once, and a wrong one found here.
    if (info->fn == Fn::kFormat && n->kids[1]->kind == Kind::kLiteral) {
      try {
        n->format.emplace(ToJsString(n->kids[1]->literal));
      } catch (const SubsetError& e) {
        Fail(callee.begin, e.what());
      }
    }
    return n;
  }

  const std::string& text_;
  Token tok_;
};

// ---- evaluation

// A value during evaluation: a reference into the datum or a literal (member reads copy
// nothing) or a value of its own.
class Value {
 public:
  Value() = default;
  static Value Ref(const Json& v) {
    Value out;
    out.ref_ = &v;
    return out;
  }
  explicit Value(Json v) : own_(std::move(v)) {}
  const Json& get() const { return ref_ ? *ref_ : own_; }
  bool is_ref() const { return ref_ != nullptr; }
  Json Take() && { return ref_ ? *ref_ : std::move(own_); }

 private:
  Json own_;
  const Json* ref_ = nullptr;
};

struct Context {
  const Json& datum;
  const Expression::ScaleFn& scale;
  const std::string& text;
};

// A JavaScript array index ("0", "12"; not "01" or "-1").
std::optional<size_t> ArrayIndex(std::string_view key) {
  if (key.empty() || key.size() > 15 || (key.size() > 1 && key[0] == '0')) return std::nullopt;
  size_t v = 0;
  for (const char c : key) {
    if (!IsDigit(c)) return std::nullopt;
    v = v * 10 + (c - '0');
  }
  return v;
}

// o[name]: an object's member, an array's element or length, a string's length or character;
// anything else (JavaScript's undefined, or its TypeError on null) null.
Value Member(Value o, const std::string& name) {
  const Json& v = o.get();
  if (v.is_object()) {
    const auto it = v.find(name);
    if (it == v.end()) return Value();
    return o.is_ref() ? Value::Ref(*it) : Value(Json(*it));
  }
  if (v.is_array()) {
    if (name == "length") return Value(Json(static_cast<double>(v.size())));
    const auto k = ArrayIndex(name);
    if (!k || *k >= v.size()) return Value();
    return o.is_ref() ? Value::Ref(v[*k]) : Value(Json(v[*k]));
  }
  if (v.is_string()) {
    const auto& s = v.get_ref<const std::string&>();
    if (name == "length") return Value(Json(static_cast<double>(Utf16Length(s))));
    const auto k = ArrayIndex(name);
    if (!k) return Value();
    auto unit = Utf16Unit(s, *k);
    return unit ? Value(Json(std::move(*unit))) : Value();
  }
  return Value();
}

Value Index(Value o, const Json& key) {
  const Json& v = o.get();
  if (v.is_array() && key.is_number()) {
    const double k = key.get<double>();
    if (k >= 0 && k < static_cast<double>(v.size()) && k == std::floor(k)) {
      const auto i = static_cast<size_t>(k);
      return o.is_ref() ? Value::Ref(v[i]) : Value(Json(v[i]));
    }
    return Value();
  }
  if (key.is_string()) return Member(std::move(o), key.get_ref<const std::string&>());
  return Member(std::move(o), ToJsString(key));  // the property key is String(key)
}

Value Number(double x) { return Value(Json(x)); }

Value Evaluate(const Ast& n, const Context& c);

double NumberArg(const Ast& n, size_t k, const Context& c) {
  return ToJsNumber(Evaluate(*n.kids[k], c).get());
}

// Math.max (max) or Math.min: NaN when any is, +0 above -0; no arguments -Infinity (+).
double Extremum(const Ast& n, const Context& c, bool max) {
  double out = max ? -kInf : kInf;
  bool nan = false;
  for (size_t k = 0; k < n.kids.size(); ++k) {
    const double x = NumberArg(n, k, c);
    if (std::isnan(x)) nan = true;
    if (max ? (x > out || (x == 0 && out == 0 && !std::signbit(x)))
            : (x < out || (x == 0 && out == 0 && std::signbit(x)))) {
      out = x;
    }
  }
  return nan ? kNaN : out;
}

// Math.pow: unlike C's pow, 1 ** NaN and (+-1) ** (+-Infinity) are NaN.
double JsPow(double base, double exponent) {
  if (std::isnan(exponent)) return kNaN;
  if (exponent == 0) return 1;
  if (std::isinf(exponent) && std::fabs(base) == 1) return kNaN;
  return std::pow(base, exponent);
}

std::string AsciiCase(std::string s, bool upper) {
  for (char& ch : s) {
    if (upper && ch >= 'a' && ch <= 'z') ch = static_cast<char>(ch - 'a' + 'A');
    if (!upper && ch >= 'A' && ch <= 'Z') ch = static_cast<char>(ch - 'A' + 'a');
  }
  return s;
}

Value Call(const Ast& n, const Context& c) {
  switch (n.fn) {
    case Fn::kScale: {
      if (!c.scale) {
        throw SubsetError("Vega expression \"" + c.text +
                          "\" calls scale(), but no scales were given to evaluate it with");
      }
      const Value name = Evaluate(*n.kids[0], c);
      const Value value = Evaluate(*n.kids[1], c);
      if (name.get().is_string()) {
        return Value(c.scale(name.get().get_ref<const std::string&>(), value.get()));
      }
      return Value(c.scale(ToJsString(name.get()), value.get()));
    }
    case Fn::kFormat: {
      const Value value = Evaluate(*n.kids[0], c);
      if (n.format) return Value(Json(n.format->FormatValue(value.get())));
      const Value spec = Evaluate(*n.kids[1], c);
      try {
        return Value(Json(NumberFormat(ToJsString(spec.get())).FormatValue(value.get())));
      } catch (const SubsetError& e) {
        throw SubsetError("Vega expression \"" + c.text + "\": " + e.what());
      }
    }
    case Fn::kAbs:
      return Number(std::fabs(NumberArg(n, 0, c)));
    case Fn::kSqrt:
      return Number(std::sqrt(NumberArg(n, 0, c)));
    case Fn::kRound:
      return Number(JsRound(NumberArg(n, 0, c)));
    case Fn::kFloor:
      return Number(std::floor(NumberArg(n, 0, c)));
    case Fn::kCeil:
      return Number(std::ceil(NumberArg(n, 0, c)));
    case Fn::kMin:
      return Number(Extremum(n, c, false));
    case Fn::kMax:
      return Number(Extremum(n, c, true));
    case Fn::kPow: {
      const double base = NumberArg(n, 0, c);
      return Number(JsPow(base, NumberArg(n, 1, c)));
    }
    case Fn::kLog:
      return Number(std::log(NumberArg(n, 0, c)));
    case Fn::kExp:
      return Number(std::exp(NumberArg(n, 0, c)));
    case Fn::kClamp: {  // Vega: Math.max(lo, Math.min(hi, x))
      const double x = NumberArg(n, 0, c), lo = NumberArg(n, 1, c), hi = NumberArg(n, 2, c);
      if (std::isnan(x) || std::isnan(lo) || std::isnan(hi)) return Number(kNaN);
      return Number(std::max(lo, std::min(hi, x)));
    }
    case Fn::kIsNaN: {  // Number.isNaN: no conversion
      const Value v = Evaluate(*n.kids[0], c);
      return Value(Json(v.get().is_number() && std::isnan(v.get().get<double>())));
    }
    case Fn::kIsFinite: {
      const Value v = Evaluate(*n.kids[0], c);
      return Value(Json(v.get().is_number() && std::isfinite(v.get().get<double>())));
    }
    case Fn::kIsValid: {  // _ != null && _ === _
      const Value v = Evaluate(*n.kids[0], c);
      const Json& x = v.get();
      return Value(Json(!x.is_null() && !(x.is_number() && std::isnan(x.get<double>()))));
    }
    case Fn::kIsNumber:
      return Value(Json(Evaluate(*n.kids[0], c).get().is_number()));
    case Fn::kIsString:
      return Value(Json(Evaluate(*n.kids[0], c).get().is_string()));
    case Fn::kToString: {  // vega-util: null and "" stay null
      const Value v = Evaluate(*n.kids[0], c);
      const Json& x = v.get();
      if (x.is_null() || (x.is_string() && x.get_ref<const std::string&>().empty())) return Value();
      if (x.is_string()) return Value(Json(x));
      return Value(Json(ToJsString(x)));
    }
    case Fn::kToNumber: {  // vega-util: null and "" stay null
      const Value v = Evaluate(*n.kids[0], c);
      const Json& x = v.get();
      if (x.is_null() || (x.is_string() && x.get_ref<const std::string&>().empty())) return Value();
      return Number(ToJsNumber(x));
    }
    case Fn::kLength:
      return Member(Evaluate(*n.kids[0], c), "length");
    case Fn::kJoin: {  // Array.prototype.join: nulls empty, "," unless given
      const Value a = Evaluate(*n.kids[0], c);
      if (!a.get().is_array()) return Value();
      std::string separator = ",";
      if (n.kids.size() > 1) {
        const Value s = Evaluate(*n.kids[1], c);
        if (!s.get().is_null()) separator = ToJsString(s.get());
      }
      std::string out;
      const Json& array = a.get();
      for (size_t k = 0; k < array.size(); ++k) {
        if (k) out += separator;
        if (!array[k].is_null()) out += ToJsString(array[k]);
      }
      return Value(Json(std::move(out)));
    }
    case Fn::kUpper:
    case Fn::kLower:
      return Value(Json(AsciiCase(ToJsString(Evaluate(*n.kids[0], c).get()), n.fn == Fn::kUpper)));
    case Fn::kIf:  // Vega compiles it to ?: : only the chosen branch is evaluated
      return IsTruthy(Evaluate(*n.kids[0], c).get()) ? Evaluate(*n.kids[1], c)
                                                     : Evaluate(*n.kids[2], c);
  }
  return Value();
}

Value Evaluate(const Ast& n, const Context& c) {
  switch (n.kind) {
    case Kind::kLiteral:
      return Value::Ref(n.literal);
    case Kind::kDatum:
      return Value::Ref(c.datum);
    case Kind::kMember:
      return Member(Evaluate(*n.kids[0], c), n.name);
    case Kind::kIndex: {
      Value o = Evaluate(*n.kids[0], c);
      const Value key = Evaluate(*n.kids[1], c);
      return Index(std::move(o), key.get());
    }
    case Kind::kNot:
      return Value(Json(!IsTruthy(Evaluate(*n.kids[0], c).get())));
    case Kind::kNegate:
      return Number(-NumberArg(n, 0, c));
    case Kind::kPlus:
      return Number(NumberArg(n, 0, c));
    case Kind::kBinary: {
      const Value a = Evaluate(*n.kids[0], c);
      const Value b = Evaluate(*n.kids[1], c);
      return Value(Binary(n.op, a.get(), b.get()));
    }
    case Kind::kAnd: {  // the first falsy operand, else the last
      Value a = Evaluate(*n.kids[0], c);
      return IsTruthy(a.get()) ? Evaluate(*n.kids[1], c) : a;
    }
    case Kind::kOr: {  // the first truthy operand, else the last
      Value a = Evaluate(*n.kids[0], c);
      return IsTruthy(a.get()) ? a : Evaluate(*n.kids[1], c);
    }
    case Kind::kConditional:
      return IsTruthy(Evaluate(*n.kids[0], c).get()) ? Evaluate(*n.kids[1], c)
                                                     : Evaluate(*n.kids[2], c);
    case Kind::kArray: {
      Json out = Json::array();
      for (const auto& kid : n.kids) out.push_back(Evaluate(*kid, c).Take());
      return Value(std::move(out));
    }
    case Kind::kObject: {
      Json out = Json::object();
      for (size_t k = 0; k < n.kids.size(); ++k) out[n.keys[k]] = Evaluate(*n.kids[k], c).Take();
      return Value(std::move(out));
    }
    case Kind::kCall:
      return Call(n, c);
  }
  return Value();
}

}  // namespace
}  // namespace expression_impl

struct Expression::Node {
  std::string text;
  expression_impl::AstPtr ast;
};

Expression::Expression(const std::string& text) : root_(std::make_unique<Node>()) {
  root_->text = text;
  root_->ast = expression_impl::Parser(root_->text).ParseAll();
}

Expression::~Expression() = default;
Expression::Expression(Expression&&) noexcept = default;
Expression& Expression::operator=(Expression&&) noexcept = default;

nlohmann::json Expression::Eval(const nlohmann::json& datum, const ScaleFn& scale) const {
  if (!root_) return nullptr;  // moved from
  const expression_impl::Context context{datum, scale, root_->text};
  return expression_impl::Evaluate(*root_->ast, context).Take();
}

const std::string& Expression::text() const {
  static const std::string kEmpty;
  return root_ ? root_->text : kEmpty;
}

}  // namespace rtscalib::app::vega

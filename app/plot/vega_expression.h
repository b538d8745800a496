// A small evaluator of the part of Vega 5's expression language that
// rtscalib's figures use (filters, colours, opacities, tooltips), and of
// d3-format's number formats (Vega's format() and its axis labels), so that
// a spec's encodings can be computed in C++ without node (vega_svg.h).
//
// The semantics are JavaScript's, as Vega compiles an expression to
// JavaScript: && and || give an operand, + joins strings, == is loose.
// A spec that uses a part of Vega outside this subset is not drawn wrongly:
// the parse throws SubsetError naming the part.
//
// Numbers follow the Vega that rtscalib runs (app/plot/vega.h: Debian's
// libjs-vega 5.22.1 in /usr/share/javascript/vega). Its vega-format bundles
// d3-format 1.4.5's locale, whose minus sign is the ASCII hyphen-minus "-"
// (checked in node: format(-3.5, '.1f') is "-3.5"), where upstream
// d3-format v2 and later write the Unicode minus U+2212: NumberFormat and
// Format take the minus sign for a figure that wants the latter.
#pragma once

#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <string_view>

namespace rtscalib::app::vega {

// A spec that uses a part of Vega outside the subset drawn here; the message names the part.
class SubsetError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// JavaScript truthiness of a JSON value (null, false, 0, NaN, "" are false).
bool Truthy(const nlohmann::json& v);

// JavaScript's Number -> String (String(x)): "1", "0.1", "1e+21", "1e-7", "NaN", "Infinity",
// "-0" -> "0".
std::string JsNumber(double x);

// JavaScript's String(v) of a JSON value: numbers as JsNumber, null as "null", arrays joined
// with "," (their nulls empty), objects "[object Object]".
std::string JsString(const nlohmann::json& v);

// JavaScript's unary plus (+v) of a JSON value: null 0, booleans 0 and 1, strings parsed as JS
// does ("" and blanks 0, "0x1f" 31, anything else unparsable NaN), arrays through their
// string, objects NaN.
double JsToNumber(const nlohmann::json& v);

// The minus signs a number format can write: the Vega that rtscalib runs writes the
// hyphen-minus (its d3-format locale says so); d3-format v2+ on its own writes U+2212.
inline constexpr std::string_view kVegaMinus = "-";
inline constexpr std::string_view kUnicodeMinus = "\xE2\x88\x92";

// One d3-format specifier, parsed once for many numbers (an axis's ticks, a column of a
// table): [[fill]align][sign][symbol][0][width][,][.precision][~][type], en-US locale
// (thousands ",", currency "$", decimal "."). Throws SubsetError on an invalid specifier.
class NumberFormat {
 public:
  explicit NumberFormat(const std::string& specifier, std::string_view minus = kVegaMinus);
  // d3's format(specifier)(x).
  std::string operator()(double x) const;
  // d3's format(specifier)(value) of any value: type 'c' writes String(value), the other
  // types format +value (JsToNumber).
  std::string FormatValue(const nlohmann::json& value) const;

 private:
  // The formatted digits `value` between their sign/currency prefix and unit suffix,
  // grouped and padded to the width.
  std::string Finish(std::string prefix, std::string value, std::string suffix) const;

  std::string fill_ = " ";  // one character (UTF-8)
  char align_ = '>';        // < > = ^
  char sign_ = '-';         // - + ( space
  bool zero_ = false;
  int width_ = -1;  // none
  bool comma_ = false;
  int precision_ = 6;
  bool trim_ = false;
  char type_ = 'g';  // after d3's aliases: "" and unknown types are ~g, n is ,g
  bool maybe_suffix_ = false;
  std::string prefix_;  // "$" or "0x"/"0o"/"0b"
  std::string suffix_;  // "%"
  std::string minus_;
};

// d3-format's format(specifier)(x) with the minus sign of the Vega that rtscalib runs
// (kVegaMinus): types e f g r s % p d x X o b c n and none ("" is d3's ".12~g"); '$' with
// en-US's "$", '#' alternate form ("0x" for x). Throws SubsetError on an invalid specifier.
std::string Format(double x, const std::string& specifier);
// The same with another minus sign (kUnicodeMinus for d3-format v2+).
std::string Format(double x, const std::string& specifier, std::string_view minus);

// A compiled expression: parsed once into a tree, evaluated per datum without copying it.
//
// The subset: number literals (1, .5, 1e-3, 0x1f), string literals '...' and "..." with
// JavaScript's escapes, true false null, `datum` and member access (datum.x, datum['x'],
// nested, array indices, .length of strings and arrays); ( ); unary ! - +; * / % + - (+ joins
// when either side is a string); < > <= >=; == != (loose) === !== (strict); && || (giving an
// operand); ?: ; object {'k': e, k2: e} and array [a, b] literals; Vega's constants NaN E LN2
// LN10 LOG2E LOG10E PI SQRT1_2 SQRT2 MIN_VALUE MAX_VALUE; the functions scale(name, v),
// format(v, spec), abs, sqrt, round, floor, ceil, min, max (any count), pow, log, exp, clamp,
// isNaN, isFinite, isValid, isNumber, isString, toString, toNumber, length, join, upper,
// lower, if(c, a, b): Vega's own, so that a spec drawn here is one Vega draws.
//
// Differences from JavaScript, where a figure's data cannot tell: a missing member is null
// (JavaScript's undefined: so datum.missing + 1 is 1, not NaN, and datum.missing === null is
// true); where JavaScript would throw a TypeError at run time (null.x, join() of a non-array)
// the value is null; arrays and objects compare by value (JavaScript compares references);
// upper() and lower() change ASCII letters only.
class Expression {
 public:
  // Parses `text`; throws SubsetError naming what is not supported (quoting the text).
  explicit Expression(const std::string& text);
  ~Expression();
  Expression(Expression&&) noexcept;
  Expression& operator=(Expression&&) noexcept;

  // scale(name, value) inside the expression calls this.
  using ScaleFn =
      std::function<nlohmann::json(const std::string& name, const nlohmann::json& value)>;
  // The value for one datum (a JSON object; `datum.field` and `datum['field']` read its
  // members, a missing member is null). Throws SubsetError when the expression calls scale()
  // and `scale` is empty, or formats with a specifier computed per datum that is invalid.
  nlohmann::json Eval(const nlohmann::json& datum, const ScaleFn& scale = nullptr) const;

  // The text it was parsed from.
  const std::string& text() const;

 private:
  struct Node;
  std::unique_ptr<Node> root_;
};

}  // namespace rtscalib::app::vega

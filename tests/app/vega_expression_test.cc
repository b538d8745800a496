// The Vega expression subset and d3-format (app/plot/vega_expression.h): the
// expressions the figures' specs use, JavaScript's operators and Vega's
// functions, what lies outside the subset, and d3-format's numbers.
//
// Expected values were computed by the real code in node 20: the formats by
// the vega-format module of Debian's libjs-vega 5.22.1 (the Vega rtscalib
// runs; defaultLocale().format(spec)(x)), the expressions as JavaScript with
// vega-functions' definitions of isValid, toString, toNumber, join.
#include "app/plot/vega_expression.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace rtscalib::app::vega {
namespace {

using nlohmann::json;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// What Eval gives `text` for `datum`.
json Eval(const std::string& text, const json& datum, const Expression::ScaleFn& scale = nullptr) {
  return Expression(text).Eval(datum, scale);
}

// The message of the SubsetError that parsing `text` throws ("" when none is thrown).
std::string SubsetMessage(const std::string& text) {
  try {
    Expression e(text);
  } catch (const SubsetError& e) {
    return e.what();
  }
  return "";
}

// A colour scale stand-in: "name:value".
json NamedValue(const std::string& name, const json& value) { return name + ":" + value.dump(); }

TEST(VegaExpression, EvaluatesTheFiguresFilters) {
  const Expression face("datum.face == 0");
  EXPECT_EQ(face.Eval({{"face", 0}}), true);
  EXPECT_EQ(face.Eval({{"face", 2}}), false);
  EXPECT_EQ(face.Eval({{"face", "0"}}), true);  // == is loose
  const Expression outside("!datum.inside");
  EXPECT_EQ(outside.Eval({{"inside", true}}), false);
  EXPECT_EQ(outside.Eval({{"inside", false}}), true);
  EXPECT_EQ(outside.Eval(json::object()), true);  // a missing member is falsy
  const Expression counted("datum.n > 0 && !datum.structure");
  EXPECT_EQ(counted.Eval({{"n", 3}, {"structure", false}}), true);
  EXPECT_EQ(counted.Eval({{"n", 3}, {"structure", true}}), false);
  EXPECT_EQ(counted.Eval({{"n", 0}, {"structure", false}}), false);
  const Expression structure("datum.structure");
  EXPECT_EQ(structure.Eval({{"structure", "board 2"}}), "board 2");
  EXPECT_TRUE(structure.Eval(json::object()).is_null());
  const Expression zoom("datum.zoom == 1");
  EXPECT_EQ(zoom.Eval({{"zoom", 1.0}}), true);
  EXPECT_EQ(zoom.Eval({{"zoom", 2}}), false);
  // A filter keeps a datum when the value is truthy.
  EXPECT_TRUE(Truthy(counted.Eval({{"n", 1}})));
  EXPECT_FALSE(Truthy(structure.Eval({{"structure", ""}})));
}

TEST(VegaExpression, EvaluatesTheFiguresEncodings) {
  std::vector<std::pair<std::string, json>> calls;
  const Expression::ScaleFn colour = [&](const std::string& name, const json& value) {
    calls.emplace_back(name, value);
    return json("#123456");
  };
  const Expression fill("datum.value === null ? '#bbbbbb' : scale('colour', datum.value)");
  EXPECT_EQ(fill.Eval({{"value", nullptr}}, colour), "#bbbbbb");
  EXPECT_TRUE(calls.empty());
  EXPECT_EQ(fill.Eval({{"value", 0.25}}, colour), "#123456");
  ASSERT_EQ(calls.size(), 1u);
  EXPECT_EQ(calls[0].first, "colour");
  EXPECT_EQ(calls[0].second, 0.25);

  const Expression opacity("datum.inside ? 1 : 0.55");
  EXPECT_EQ(opacity.Eval({{"inside", true}}), 1.0);
  EXPECT_EQ(opacity.Eval({{"inside", false}}), 0.55);
  const Expression status("datum.status == 'fitted' ? '#00e5ff' : '#ff00ff'");
  EXPECT_EQ(status.Eval({{"status", "fitted"}}), "#00e5ff");
  EXPECT_EQ(status.Eval({{"status", "held out"}}), "#ff00ff");
  const Expression stroke("datum.rms > 0.5 ? '#d62728' : null");
  EXPECT_EQ(stroke.Eval({{"rms", 0.7}}), "#d62728");
  EXPECT_TRUE(stroke.Eval({{"rms", 0.2}}).is_null());

  const Expression tooltip(
      "{'from': format(datum.x0, '.3g'), 'to': format(datum.x1, '.3g'), 'count': datum.n}");
  EXPECT_EQ(tooltip.Eval({{"x0", 0.000123456}, {"x1", 123456}, {"n", 7}}),
            json({{"from", "0.000123"}, {"to", "1.23e+5"}, {"count", 7}}));
  EXPECT_EQ(tooltip.Eval({{"x0", -1.5}, {"x1", 2}, {"n", 0}}),
            json({{"from", "-1.50"}, {"to", "2.00"}, {"count", 0}}));
  const Expression pair("datum.i + ', ' + datum.j");
  EXPECT_EQ(pair.Eval({{"i", 3}, {"j", 0.5}}), "3, 0.5");
  EXPECT_EQ(pair.Eval({{"i", "a"}, {"j", 1e21}}), "a, 1e+21");
}

TEST(VegaExpression, FollowsJavaScriptOperators) {
  const json d = json::parse(R"({"a": 1, "b": 2.5, "z": 0, "s": "abc", "e": "", "t": "12",
      "n": null, "tr": true, "arr": [1, "x", null, [2, 3]], "o": {"p": {"q": "deep"}, "k": 7},
      "u": "\u00e9\ud83d\ude00"})");
  const std::vector<std::pair<std::string, json>> cases = {
      // + adds numbers and joins strings; arrays join with ",".
      {"datum.a + datum.b", 3.5},
      {"datum.a + datum.s", "1abc"},
      {"datum.s + datum.n", "abcnull"},
      {"datum.a + datum.n", 1},
      {"datum.a + datum.tr", 2},
      {"datum.arr + ''", "1,x,,2,3"},
      {"[1, 2] + [3]", "1,23"},
      {"1 + 2 + '3' + 4 + 5", "3345"},
      {"0.1 + 0.2 + ''", "0.30000000000000004"},
      {"datum.t - 2", 10},
      {"datum.t * '3'", 36},
      {"2 - 3 * 4 + 10 / 4", -7.5},
      {"-7 % 3", -1},
      {"7.5 % -2", 1.5},
      {"datum.a / datum.z", kInf},
      // == is loose, === strict.
      {"datum.a == '1'", true},
      {"datum.t == 12", true},
      {"datum.n == null", true},
      {"datum.n == 0", false},
      {"datum.z == false", true},
      {"datum.z == ''", true},
      {"datum.tr == '1'", true},
      {"datum.arr == '1,x,,2,3'", true},
      {"datum.a === '1'", false},
      {"datum.n === null", true},
      {"datum.a !== datum.b", true},
      {"datum.a != '2'", true},
      // Strings compare by UTF-16 units, anything else as numbers.
      {"datum.s < 'abd'", true},
      {"'B' < 'a'", true},
      {"'10' < '9'", true},
      {"10 < '9'", false},
      {"datum.a < datum.s", false},
      {"datum.a >= datum.s", false},
      {"datum.n <= 0", true},
      {"'a' < datum.u", true},
      // && and || give an operand.
      {"datum.a && datum.s", "abc"},
      {"datum.z && datum.s", 0},
      {"datum.n || datum.e || 'last'", "last"},
      {"!datum.e", true},
      {"!!datum.arr", true},
      {"-datum.t", -12},
      {"+' 0x1F '", 31},
      {"+'5.'", 5},
      {"+'1e400'", kInf},
      {"+[5]", 5},
      {"- - 1", 1},
      {"datum.z ? 'y' : datum.s ? 'n1' : 'n2'", "n1"},
      // Members.
      {"datum.o.p.q", "deep"},
      {"datum.o['p']['q']", "deep"},
      {"datum['o'].k", 7},
      {"datum.arr[1]", "x"},
      {"datum.arr[3][0]", 2},
      {"datum.arr['1']", "x"},
      {"datum.arr.length", 4},
      {"datum.u.length", 3},
      {"datum.s[1]", "b"},
      {"datum.o.missing", nullptr},
      {"datum.arr[7]", nullptr},
      {"datum.n.x", nullptr},  // JavaScript: a TypeError
      // Literals.
      {"1e-3 + .5", 0.501},
      {"0x1F + 1", 32},
      {R"('\x41\u0042\u{43}\n\'q\'\t\\')", "ABC\n'q'\t\\"},
      {R"("it's")", "it's"},
      {R"('\uD83D\uDE00'.length)", 2},
      {"[datum.a, datum.s, [datum.z]]", json::parse(R"([1, "abc", [0]])")},
      {"{a: 1, 'b c': datum.s, 3: 'three', \"d\": datum.o.k}",
       json::parse(R"({"a": 1, "b c": "abc", "3": "three", "d": 7})")},
      {"PI * 2", 2 * M_PI},
      {"1 / 3 /* a comment */", 1.0 / 3},
  };
  for (const auto& [text, want] : cases) {
    SCOPED_TRACE(text);
    const json got = Eval(text, d);
    if (want.is_number() && got.is_number()) {
      EXPECT_EQ(got.get<double>(), want.get<double>());
    } else {
      EXPECT_EQ(got, want);
    }
  }
  EXPECT_TRUE(std::isnan(Eval("datum.z / datum.z", d).get<double>()));
  EXPECT_TRUE(std::isnan(Eval("+datum.s", d).get<double>()));
  EXPECT_TRUE(std::isnan(Eval("datum.a - datum.s", d).get<double>()));
}

TEST(VegaExpression, CallsTheSubsetsFunctions) {
  const json d = json::parse(
      R"({"a": 1, "z": 0, "s": "abc", "e": "", "t": "12", "n": null, "neg": -3.5, "big": 1e21,
          "arr": [1, "x", null, [2, 3]]})");
  const std::vector<std::pair<std::string, json>> cases = {
      {"format(datum.neg, '.1f')", "-3.5"},
      {"format(datum.t, '.2f')", "12.00"},
      {"format(datum.s, 'c')", "abc"},
      {"format(1234.5, ',.' + 1 + 'f')", "1,234.5"},  // a specifier computed per datum
      {"abs(datum.neg)", 3.5},
      {"sqrt(16)", 4},
      {"round(2.5)", 3},
      {"round(-2.5)", -2},
      {"round(0.49999999999999994)", 0},
      {"ceil(-0.5)", -0.0},
      {"ceil(datum.t)", 12},
      {"min(3, datum.a, '0.5')", 0.5},
      {"max(datum.n, -1)", 0},
      {"max()", -kInf},
      {"min()", kInf},
      {"pow(2, 10)", 1024},
      {"log(E)", 1},
      {"exp(0)", 1},
      {"clamp(5, 0, 3)", 3},
      {"isNaN(NaN)", true},
      {"isNaN('x')", false},
      {"isFinite(datum.big)", true},
      {"isFinite('1')", false},
      {"isValid(datum.n)", false},
      {"isValid(datum.missing)", false},
      {"isValid(datum.z)", true},
      {"isValid(0/0)", false},
      {"isValid(datum.e)", true},
      {"isNumber(datum.t)", false},
      {"isNumber(NaN)", true},
      {"isString(datum.t)", true},
      {"toString(datum.a)", "1"},
      {"toString(datum.e)", nullptr},
      {"toString(datum.n)", nullptr},
      {"toString(datum.arr)", "1,x,,2,3"},
      {"toString(datum.big)", "1e+21"},
      {"toNumber(datum.t)", 12},
      {"toNumber(datum.e)", nullptr},
      {"length(datum.s)", 3},
      {"length(datum.arr)", 4},
      {"join(datum.arr)", "1,x,,2,3"},
      {"join(datum.arr, ' | ')", "1 | x |  | 2,3"},
      {"join([1.5, true, 'x'], '')", "1.5truex"},
      {"upper(datum.s)", "ABC"},
      {"lower('ABC dEf')", "abc def"},
      {"upper(datum.n)", "NULL"},
      {"if(datum.a, 'yes', 'no')", "yes"},
      {"if(datum.e, 'yes', 'no')", "no"},
  };
  for (const auto& [text, want] : cases) {
    SCOPED_TRACE(text);
    const json got = Eval(text, d);
    if (want.is_number() && got.is_number()) {
      EXPECT_EQ(got.get<double>(), want.get<double>());
      EXPECT_EQ(std::signbit(got.get<double>()), std::signbit(want.get<double>()));
    } else {
      EXPECT_EQ(got, want);
    }
  }
  EXPECT_TRUE(std::isnan(Eval("sqrt(-1)", d).get<double>()));
  EXPECT_TRUE(std::isnan(Eval("pow(1, NaN)", d).get<double>()));  // C's pow gives 1
  EXPECT_TRUE(std::isnan(Eval("max(1, NaN, 3)", d).get<double>()));
  EXPECT_TRUE(std::isnan(Eval("toNumber('abc')", d).get<double>()));
  // scale() hands the name and the value over; if() evaluates only the branch it takes.
  EXPECT_EQ(Eval("scale('x', datum.arr)", d, NamedValue), R"(x:[1,"x",null,[2,3]])");
  EXPECT_EQ(Eval("if(datum.z, scale('x', 1), 'no scale')", d), "no scale");
}

TEST(VegaExpression, IsParsedOnceAndMoves) {
  Expression e("datum.v * 2");
  Expression moved(std::move(e));
  EXPECT_EQ(moved.text(), "datum.v * 2");
  for (int v = 0; v < 1000; ++v) ASSERT_EQ(moved.Eval({{"v", v}}).get<double>(), 2.0 * v);
  Expression assigned("0");
  assigned = std::move(moved);
  EXPECT_EQ(assigned.Eval({{"v", 4}}), 8.0);
}

TEST(VegaExpression, RejectsWhatIsOutsideTheSubset) {
  struct Case {
    std::string text;
    std::string names;  // the message names this
  };
  const std::vector<Case> cases = {
      {"foo(datum.x)", "unknown function 'foo'"},
      {"window.x", "identifier 'window'"},
      {"sign(-3)", "sign"},  // JavaScript's Math.sign, not a Vega function
      {"datum.x == 'abc", "unterminated string literal"},
      {"'abc\ndef'", "unterminated string literal"},
      {"datum.x = 1", "assignment"},
      {"datum.x += 1", "assignment"},
      {"/ab+c/.test(datum.s)", "regular expression"},
      {"this.x", "'this'"},
      {"typeof datum.x", "'typeof'"},
      {"datum.x | 1", "operator '|'"},
      {"datum.x ** 2", "operator '**'"},
      {"'a' in datum", "operator 'in'"},
      {"datum.x++", "'++'"},
      {"datum.f(1)", "only the functions of the subset"},
      {"event.x", "identifier 'event'"},
      {"undefined", "identifier 'undefined'"},
      {"if(datum.x, 1)", "if() takes 3 arguments, not 2"},
      {"scale('x', 1, 'group')", "scale() takes 2 arguments"},
      {"format(datum.x, '.2q.')", "invalid d3 format specifier \".2q.\""},
      {"datum.x ? 1", "expected ':'"},
      {"(datum.x", "expected ')'"},
      {"datum.x 1", "unexpected number 1"},
      {"", "the expression ends early"},
      {"`a${1}`", "template literals"},
      {"1, 2", "comma operator"},
      {"[1, , 2]", "holes"},
      {"{a}", "need a value"},
      {"012", "leading zero"},
      {"3in", "a name right after a number"},
      {"datum.x; 1", "statements"},
      {"datum?.x", "optional chaining"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.text);
    const std::string message = SubsetMessage(c.text);
    EXPECT_NE(message.find(c.names), std::string::npos) << message;
    EXPECT_NE(message.find("\"" + c.text + "\""), std::string::npos) << message;  // quoted
  }
  // scale() without scales, and a format specifier computed per datum, fail when evaluated.
  EXPECT_THROW(Eval("scale('colour', 1)", json::object()), SubsetError);
  EXPECT_THROW(Eval("format(1, datum.spec)", {{"spec", "..2f"}}), SubsetError);
  // Conditionals that look like other syntax are fine.
  EXPECT_EQ(Eval("datum.x?.5:1", {{"x", true}}), 0.5);
}

TEST(VegaFormat, MatchesD3Format) {
  struct Case {
    double x;
    const char* specifier;
    const char* d3;  // d3-format's output (node, vega-format of libjs-vega 5.22.1)
  };
  const std::vector<Case> cases = {
      {1234.5, ",f", "1,234.500000"},
      {1234.5, ",.0f", "1,235"},
      {0.000123, ".3g", "0.000123"},
      {123456, ".3g", "1.23e+5"},  // toPrecision: exponent >= precision
      {1.5e-7, ".3g", "1.50e-7"},
      {0.25, ".0%", "25%"},
      {-3.5, ".1f", "-3.5"},  // this Vega's locale: the hyphen-minus
      {42, "d", "42"},
      {1500, ".2s", "1.5k"},
      {0.02, "~s", "20m"},
      {0.5, "", "0.5"},
      {3, ".1f", "3.0"},
      {1000000, ",", "1,000,000"},
      {0.1 + 0.2, "~g", "0.3"},
      {-0.0, ".1f", "0.0"},
      {-0.04, ".1f", "0.0"},  // rounds to zero: no sign
      {2.5, ".0f", "3"},      // toFixed: a tie rounds up (printf would give 2)
      {0.125, ".2f", "0.13"},
      {1.005, ".2f", "1.00"},  // 1.005 is 1.00499999999999989...
      {999.5, ".0f", "1000"},
      {9.995, ".2f", "9.99"},
      {0.0005, ".0e", "5e-4"},
      {2.5, ".1e", "2.5e+0"},
      {25, ".1r", "30"},
      {0.00012345, ".2r", "0.00012"},
      {1234567, ".3r", "1230000"},
      {1e-7, ".3s", "100n"},
      {1.5e-30, ".2s", "0.0000015y"},
      {123456789, "~s", "123.457M"},
      {0, "s", "0.00000"},
      {0.0042, ".1p", "0.4%"},
      {0.123, "~%", "12.3%"},
      {255, "x", "ff"},
      {255, "#X", "0xFF"},
      {5, "#b", "0b101"},
      {8, "o", "10"},
      {-255, "x", "-ff"},
      {1e+21, "d", "1e+21"},
      {-2.5, "d", "-3"},  // Math.round of 2.5, then the sign
      {65, "c", "65"},
      {42.5, "$,.2f", "$42.50"},
      {-42.5, "($.2f", "($42.50)"},
      {42, "+d", "+42"},
      {42, " d", " 42"},
      {-1234.5, "010,.1f", "-0,001,234.5"},
      {1234.5, "0=12,.1f", "00,001,234.5"},
      {3.14159, "*^11.3f", "***3.142***"},
      {42, "<6d", "42    "},
      {-42, "=+8d", "-     42"},
      {12345678, "020,d", "0,000,000,012,345,678"},
      {1e+21, ",", "1e+21"},
      {1.23456789e-7, "", "1.23456789e-7"},
      {kNaN, ".2f", "NaN"},
      {kInf, ",.1f", "Infinity"},
      {-kInf, "e", "-Infinity"},
      {123.456, "~e", "1.23456e+2"},
      {0.000001, "", "0.000001"},
      {123456.789, ".3n", "1.23e+5"},
      {1.5, "E", "1.5"},  // an unknown type is ".12~g"
      {3.7, "~f", "3.7"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(std::string(c.specifier) + " of " + JsNumber(c.x));
    EXPECT_EQ(Format(c.x, c.specifier), c.d3);
    EXPECT_EQ(NumberFormat(c.specifier)(c.x), c.d3);
  }
  // Multi-byte fills count as one character, as in JavaScript.
  EXPECT_EQ(Format(-42, "\xC2\xB5>6d"), "\xC2\xB5\xC2\xB5\xC2\xB5-42");
  EXPECT_EQ(Format(1.5e-6, ".2s"), "1.5\xC2\xB5");  // micro sign U+00B5
}

TEST(VegaFormat, WritesTheMinusSignAsked) {
  EXPECT_EQ(Format(-3.5, ".1f", kUnicodeMinus),
            "\xE2\x88\x92"
            "3.5");
  EXPECT_EQ(Format(-3.5, ".1f", kVegaMinus), "-3.5");
  EXPECT_EQ(Format(-0.0, ".1f", kUnicodeMinus), "0.0");
  // The minus sign is one character of a width.
  EXPECT_EQ(NumberFormat("6.1f", kUnicodeMinus)(-3.5),
            "  \xE2\x88\x92"
            "3.5");
}

TEST(VegaFormat, FormatsAnyValueAsD3Does) {
  const NumberFormat f(".1f");
  EXPECT_EQ(f.FormatValue("2.25"), "2.3");
  EXPECT_EQ(f.FormatValue(nullptr), "0.0");
  EXPECT_EQ(f.FormatValue(true), "1.0");
  EXPECT_EQ(f.FormatValue("x"), "NaN");
  EXPECT_EQ(NumberFormat(">5c").FormatValue("ab"), "   ab");
}

TEST(VegaFormat, RejectsInvalidSpecifiers) {
  for (const char* s : {".", "..2f", ".f", "~~f", "5.2.f", "$$", "abc", "<<<", "\n>5"}) {
    SCOPED_TRACE(s);
    EXPECT_THROW(Format(1, s), SubsetError);
  }
  EXPECT_NO_THROW(Format(1, ""));
  try {
    Format(1, ".2q.");
    FAIL();
  } catch (const SubsetError& e) {
    EXPECT_NE(std::string(e.what()).find("\".2q.\""), std::string::npos) << e.what();
  }
}

TEST(VegaJsNumber, WritesNumbersAsJavaScript) {
  const std::vector<std::pair<double, const char*>> cases = {
      {1, "1"},
      {0.1, "0.1"},
      {1e+21, "1e+21"},
      {1e-7, "1e-7"},
      {1.5e-7, "1.5e-7"},
      {123456789012345680000.0, "123456789012345680000"},
      {0.000001, "0.000001"},
      {-0.0, "0"},
      {-1.5, "-1.5"},
      {1.0 / 3, "0.3333333333333333"},
      {0.1 + 0.2, "0.30000000000000004"},
      {9007199254740992, "9007199254740992"},
      {1e+300, "1e+300"},
      {5e-324, "5e-324"},
      {100, "100"},
      {1.7976931348623157e+308, "1.7976931348623157e+308"},
      {1.23e-18, "1.23e-18"},
      {kNaN, "NaN"},
      {kInf, "Infinity"},
      {-kInf, "-Infinity"},
  };
  for (const auto& [x, want] : cases) EXPECT_EQ(JsNumber(x), want);
  EXPECT_EQ(JsString(json::parse(R"([1, null, [2, "a"], {"k": 1}])")), "1,,2,a,[object Object]");
  EXPECT_EQ(JsToNumber(json("  -1.5e3 ")), -1500);
  EXPECT_TRUE(std::isnan(JsToNumber(json("1_000"))));
}

}  // namespace
}  // namespace rtscalib::app::vega

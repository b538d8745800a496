#include "libcalib/text/number_text.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

namespace rtscalib {
namespace {

TEST(NumberText, ParsesDecimalNumbersOnly) {
  EXPECT_EQ(ParseFiniteDouble("1.5"), 1.5);
  EXPECT_EQ(ParseFiniteDouble("+2e-3"), 2e-3);
  EXPECT_EQ(ParseFiniteDouble("-.5"), -0.5);
  for (const char* bad :
       {"", "abc", "1.5x", "nan", "NaN", "inf", "-inf", "Infinity", "0x10", "+-1", "1,5", " 1"}) {
    EXPECT_FALSE(ParseFiniteDouble(bad).has_value()) << bad;
  }
  EXPECT_TRUE(std::isnan(*ParseDouble("nan")));
  EXPECT_TRUE(std::isinf(*ParseDouble("-inf")));
}

TEST(NumberText, IntegersMayBeWrittenAsIntegralDecimals) {
  EXPECT_EQ(ParseInteger("2"), 2);
  EXPECT_EQ(ParseInteger("2.0"), 2);
  EXPECT_EQ(ParseInteger("-1"), -1);
  EXPECT_EQ(ParseInteger("9007199254740993"), 9007199254740993LL);  // beyond 2^53: exact
  EXPECT_FALSE(ParseInteger("2.5").has_value());
  EXPECT_FALSE(ParseInteger("1e30").has_value());
  EXPECT_FALSE(ParseInteger("one").has_value());
}

// %.17g and the shortest form both read back to the same double.
TEST(NumberText, FormattingRoundTripsBitExactly) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> mantissa(-1, 1);
  std::uniform_int_distribution<int> exponent(-300, 300);
  for (int i = 0; i < 2000; ++i) {
    const double x = std::ldexp(mantissa(rng), exponent(rng));
    EXPECT_EQ(*ParseFiniteDouble(FormatDouble(x)), x);
    EXPECT_EQ(*ParseFiniteDouble(FormatShortestDouble(x)), x);
  }
  EXPECT_EQ(FormatShortestDouble(1e-5), "1e-05");
  EXPECT_EQ(YamlDouble(std::nan("")), ".nan");
  EXPECT_EQ(YamlDouble(-INFINITY), "-.inf");
}

// Significant digits are printf's %.*g to the character (residuals.csv was
// written with snprintf, and people diff such tables across versions): random
// doubles over the whole exponent range, values that round up to the next
// power of ten, the switch between fixed and exponent form, signed zeros and
// the non-finite values.
TEST(NumberText, SignificantIsPrintfG) {
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> mantissa(-1, 1);
  std::uniform_int_distribution<int> exponent(-1070, 1020);
  std::vector<double> values = {0.0,       -0.0,        1.0,         9.9999999999,
                                99999.95,  1e-5,        1.5e-4,      123456,
                                1234567.0, 0.000123456, 5e-324,      1.7976931348623157e308,
                                INFINITY,  -INFINITY,   std::nan("")};
  for (int i = 0; i < 5000; ++i) values.push_back(std::ldexp(mantissa(rng), exponent(rng)));
  for (const double x : values) {
    for (const int digits : {1, 3, 6, 8, 10, 17}) {
      char expected[64];
      std::snprintf(expected, sizeof expected, "%.*g", digits, x);
      std::string got = "#";
      AppendSignificant(&got, x, digits);
      EXPECT_EQ(got, std::string("#") + expected) << digits;
      EXPECT_EQ(Significant(x, digits), expected);
    }
  }
}

}  // namespace
}  // namespace rtscalib

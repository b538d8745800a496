#include "libcalib/text/number_text.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

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

}  // namespace
}  // namespace rtscalib

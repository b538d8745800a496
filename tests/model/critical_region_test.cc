#include "libcalib/model/critical_region.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

namespace rtscalib {
namespace {

using ::testing::HasSubstr;

TEST(CriticalRegion, BothFaces) {
  // Zenith angles near 0 and beyond the upper limit, and their face-2
  // mirrors (2 pi - theta), are critical.
  const double deg = M_PI / 180;
  const CriticalRegion region;  // the defaults: 10 and 135 deg
  EXPECT_EQ(region.min_zenith_rad, 10 * deg);
  EXPECT_EQ(region.max_zenith_rad, 135 * deg);
  EXPECT_TRUE(region.Contains(5 * deg));
  EXPECT_FALSE(region.Contains(90 * deg));
  EXPECT_TRUE(region.Contains(140 * deg));
  EXPECT_TRUE(region.Contains(2 * M_PI - 5 * deg));
  EXPECT_FALSE(region.Contains(2 * M_PI - 90 * deg));
  EXPECT_TRUE(region.Contains(2 * M_PI - 140 * deg));
  EXPECT_FALSE(region.Contains(region.min_zenith_rad)) << "the limits themselves are usable";
  EXPECT_FALSE(region.Contains(region.max_zenith_rad));
}

TEST(CriticalRegion, CheckNamesBothLimits) {
  EXPECT_EQ(CriticalRegion().Check(), "");
  EXPECT_EQ((CriticalRegion{0.0, M_PI}).Check(), "") << "the whole half circle is valid";
  EXPECT_THAT((CriticalRegion{2.0, 1.0}).Check(), HasSubstr("got min 2, max 1"));
  EXPECT_THAT((CriticalRegion{-0.1, 1.0}).Check(), HasSubstr("zenith limits"));
  EXPECT_THAT((CriticalRegion{0.1, 4.0}).Check(), HasSubstr("max 4"));
  EXPECT_THAT((CriticalRegion{std::nan(""), 1.0}).Check(), HasSubstr("zenith limits"));
}

}  // namespace
}  // namespace rtscalib

#include "libcalib/geometry/convex_hull.h"

#include <gtest/gtest.h>

namespace rtscalib {
namespace {

TEST(ConvexHull, KeepsTheCornersDropsInteriorAndCollinearPoints) {
  std::vector<Eigen::Vector2d> p = {{0, 0}, {10, 0}, {10, 5}, {0, 5}, {5, 0},
                                    {3, 2}, {7, 4},  {0, 2},  {10, 5}};
  const std::vector<Eigen::Vector2d> hull = ConvexHull(p);
  ASSERT_EQ(hull.size(), 4u);
  EXPECT_TRUE(InsideConvexHull(hull, {5, 2.5}));
  EXPECT_TRUE(InsideConvexHull(hull, {10, 5}));  // on the hull counts as inside
  EXPECT_FALSE(InsideConvexHull(hull, {10.01, 2}));
  EXPECT_FALSE(InsideConvexHull(hull, {-1, -1}));
}

TEST(ConvexHull, FewerThanThreePointsHaveNoInside) {
  EXPECT_TRUE(ConvexHull({}).empty());
  const std::vector<Eigen::Vector2d> two = ConvexHull({{0, 0}, {1, 1}, {0, 0}});
  EXPECT_EQ(two.size(), 2u);
  EXPECT_FALSE(InsideConvexHull(two, {0.5, 0.5}));
}

}  // namespace
}  // namespace rtscalib

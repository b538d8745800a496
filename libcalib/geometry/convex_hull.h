// The convex hull of points in the plane (Andrew's monotone chain,
// O(n log n)): the valid region of a camera, the hull of the pixels where
// calibration points fell (model.yaml `valid_region`).
#pragma once

#include <Eigen/Core>
#include <vector>

namespace rtscalib {

// Hull vertices in counter-clockwise order of the (x, y) axes as drawn (in
// image coordinates, v down, the order looks clockwise), without collinear
// points; fewer than 3 points (or all collinear) give the distinct extremes.
std::vector<Eigen::Vector2d> ConvexHull(std::vector<Eigen::Vector2d> points);

// Whether p lies inside or on the hull (a polygon from ConvexHull with at
// least 3 vertices; false otherwise).
bool InsideConvexHull(const std::vector<Eigen::Vector2d>& hull, const Eigen::Vector2d& p);

}  // namespace rtscalib

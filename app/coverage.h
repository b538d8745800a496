// Where in each zoom's images the observed points fell, and what that means
// for the distortion model.
//
// Per zoom: an occupancy grid of kCoverageCells x kCoverageCells cells over
// the image (counts of pixel observations per cell; cell (i, j) covers
// u in [i W/n, (i+1) W/n), v in [j H/n, (j+1) H/n)), the fraction of cells
// with at least one point (the covered fraction of the image's area at that
// resolution), and the largest observed radius from the principal point
// over the radius of the farthest image corner (both in pixels of the
// fitted camera). Warnings:
//   * extrapolated: radius fraction < 0.8, or a corner cell (of the 3x3
//     grid's corners) without points: the distortion polynomial is evaluated
//     at the image's corners beyond the data;
//   * badly determined: a fitted distortion coefficient whose sigma exceeds
//     its absolute value (relative sigma > 1), naming coefficient and zoom,
//     with the shift one sigma gives at the image corner (k1, k2, k3, p1,
//     p2), so that a coefficient merely near zero (a small shift) can be told
//     from one that leaves the outer image undetermined.
#pragma once

#include <string>
#include <vector>

#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"

namespace rtscalib::app {

inline constexpr int kCoverageCells = 8;

struct ZoomCoverage {
  int zoom = 0;
  int width = 0, height = 0;
  int points = 0;
  std::vector<int> counts;  // kCoverageCells^2, row-major by v cell, then u cell
  double covered_fraction = 0;
  double radius_fraction = 0;    // largest observed radius / image corner radius
  bool corners_covered = false;  // each 3x3 corner cell holds points
};

struct CoverageReport {
  std::vector<ZoomCoverage> zooms;
  std::vector<std::string> warnings;
};

CoverageReport ComputeCoverage(const Observations& obs, const InstrumentModel& model);

}  // namespace rtscalib::app

// What the data cover, and what an effect would need to be identifiable.
//
// Each catalogue effect's signature (SPEC 4) needs some variation in the data
// to be told apart from the rest of the model:
//   collimation   c/sin z, sign flips with face     -> steep sights, both faces
//   tilting_axis  i cot z, sign flips with face     -> steep sights, both faces
//   vertical_index constant dz, flips with face     -> both faces
//   hz_eccentricity, hz_scale, axis_wobble          -> a full turn in phi (wobble: steep sights
//   too) v_eccentricity, v_scale                         -> a wide zenith range, both faces
//   edm_scale                                       -> distances over a wide range
//   edm_offset                                      -> EDM distances at all
//   edm_cyclic                                      -> distances sampled finer than U/4 over >= U
//   distortion groups                               -> points near the image corners
//   focus                                           -> camera targets near and far (per zoom)
//   board_warp                                      -> each board of estimated pose seen in
//                                                      several views, tilted both ways about
//                                                      both its axes (BoardViews)
// `WhatWouldHelp` returns the requirements the data do not meet, in words.
//
// Image coverage per zoom (ImageCoverage): an occupancy grid of
// kCoverageCells x kCoverageCells cells over the image (cell (i, j) covers
// u in [i W/n, (i+1) W/n), v in [j H/n, (j+1) H/n), pixel centres at integers,
// SPEC 2), the share of cells holding points, and whether each corner ninth
// of the image (3 x 3 grid) holds points. `CoverageWarnings` turns coverage and
// the fitted distortion into sentences:
//   * extrapolated: the farthest point below CoverageRules::corner_fraction of
//     the half-diagonal, or a corner ninth without points: the distortion
//     polynomial is evaluated at the image's corners beyond the data;
//   * badly determined: a fitted distortion coefficient whose sigma exceeds its
//     absolute value, with the shift one sigma gives at the image corner (k1,
//     k2, k3, p1, p2), so that a coefficient merely near zero (a small shift)
//     can be told from one that leaves the outer image undetermined.
#pragma once

#include <map>
#include <set>
#include <string>
#include <vector>

#include "libcalib/fit/refine.h"
#include "libcalib/model/effects.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"

namespace rtscalib {

// Thresholds of the requirements above (degrees, metres, fractions).
struct CoverageRules {
  double steep_zenith_deg = 60.0;  // a sight is steep below this zenith angle or above 180 - it
  double wide_zenith_deg = 90.0;   // zenith range counted as wide
  double full_turn_deg = 270.0;    // phi span counted as a full turn
  double distance_ratio = 5.0;     // max / min EDM distance for scale
  double long_distance_m = 10.0;
  double corner_fraction = 0.7;  // of the half-diagonal from the image centre
  // focus (SPEC 4.1) is 1/D: targets at one distance cannot tell it from fx, cx, cy.
  double focus_distance_ratio = 2.0;  // farthest / nearest camera target of a zoom
  // board_warp: seen head-on, a board's bow moves its image like a change of
  // its distance and of the lens's radial distortion; tilted, its near and
  // far halves move apart, which no pose does. Views of each board spanning
  // this much tilt about each of its axes, and this many views.
  double warp_tilt_span_deg = 20.0;
  int warp_views = 3;
};

// How a board of estimated pose was seen: its views (photos) and the span of
// the viewing direction's tilt away from the board's normal, about the
// board's y axis (across, along x) and about its x axis (along y) [deg].
struct BoardViews {
  int views = 0;
  double tilt_x_min = 0, tilt_x_max = 0;  // about the board's y axis
  double tilt_y_min = 0, tilt_y_max = 0;  // about the board's x axis
};

inline constexpr int kCoverageCells = 8;

struct ImageCoverage {
  int zoom = 0;
  int width = 0, height = 0;
  int points = 0;
  std::vector<int> counts;       // kCoverageCells^2, row-major by v cell, then u cell
  double covered_fraction = 0;   // cells with points / all cells
  bool corners_covered = false;  // each corner ninth of the image holds points
};

struct Coverage {
  std::set<int> faces;
  double min_zenith_deg = 0, max_zenith_deg = 0;
  double phi_span_deg = 0;  // 360 minus the largest gap between pointings
  bool has_edm = false, has_cam = false;
  double min_edm_m = 0, max_edm_m = 0;
  int distinct_edm = 0;
  double finest_edm_step_m = 0;         // smallest gap between distinct EDM distances
  std::vector<double> corner_fraction;  // per zoom: farthest observed pixel / half-diagonal
  // per zoom: nearest and farthest camera target (photos' D, cam rows' d) [m]
  std::map<int, std::pair<double, double>> target_distance;
  std::vector<ImageCoverage> images;    // per zoom with image points
  std::map<int, BoardViews> boards;     // per board of estimated pose (first_id)
  int records = 0, pixels = 0;          // used (outside the critical regions)
};

// Over the rows the fit uses (outside the critical regions): pixels and cam
// records.
Coverage MeasureCoverage(const Observations& obs, const InstrumentModel& model,
                         const FitOptions& fit);

std::vector<std::string> CoverageWarnings(const Coverage& c, const InstrumentModel& model,
                                          const CoverageRules& rules = {});

std::vector<std::string> WhatWouldHelp(Effect e, const Coverage& c, const InstrumentModel& model,
                                       const CoverageRules& rules = {});

}  // namespace rtscalib

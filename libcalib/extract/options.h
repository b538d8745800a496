// Options and the error type of the geometric model extraction (Klug et al.
// Sec. 3, docs/extraction.md).
#pragma once

#include <cmath>
#include <stdexcept>
#include <string>

#include "libcalib/geometry/lines.h"
#include "libcalib/model/critical_region.h"

namespace rtscalib {

// Raised when the records cannot give a model: no joint sweep, a sweep whose
// points lie on neither a circle nor a line, an end effector on a joint axis,
// a prismatic joint (the instrument model has revolute joints only), or too
// few tool correspondences. The message names the sweep (face, tool, constant
// control value, number of points, fit residual) and the paper's remedy.
struct ExtractionError : std::runtime_error {
  explicit ExtractionError(const std::string& message) : std::runtime_error(message) {}
};

struct ExtractOptions {
  // Face-1 rows in the critical regions are excluded from extraction and
  // counted (Calibrate passes FitOptions::critical_region).
  CriticalRegion critical_region;

  // Two control readings (or two distances) closer than this are "the same".
  // Above the encoder noise of an RTS (~1e-5 rad, 2"), far below any sensible
  // sweep step (the paper's is 24 deg).
  double angle_tolerance_rad = 1e-4;
  double distance_tolerance_m = 1e-6;
  // Two pixels closer than this are the same pixel (CSV round trips are exact
  // to ~1e-12 px; the paper's pixel steps are 1 px).
  double pixel_tolerance_px = 1e-3;

  // A joint sweep needs at least this many distinct control values. Three
  // points always lie on a circle, so fewer than 5 cannot tell circle from
  // "neither".
  int min_sweep_points = 5;
  // A trajectory is a circle (line) when the RMS of the points' distances to
  // the fitted circle (line) is at most this. 1 mm: ten times the point noise
  // of a good RTS at the paper's 1 m arm, and 100 times below the deviation
  // of a wrong trajectory type at that arm.
  double max_fit_rms_m = 1e-3;
  // A circle of a smaller radius (or a point cloud of a smaller spread) means
  // the recorded point sits on the joint axis: the axis direction is then not
  // observable (Klug footnote 4).
  double min_radius_m = 1e-3;

  // Constellation of consecutive joint axes (Eq. 40, 47). Parallel only when
  // the angle is at round-off level (an RTS's axes are perpendicular; a
  // looser value would make the DH frames inexact). Axes closer than 1 mm are
  // "intersecting": this only picks the sign of x_{i+1} in Eq. 47 (the cross
  // product instead of the noise-dominated common-normal direction); a_i then
  // carries the small signed offset, so the model stays exact.
  LineTolerances axis_tolerances{1e-9, 1e-3};

  // Camera tool (Eq. 62-73). true: the camera-frame points are the exact
  // back-projections d * ray(u) of the known intrinsics and distortion (exact
  // for any camera). false: the paper's Eq. 69/70 unit axes, which assume
  // that the ray through c + [1, 0] at length d ends at d * [1/f, 0, 1]; with
  // length d it ends d (1 - 1/(2 f^2)) along z, which tilts the normalised
  // axis of Eq. 69 by ~1/(2 f) rad (5e-4 rad at f = 1000 px).
  bool exact_camera_rays = true;

  // Set labels used as a hint when several sweeps qualify (SPEC 3 `set`).
  std::string joint1_set_hint = "sweep1";
  std::string joint2_set_hint = "sweep2";

  std::string Check() const;  // empty if valid
};

}  // namespace rtscalib

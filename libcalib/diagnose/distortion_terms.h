// Fitted distortion coefficients the data do not determine, and the config
// line that drops them (holds them at zero) next to the diagnosis's effects
// to add (docs/diagnostics.md, "Distortion coefficients to drop").
//
// The covariance of the fit's free parameters is the inverse of the normal
// matrix of the linearisation's base columns (already whitened by the fit's
// a-posteriori sigmas): C = (J^T J)^-1. For each fitted coefficient k of a
// zoom (value v, sigma s = sqrt(C_kk)):
//   corner_px  = s * max over the four image corners of |d pixel / d k|: how
//                far the coefficient's uncertainty alone moves the image's
//                corners (the distortion is extrapolated where no point was);
//   data_px    = the same at the edge of the data: along the diagonals at
//                the farthest observed point's distance from the principal
//                point (Coverage::corner_fraction, `reach`);
//   rho        = the largest |C_kl| / (s_k s_l) over the other fitted
//                coefficients l of the same zoom.
//   corner_value_px = |v| * the same derivative: how far the coefficient's
//                value moves the corners.
// Rule: k is suggested for dropping when it is not distinguishable from the
// held value 0, |v| < 2 s (so that dropping it costs nothing significant),
// AND it is badly determined where the data are: data_px > the fit's pixel
// sigma, or |rho| > 0.99. The advice states its size there, and where the
// data end, never at image corners that no photo reached. A coefficient whose sigma or value moves the corners by more
// than the image's size is never suggested for dropping: the fit went wild
// there (`wild`), which wild_fit.h reports with its likely cause (a missing
// effect the coefficient tries to absorb, or a coefficient the data cannot
// determine), not as a coefficient to drop. Per zoom and group at most one coefficient is suggested:
// the one of the highest power of the radius (k3 before k2 before k1: data
// without the image corners cannot tell r^4 from r^6, and the series is
// truncated from the top), then the smallest |v| / s. Drop one at a time and
// refit, as when adding effects.
#pragma once

#include <string>
#include <vector>

#include "libcalib/diagnose/linearization.h"
#include "libcalib/model/effects.h"
#include "libcalib/model/instrument.h"

namespace rtscalib {

struct DistortionTermRules {
  double max_t = 2.0;              // |v| / s below this: not distinguishable from 0
  double max_corner_sigmas = 1.0;  // corner_px above this many pixel sigmas: badly determined
  double max_rho = 0.99;           // |correlation| above this with a coefficient of the same zoom
};

// One fitted coefficient and what the data say about it.
struct DistortionTerm {
  int zoom = 0;
  int index = 0;     // DistortionIndex
  std::string name;  // "k3"
  Effect group = Effect::kRadialDistortion;
  double value = 0, sigma = 0;
  double corner_px = 0;     // sigma's effect at the farthest image corner [px]
  double corner_value_px = 0;  // the value's effect there [px]
  double data_px = 0;          // sigma's effect at the edge of the data [px]
  double reach = 1;            // the data's farthest point / half-diagonal (1: unknown)
  bool wild = false;        // corner_px or corner_value_px beyond the image's size
  double rho = 0;           // largest |correlation| with another fitted coefficient of the zoom
  std::string partner;      // that coefficient's name ("" when there is none)
  bool drop = false;        // the rule above holds and it is the zoom's and group's weakest
  std::string reason;       // why, in words (drop only)
  std::string config_line;  // the group's config line with it dropped (drop only)
};

struct DistortionTerms {
  std::vector<DistortionTerm> terms;  // every fitted distortion coefficient, by zoom and index
  double pixel_sigma = 0;             // the fit's pixel sigma used by the rule [px]
  // The terms with drop == true.
  std::vector<const DistortionTerm*> Drops() const;
};

// `lin` must be the linearisation of `model` (base columns = the fit's free
// parameters). Empty when no distortion coefficient was fitted or the normal
// matrix is singular.
// `reach`: per zoom, the farthest observed point from the principal point
// over the half-diagonal (Coverage::corner_fraction; missing zooms: 1).
DistortionTerms AssessDistortionTerms(const Linearization& lin, const InstrumentModel& model,
                                      const std::vector<double>& reach = {},
                                      const DistortionTermRules& rules = {});

// The config line that fits, per zoom, the coefficients of `group` that
// `model` fits, minus `drop_index` at zoom `drop_zoom`:
//   model.radial_distortion: {coefficients: [k1, k2]}
//   model.radial_distortion: {coefficients: [k1, k2, k3], zooms: {1: [k1, k2]}}
// (the list most zooms share is `coefficients`; the others are in `zooms`).
std::string DistortionConfigLine(const InstrumentModel& model, Effect group, int drop_zoom,
                                 int drop_index);

}  // namespace rtscalib

// Structure outside the catalogue: harmonics of reading errors.
//
// A probe (linearization.h) is the error of one reading as a harmonic of one
// variable on one face:
//   phi* = phi + A sin(k phi - p)        "k times per turn in phi"   (horizontal encoder, k >= 2
//   not in the catalogue) theta* = theta + A sin(k theta - p)  "k times per turn in theta"
//   (vertical encoder) theta* = theta + A sin(k phi - p)    zenith error periodic in phi (axis
//   tilt; k = 1 is the base tilt) d* = d + A sin(2 pi k d / U - p)     distance error periodic in d
//   (k = 1 is edm_cyclic)
// for k = 1..4 and each face with data. Residuals projected onto a probe's
// columns are the residuals' harmonic content in that reading, measured in
// the reading's own units (arcsec, mm), with whatever the fitted model can
// absorb already taken out.
//
// The tests are AnalyseProbes' (probes.h: against the fitted model alone,
// then on top of the whole catalogue, then what explains them); this file
// reports the harmonic probes among them: joint amplitude and phase, never
// under an effect's name.
#pragma once

#include <set>
#include <string>
#include <vector>

#include "libcalib/diagnose/linearization.h"
#include "libcalib/diagnose/probes.h"
#include "libcalib/diagnose/ranking.h"

namespace rtscalib {

struct Harmonic {
  Probe probe;
  double amplitude = 0;  // arcsec (phi, theta readings) or mm (distance)
  double amplitude_sigma = 0;
  double phase_deg = 0;  // error = amplitude * sin(k x - phase), in [0, 360)
  std::string unit;
  double wald = 0, p_value = 1;
  bool significant = false;
  // The relative fall of the fit's rms if it were modelled (RelativeGain),
  // and whether that is worth a sentence (Materiality).
  double gain = 0;
  bool material = false;
  std::string explained_by;  // catalogue effect that removes it; "" if none does
  std::string description;   // "twice per turn in phi: phi reading error 3.1 arcsec (face 1)"
  std::string block;         // the probe's column block name
};

struct HarmonicAnalysis {
  std::vector<Harmonic> before_catalogue;  // significant against the fitted model alone
  std::vector<Harmonic> unexplained;       // significant on top of the whole catalogue, material
  std::vector<Harmonic> negligible;        // significant on top of the catalogue, within the scatter
  double level = 0;                        // per-test level
  int tests = 0;
};

// Probes for the faces present: the four families above, k = 1..max_harmonic.
std::vector<Probe> DefaultProbes(const std::set<int>& faces, bool has_edm, int max_harmonic = 4);

// The harmonic probes of `probes` (AnalyseProbes over `lin`).
HarmonicAnalysis AnalyseHarmonics(const Linearization& lin, const ProbeAnalysis& probes,
                                  const Materiality& scale);

// "twice per turn in phi", "harmonic 2 of the EDM unit length (period 0.75 m)".
std::string HarmonicName(const Probe& p, double unit_length_m);

}  // namespace rtscalib

#include "libcalib/diagnose/harmonics.h"
#include "libcalib/diagnose/ranking.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace rtscalib {
namespace {

constexpr double kArcsecPerRad = 180.0 * 3600.0 / M_PI;

// `t` gives the amplitude, phase and test; `added` the gain (for a
// selected probe, what it adds where the selection took it).
Harmonic MakeHarmonic(const ColumnBlock& block, const ColumnTest& t, const ColumnTest& added,
                      double level, double unit_length, const Linearization& lin,
                      const Materiality& material) {
  Harmonic h;
  h.gain = RelativeGain(material.current, RmsLess(lin, material.current, added.fitted));
  h.material = material.Material(h.gain);
  h.probe = block.probe;
  h.block = block.name;
  const bool distance = block.probe.reading == Reading::kDistance;
  const double scale = distance ? 1e3 : kArcsecPerRad;
  h.unit = distance ? "mm" : "arcsec";
  // The residual (model - observed) regressed on d r / d reading gives minus
  // the reading error.
  const double a = t.beta.size() > 0 ? -t.beta[0] : 0.0;  // cos
  const double b = t.beta.size() > 1 ? -t.beta[1] : 0.0;  // sin
  const double amp = std::hypot(a, b);
  h.amplitude = amp * scale;
  // a cos(kx) + b sin(kx) = A sin(kx - p) with b = A cos p, a = -A sin p.
  double phase = std::atan2(-a, b) * 180.0 / M_PI;
  if (phase < 0) phase += 360.0;
  h.phase_deg = phase;
  if (amp > 0 && t.cov.rows() == 2) {
    const Eigen::Vector2d j(a / amp, b / amp);
    h.amplitude_sigma = std::sqrt(std::max(j.dot(t.cov * j), 0.0)) * scale;
  }
  h.wald = t.wald;
  h.p_value = t.p_value;
  const double floor = h.unit == "mm" ? kDistanceFloorMm : kAngleFloorArcsec;
  h.significant = t.rank > 0 && t.p_value < level && h.amplitude > floor;
  char buf[160];
  const char* what = block.probe.reading == Reading::kPhi     ? "phi (horizontal angle) error"
                     : block.probe.reading == Reading::kTheta ? "theta (vertical angle) error"
                                                              : "distance error";
  std::snprintf(buf, sizeof(buf), ": %s %.3g %s (+- %.2g), phase %.0f deg, face %d", what,
                h.amplitude, h.unit.c_str(), h.amplitude_sigma, h.phase_deg, block.probe.face);
  h.description = HarmonicName(block.probe, unit_length) + buf;
  return h;
}

}  // namespace

std::string HarmonicName(const Probe& p, double unit_length_m) {
  static const char* kTimes[] = {"", "once", "twice", "three times", "four times"};
  char buf[128];
  if (p.variable == Reading::kDistance) {
    std::snprintf(buf, sizeof(buf), "harmonic %d of the EDM unit length U = %.3g m (period %.3g m)",
                  p.harmonic, unit_length_m, unit_length_m / p.harmonic);
    return buf;
  }
  const std::string times = p.harmonic >= 1 && p.harmonic <= 4
                                ? kTimes[p.harmonic]
                                : std::to_string(p.harmonic) + " times";
  return times + " per turn in " + ReadingName(p.variable);
}

std::vector<Probe> DefaultProbes(const std::set<int>& faces, bool has_edm, int max_harmonic) {
  std::vector<Probe> out;
  for (int face : faces) {
    for (int k = 1; k <= max_harmonic; ++k) {
      auto add = [&](Reading reading, Reading variable) {
        Probe p;
        p.kind = ProbeKind::kHarmonic;
        p.reading = reading;
        p.variable = variable;
        p.harmonic = k;
        p.face = face;
        out.push_back(p);
      };
      add(Reading::kPhi, Reading::kPhi);
      add(Reading::kTheta, Reading::kTheta);
      add(Reading::kTheta, Reading::kPhi);
      if (has_edm) add(Reading::kDistance, Reading::kDistance);
    }
  }
  return out;
}

HarmonicAnalysis AnalyseHarmonics(const Linearization& lin, const ProbeAnalysis& probes,
                                  const Materiality& scale) {
  HarmonicAnalysis out;
  out.level = probes.level;
  out.tests = probes.tests;
  for (int s : probes.selected) {
    const ProbeResult& r = probes.probes[s];
    if (r.block->probe.kind != ProbeKind::kHarmonic) continue;
    Harmonic h = MakeHarmonic(*r.block, r.joint, r.at_selection, out.level,
                              lin.edm_cyclic_unit_length, lin, scale);
    // Below the resolution floor a statistically significant term is
    // round-off of exact data, not structure; within the scatter it is real
    // but buys nothing.
    if (h.significant) (h.material ? out.unexplained : out.negligible).push_back(h);
  }
  for (const ProbeResult& r : probes.probes) {
    if (r.block->probe.kind != ProbeKind::kHarmonic || !r.raw_significant) continue;
    Harmonic h =
        MakeHarmonic(*r.block, r.raw, r.raw, out.level, lin.edm_cyclic_unit_length, lin, scale);
    h.explained_by = r.explained_by;
    out.before_catalogue.push_back(h);
  }
  return out;
}

}  // namespace rtscalib

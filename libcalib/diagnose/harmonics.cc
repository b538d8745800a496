#include "libcalib/diagnose/harmonics.h"
#include "libcalib/diagnose/ranking.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace rtscalib {
namespace {

constexpr double kArcsecPerRad = 180.0 * 3600.0 / M_PI;

Eigen::MatrixXd Columns(const Eigen::MatrixXd& m, const ColumnBlock& b) {
  return m.middleCols(b.first, b.size);
}

Harmonic MakeHarmonic(const ColumnBlock& block, const ColumnTest& t, double level,
                      double unit_length) {
  Harmonic h;
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
      out.push_back({Reading::kPhi, Reading::kPhi, k, face});
      out.push_back({Reading::kTheta, Reading::kTheta, k, face});
      out.push_back({Reading::kTheta, Reading::kPhi, k, face});
      if (has_edm) out.push_back({Reading::kDistance, Reading::kDistance, k, face});
    }
  }
  return out;
}

HarmonicAnalysis AnalyseHarmonics(const Linearization& lin, const Reduced& red,
                                  const std::vector<const ColumnBlock*>& catalogue,
                                  double significance, int max_terms) {
  HarmonicAnalysis out;
  std::vector<const ColumnBlock*> probes;
  for (const ColumnBlock& b : lin.blocks) {
    if (b.is_probe) probes.push_back(&b);
  }
  out.tests = static_cast<int>(probes.size());
  if (probes.empty()) return out;
  out.level = significance / out.tests;
  const int n = lin.NumRows();
  const int g = lin.num_clusters;
  const int dof_base = red.base.rank();

  // 1. Against the fitted model alone.
  std::vector<int> raw_significant;
  for (size_t j = 0; j < probes.size(); ++j) {
    const ColumnTest t =
        TestColumns(red.r, Columns(red.extra, *probes[j]), red.cluster, g, dof_base);
    if (t.rank > 0 && t.p_value < out.level) raw_significant.push_back(static_cast<int>(j));
  }

  // 2. On top of every catalogue effect the data see.
  Projector cat(n);
  {
    int cols = 0;
    for (const ColumnBlock* b : catalogue) cols += b->size;
    Eigen::MatrixXd c(n, cols);
    int k = 0;
    for (const ColumnBlock* b : catalogue) {
      c.middleCols(k, b->size) = Columns(red.extra, *b);
      k += b->size;
    }
    cat.Add(c);
  }
  const Eigen::VectorXd y = cat.Apply(red.r);
  std::vector<Eigen::MatrixXd> t_cat(probes.size());
  for (size_t j = 0; j < probes.size(); ++j) t_cat[j] = cat.Apply(Columns(red.extra, *probes[j]));
  std::vector<int> selected;
  Projector sel(n);
  for (int iter = 0; iter < max_terms; ++iter) {
    const Eigen::VectorXd ys = sel.Apply(y);
    int best = -1;
    double best_p = 1.0, best_wald = 0.0;
    for (size_t j = 0; j < probes.size(); ++j) {
      if (std::find(selected.begin(), selected.end(), static_cast<int>(j)) != selected.end())
        continue;
      const ColumnTest t =
          TestColumns(ys, sel.Apply(t_cat[j]), red.cluster, g, dof_base + cat.rank() + sel.rank());
      if (t.rank == 0) continue;
      if (t.p_value < best_p || (t.p_value == best_p && t.wald > best_wald)) {
        best = static_cast<int>(j);
        best_p = t.p_value;
        best_wald = t.wald;
      }
    }
    if (best < 0 || best_p >= out.level) break;
    selected.push_back(best);
    sel.Add(t_cat[best]);
  }
  // Joint amplitudes of the selected probes.
  for (int s : selected) {
    Projector others(n);
    for (int o : selected) {
      if (o != s) others.Add(t_cat[o]);
    }
    const ColumnTest t = TestColumns(others.Apply(y), others.Apply(t_cat[s]), red.cluster, g,
                                     dof_base + cat.rank() + others.rank());
    Harmonic h = MakeHarmonic(*probes[s], t, out.level, lin.edm_cyclic_unit_length);
    // Below the resolution floor a statistically significant term is
    // round-off of exact data, not structure.
    if (h.significant) out.unexplained.push_back(h);
  }

  // 3. What the catalogue explains.
  for (int j : raw_significant) {
    const ColumnTest raw =
        TestColumns(red.r, Columns(red.extra, *probes[j]), red.cluster, g, dof_base);
    Harmonic h = MakeHarmonic(*probes[j], raw, out.level, lin.edm_cyclic_unit_length);
    const bool unexplained = std::find(selected.begin(), selected.end(), j) != selected.end();
    if (!unexplained) {
      double best = std::numeric_limits<double>::infinity();
      for (const ColumnBlock* b : catalogue) {
        Projector pb(n);
        pb.Add(Columns(red.extra, *b));
        const ColumnTest t = TestColumns(pb.Apply(red.r), pb.Apply(Columns(red.extra, *probes[j])),
                                         red.cluster, g, dof_base + pb.rank());
        if (t.wald < best) {
          best = t.wald;
          h.explained_by = b->name;
        }
      }
    }
    out.before_catalogue.push_back(h);
  }
  return out;
}

}  // namespace rtscalib

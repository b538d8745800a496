#include "libcalib/diagnose/diagnose.h"

#include <algorithm>
#include <chrono>
#include <map>
#include <optional>
#include <set>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "libcalib/fit/unknowns.h"
#include "libcalib/text/number_text.h"

namespace rtscalib {
namespace {

// Below this fraction of its norm outside the model's span, a column is
// absorbed by the model (RankingOptions::redundant_fraction).
constexpr double kRedundantFraction = 1e-3;

std::string Rms(const GroupRms& g) {
  std::vector<std::string> parts;
  if (g.edm_n > 0) parts.push_back("EDM points " + Fmt("%.3g", g.edm_m * 1e3) + " mm");
  if (g.cam_n > 0) parts.push_back("camera points " + Fmt("%.3g", g.cam_m * 1e3) + " mm");
  if (g.pixels_n > 0) parts.push_back("image points " + Fmt("%.3g", g.pixels_px) + " px");
  std::string out;
  for (size_t i = 0; i < parts.size(); ++i) out += (i ? ", " : "") + parts[i];
  return out + " rms";
}

// "EDM points 0.323 -> 0.0908 mm, camera points 0.0326 -> 0.0221 mm rms";
// `format` the number's (a small gain needs "%.4g": 0.08133 -> 0.08121).
std::string Change(const GroupRms& a, const GroupRms& b, const char* format = "%.3g") {
  std::vector<std::string> parts;
  auto part = [&](const char* what, double before, double after, const char* unit) {
    parts.push_back(std::string(what) + " " + Fmt(format, before) + " -> " + Fmt(format, after) +
                    " " + unit);
  };
  if (a.edm_n > 0) part("EDM points", a.edm_m * 1e3, b.edm_m * 1e3, "mm");
  if (a.cam_n > 0) part("camera points", a.cam_m * 1e3, b.cam_m * 1e3, "mm");
  if (a.pixels_n > 0) part("image points", a.pixels_px, b.pixels_px, "px");
  std::string out;
  for (size_t i = 0; i < parts.size(); ++i) out += (i ? ", " : "") + parts[i];
  return out + " rms";
}

// "board 0: wx = 0.0542 +- 0.021 mm wy = ...; board 1: ..." (per zoom for
// focus), or "c = ..., i = ..." for a kinematic effect.
std::string ValueText(const RankedEffect& r) {
  std::string out;
  const std::vector<EstimatePart> parts = EstimateParts(r);
  for (size_t i = 0; i < parts.size(); ++i) {
    const EstimatePart& p = parts[i];
    if (p.where.empty()) {
      out += i ? ", " : "";
    } else {
      if (i == 0 || parts[i - 1].where != p.where) out += (i ? "; " : "") + p.where + ":";
      out += " ";
    }
    out += p.name + " = " + Fmt("%.3g", p.value) + " +- " + Fmt("%.2g", p.sigma) + " " + p.unit;
  }
  return out;
}

// "0.0123 mm" or "0.334 px" for a per-coordinate sigma.
std::string SigmaText(double value, const std::string& unit) {
  return unit == "m" ? Fmt("%.3g", value * 1e3) + " mm" : Fmt("%.3g", value) + " px";
}

// The first sentence when some kind of observation fits worse than its
// a-priori sigma allows: which kinds, at which zoom, by how much (the
// largest factor over the faces; the faces named when not all exceed).
std::string FitQualitySentence(const Diagnosis& d) {
  struct Kind {
    const FitQualityCell* worst = nullptr;
    std::vector<int> faces, exceeding;
  };
  std::vector<std::pair<std::pair<int, int>, Kind>> kinds;  // (group, zoom), in cell order
  for (const FitQualityCell& c : d.fit_quality.cells) {
    const std::pair<int, int> key{static_cast<int>(c.group), c.zoom};
    auto it = std::find_if(kinds.begin(), kinds.end(), [&](const auto& k) { return k.first == key; });
    if (it == kinds.end()) it = kinds.insert(kinds.end(), {key, Kind()});
    Kind& k = it->second;
    k.faces.push_back(c.face);
    if (!c.exceeds) continue;
    k.exceeding.push_back(c.face);
    if (!k.worst || c.factor > k.worst->factor) k.worst = &c;
  }
  std::string cells;
  for (const auto& [key, k] : kinds) {
    if (!k.worst) continue;
    const FitQualityCell& c = *k.worst;
    std::string name = c.name.substr(0, c.name.find(", face"));
    if (k.exceeding.size() < k.faces.size()) {
      name += " in face " + std::to_string(k.exceeding.front());
    }
    cells += std::string(cells.empty() ? "" : "; ") + name + " " + Fmt("%.2g", c.factor) + "x (" +
             SigmaText(c.rms, c.unit) + " rms per coordinate against " +
             SigmaText(c.apriori, c.unit) + ")";
  }
  return "The model (" + d.model_description +
         ") is incomplete or its a-priori sigmas are too small: observations fit worse than "
         "their a-priori sigma (fit.sigmas) allows: " +
         cells + ".";
}

// Whether the residuals say that the model lacks an effect (the likely
// cause of a fit gone wild): some kind of observation fits worse than its
// a-priori sigma allows. Residuals at the noise level mean the parameters
// that went wild are merely undetermined.
bool MissingEffectEvidence(const Diagnosis& d) { return d.fit_quality.Exceeds(); }

std::vector<std::string> Verdict(const Diagnosis& d) {
  std::vector<std::string> v;
  const bool incomplete = d.fit_quality.Exceeds();
  if (incomplete) v.push_back(FitQualitySentence(d));
  const int records = d.current.edm_n + d.current.cam_n;
  v.push_back("The model (" + d.model_description + ") fits " + Rms(d.current) + " over " +
              (records > 0 ? std::to_string(records) + " records and " : std::string()) +
              std::to_string(d.current.pixels_n) + " image points outside the critical regions.");
  if (!d.wild.empty()) {
    std::string list;
    for (size_t i = 0; i < d.wild.size() && i < 4; ++i) {
      const WildParameter& w = d.wild[i];
      list += std::string(i ? "; " : "") + w.name + " = " + w.value + " (" + w.why + ")";
    }
    if (d.wild.size() > 4) list += "; and " + std::to_string(d.wild.size() - 4) + " more";
    bool undetermined = false;
    for (const WildParameter& w : d.wild) undetermined = undetermined || w.undetermined;
    std::string cause;
    if (MissingEffectEvidence(d)) {
      cause = "the model lacks an effect, which these parameters try to absorb (see the fit "
              "against the a-priori sigmas, the effects and the structure below): add what is "
              "missing before reading these values";
    } else if (undetermined) {
      cause = "parameters these data do not determine (no point near where they act, e.g. the "
              "image corners): hold them, or add data that reach there";
    } else {
      cause = "values no instrument has: check the start values and the data's conventions "
              "(angle unit, faces, zoom labels)";
    }
    v.push_back("Warning: the fit went wild: " + list + ". Likely cause: " + cause + ".");
  }
  std::vector<const RankedEffect*> recommended, detectable;
  for (const RankedEffect& r : d.ranking.entries) {
    if (r.recommended) {
      recommended.push_back(&r);
    } else if (r.significant && !r.redundant) {
      detectable.push_back(&r);
    }
  }
  const std::string level = Fmt("%g", 100 * d.ranking.level * d.ranking.tested);
  const std::string min_gain = Fmt("%g", 100 * d.min_gain);
  if (recommended.empty()) {
    if (incomplete) {
      v.push_back("None of the " + std::to_string(d.ranking.tested) +
                  " catalogue effects tested is both significant at the " + level +
                  "% level and worth " + min_gain +
                  " % of the rms: what the model lacks is outside the catalogue (see the "
                  "structure below), or the a-priori sigmas are too small.");
    } else {
      v.push_back("No catalogue effect is missing: none of the " +
                  std::to_string(d.ranking.tested) + " effects tested is both significant at the " +
                  level + "% level and worth " + min_gain + " % of the rms.");
    }
  } else {
    const RankedEffect& r = *recommended.front();
    std::string s = "Add " + r.name + " next: " + Change(r.before, r.after) +
                    (r.after_source == "refined" ? " (refitted with it" : " (predicted to first order") +
                    ", delta BIC " + Fmt("%.0f", r.delta_bic) + ")";
    const std::string value = ValueText(r);
    if (!value.empty()) s += "; " + value;
    s += ". Config: " + r.config_line;
    if (!r.identifiable) s += " (note: " + r.note + ")";
    v.push_back(s);
    if (!d.ranking.also_after_best.empty()) {
      std::string also = "Still significant and worth adding once " + r.name + " is in:";
      for (size_t i = 0; i < d.ranking.also_after_best.size(); ++i) {
        also += (i ? ", " : " ") + d.ranking.also_after_best[i];
      }
      v.push_back(also + " (add one at a time; `rtscalib diagnose --auto` does it).");
    } else if (recommended.size() > 1) {
      std::string also;
      for (size_t i = 1; i < recommended.size(); ++i)
        also += (i > 1 ? ", " : "") + recommended[i]->name;
      v.push_back(d.ranking.after_best_tested
                      ? "Also worth adding alone, but not once " + r.name + " is in: " + also + "."
                      : "Also worth adding alone: " + also + "; diagnose again once " + r.name +
                            " is in (`rtscalib diagnose --auto` does it).");
    }
  }
  if (!detectable.empty()) {
    std::string list;
    for (size_t i = 0; i < detectable.size(); ++i) {
      const RankedEffect& r = *detectable[i];
      list += std::string(i ? "; " : "") + r.name + " (" + Change(r.before, r.after, "%.4g") + ", " +
              Fmt("%.2g", 100 * r.gain) + " %" +
              (r.after_source == "refined" ? ", refitted" : "") + ")";
    }
    v.push_back("Statistically detectable but not worth adding (less than " + min_gain +
                " % of the rms): " + list + ".");
  }
  for (const DistortionTerm* t : d.distortion_terms.Drops()) {
    v.push_back("Drop " + t->name + " of zoom " + std::to_string(t->zoom) +
                " (hold it at 0): " + t->reason + ". Config: " + t->config_line);
  }
  // Structure is found on top of the catalogue to first order; beside an
  // effect worth adding (which moves the model more than a first-order step
  // may describe) it is to be confirmed once that effect is in.
  const std::string outside =
      recommended.empty()
          ? "Structure outside the catalogue: "
          : "Structure outside the catalogue (to first order; check again once " +
                recommended.front()->name + " is in): ";
  for (const Harmonic& h : d.harmonics.unexplained) v.push_back(outside + h.description + ".");
  for (const StructureFinding& f : d.structure.unexplained) {
    v.push_back(outside + f.description +
                (f.points_to.empty() ? "" : "; points to " + f.points_to) + ".");
  }
  // Structure a catalogue effect explains, for the few most significant
  // that matter (what the surveyor would see in the residuals without that
  // effect). It supports the ranking, never contradicts it: said only of an
  // effect the verdict recommends (one that is not recommended does not pay
  // its way in these data, whatever a probe of similar shape finds), and of
  // a field over the image only when a distortion group explains it (what
  // another effect takes of a field is a side effect, not its signature).
  // One sentence per effect and zoom: the most significant of the probes
  // that show the same structure (1/D and D, target and focus distance).
  std::set<std::pair<std::string, int>> said;
  for (const StructureFinding& f : d.structure.explained) {
    if (said.size() >= 3) break;
    if (f.explained_by.empty() || !f.material) continue;
    if (said.count({f.explained_by, f.probe.zoom})) continue;
    const std::optional<Effect> by = EffectFromName(f.explained_by);
    if (f.probe.kind == ProbeKind::kImageField && !(by && IsDistortion(*by))) continue;
    const auto e = std::find_if(recommended.begin(), recommended.end(),
                                [&](const RankedEffect* r) { return r->name == f.explained_by; });
    if (e == recommended.end()) continue;
    v.push_back("Structure against " + f.variable + " (" + f.description + ") is what " +
                f.explained_by + " explains" +
                (e == recommended.begin() ? "" : " (also worth adding, see the ranking)") + ".");
    said.insert({f.explained_by, f.probe.zoom});
  }
  if (d.outliers.flagged > 0) {
    v.push_back(std::to_string(d.outliers.flagged) + " of " + std::to_string(d.outliers.tested) +
                " observations fail the w-test (w > " + Fmt("%.2f", d.outliers.critical_w) +
                "); the worst is " + d.outliers.worst.front().where +
                " (w = " + Fmt("%.1f", d.outliers.worst.front().w) + ").");
  }
  return v;
}

}  // namespace

std::string DiagnosisSettings::Check() const {
  if (!(significance > 0 && significance < 1)) return "diagnose.significance must be in (0, 1)";
  if (refine_top < 0) return "diagnose: refine_top must be >= 0";
  if (!(min_gain >= 0 && min_gain < 1)) return "diagnose: min_gain must be in [0, 1)";
  if (max_harmonic < 1 || max_harmonic > 12) return "diagnose: max_harmonic must be in 1..12";
  if (max_unexplained < 0) return "diagnose: max_unexplained must be >= 0";
  return "";
}

FitContext ContextOf(const FitOptions& used, const FitSummary& summary) {
  FitContext c;
  c.options = used;
  c.sigma[0] = summary.sigma_edm_m > 0 ? summary.sigma_edm_m : used.sigma_edm_m;
  c.sigma[1] = summary.sigma_cam_m > 0 ? summary.sigma_cam_m : used.sigma_cam_m;
  c.sigma[2] = summary.sigma_pixel_px > 0 ? summary.sigma_pixel_px : used.sigma_pixel_px;
  return c;
}

const RankedEffect* Diagnosis::Next() const {
  for (const RankedEffect& r : ranking.entries) {
    if (r.recommended) return &r;
  }
  return nullptr;
}

Diagnosis Diagnose(const Observations& obs, const InstrumentModel& model, const FitContext& fit,
                   const DiagnosisSettings& settings) {
  const std::string msg = settings.Check();
  if (!msg.empty()) throw std::invalid_argument(msg);
  const auto t0 = std::chrono::steady_clock::now();
  Diagnosis d;
  d.kinematics = model.kinematics;
  d.effects = model.effects.Names();
  d.model_description = (model.kinematics == Kinematics::kNone
                             ? std::string("camera only")
                             : std::string(KinematicsName(model.kinematics))) +
                        ", effects: [";
  for (size_t i = 0; i < d.effects.size(); ++i)
    d.model_description += (i ? ", " : "") + d.effects[i];
  d.model_description += "]";
  for (int g = 0; g < 3; ++g) d.sigma[g] = fit.sigma[g];
  d.min_gain = settings.min_gain;
  // Every point's position (the estimated boards' corners where the pixels
  // leave them empty) for what needs it; the linearisation and the refits
  // see `obs` as the fit did, the boards' poses free.
  const Observations known = WithEstimates(obs, model);
  d.coverage = MeasureCoverage(known, model, fit.options);

  // A camera-only model (SPEC 7.1) has no axes and no EDM: only the camera's
  // own effects are candidates, and there is no phi or theta to find
  // structure in.
  const bool camera_only = model.kinematics == Kinematics::kNone;
  std::vector<Effect> candidates, contained;
  for (const EffectInfo& info : EffectCatalogue()) {
    if (model.effects.Has(info.effect)) continue;
    if (camera_only && IsKinematic(info.effect)) continue;
    if (std::find(settings.untested.begin(), settings.untested.end(), info.effect) !=
        settings.untested.end()) {
      continue;
    }
    if (ContainedInKinematics(model.kinematics, info.effect)) {
      contained.push_back(info.effect);
    } else {
      candidates.push_back(info.effect);
    }
  }
  LinearizeOptions lo;
  lo.fit = fit.options;
  for (int g = 0; g < 3; ++g) lo.sigma[g] = fit.sigma[g];
  lo.candidates = candidates;
  const bool harmonics = settings.harmonics && !camera_only;
  if (harmonics)
    lo.probes = DefaultProbes(d.coverage.faces, d.coverage.has_edm, settings.max_harmonic);
  if (settings.structure) {
    lo.variables = SessionVariables(known, model);
    for (const Probe& p : StructureProbes(lo.variables, known, model, !camera_only)) {
      lo.probes.push_back(p);
    }
  }
  const Linearization lin = Linearize(obs, model, lo);
  const Reduced red = Reduce(lin);
  d.num_rows = lin.NumRows();
  d.num_parameters = red.Rank();
  d.excluded_critical = lin.excluded_critical;
  d.fit_quality =
      AssessFitQuality(lin, known, fit.options, d.num_parameters, settings.significance);

  std::vector<const ColumnBlock*> catalogue;
  for (const ColumnBlock& b : lin.blocks) {
    if (!b.is_effect) continue;
    double kept = 0;
    for (int j = b.first; j < b.first + b.size; ++j) kept = std::max(kept, red.kept_fraction[j]);
    if (kept >= kRedundantFraction) catalogue.push_back(&b);
  }
  Materiality scale;
  scale.current = RmsOfWhitened(lin, lin.r);
  scale.min_gain = settings.min_gain;
  scale.reach = d.coverage.corner_fraction;
  Projector nuisance(lin.NumRows());
  if (!lo.probes.empty()) {
    const ProbeAnalysis probes =
        AnalyseProbes(lin, red, catalogue, settings.significance, settings.max_unexplained);
    d.harmonics = AnalyseHarmonics(lin, probes, scale);
    d.structure = AnalyseStructure(lin, red, probes, model, scale);
    // Structure outside the catalogue is a nuisance for the ranking: an
    // effect is credited only with what it explains beyond it.
    for (const Harmonic& h : d.harmonics.unexplained) {
      if (const ColumnBlock* b = lin.Find(h.block))
        nuisance.Add(red.extra.middleCols(b->first, b->size));
    }
    for (const StructureFinding& f : d.structure.unexplained) {
      if (const ColumnBlock* b = lin.Find(f.block))
        nuisance.Add(red.extra.middleCols(b->first, b->size));
    }
  }
  if (model.kinematics == Kinematics::kDh && !contained.empty()) {
    d.equivalents = EquivalentSurveyingTerms(model, fit.options);
  }

  RankingInput in;
  in.obs = &obs;
  in.model = &model;
  in.fit = fit.options;
  in.lin = &lin;
  in.red = &red;
  in.nuisance = &nuisance;
  in.coverage = &d.coverage;
  in.equivalents = &d.equivalents;
  in.contained = contained;
  RankingOptions ro;
  ro.significance = settings.significance;
  ro.redundant_fraction = kRedundantFraction;
  ro.refine_top = settings.refine_top;
  ro.min_gain = settings.min_gain;
  d.ranking = RankEffects(in, ro);
  d.current = d.ranking.current;

  d.distortion_terms = AssessDistortionTerms(lin, model, d.coverage.corner_fraction);
  {
    // The nearest target of each zoom (photos' D, camera records' d).
    std::map<int, double> nearest;
    for (const SessionVariable& v : lin.variables) {
      if (v.name != "target distance") continue;
      auto keep = [&](int zoom, double x) {
        if (!(x > 0)) return;
        auto [it, fresh] = nearest.emplace(zoom, x);
        if (!fresh) it->second = std::min(it->second, x);
      };
      for (size_t i = 0; i < known.pixels.size(); ++i) keep(known.pixels[i].zoom, v.pixel[i]);
      for (size_t i = 0; i < known.records.size(); ++i) {
        if (known.records[i].tool == Tool::kCam) keep(known.records[i].zoom, v.record[i]);
      }
    }
    d.wild = FindWildParameters(lin, model, d.distortion_terms, nearest);
  }
  if (settings.outliers) {
    d.outliers = TestOutliers(known, lin, red, ObservationResiduals(known, model, fit.options),
                              settings.significance, settings.outliers_listed);
  }
  d.verdict = Verdict(d);
  d.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return d;
}

}  // namespace rtscalib

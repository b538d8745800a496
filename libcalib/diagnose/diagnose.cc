#include "libcalib/diagnose/diagnose.h"

#include <algorithm>
#include <chrono>
#include <map>
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

// "EDM points 0.323 -> 0.0908 mm, camera points 0.0326 -> 0.0221 mm rms"
std::string Change(const GroupRms& a, const GroupRms& b) {
  std::vector<std::string> parts;
  if (a.edm_n > 0)
    parts.push_back("EDM points " + Fmt("%.3g", a.edm_m * 1e3) + " -> " +
                    Fmt("%.3g", b.edm_m * 1e3) + " mm");
  if (a.cam_n > 0)
    parts.push_back("camera points " + Fmt("%.3g", a.cam_m * 1e3) + " -> " +
                    Fmt("%.3g", b.cam_m * 1e3) + " mm");
  if (a.pixels_n > 0)
    parts.push_back("image points " + Fmt("%.3g", a.pixels_px) + " -> " + Fmt("%.3g", b.pixels_px) +
                    " px");
  std::string out;
  for (size_t i = 0; i < parts.size(); ++i) out += (i ? ", " : "") + parts[i];
  return out + " rms";
}

std::string ValueText(const RankedEffect& r) {
  const EffectInfo& info = Info(r.effect);
  if (r.effect == Effect::kFocus) {
    std::string out;
    int zoom = -1;
    for (const FocusValue& f : r.focus) {
      if (f.zoom != zoom) {
        out += std::string(out.empty() ? "" : "; ") + "zoom " + std::to_string(f.zoom) + ":";
        zoom = f.zoom;
      }
      out += " " + f.name + " = " + Fmt("%.3g", f.value * kFocusReportScale[f.index]) + " +- " +
             Fmt("%.2g", f.sigma * kFocusReportScale[f.index]) + " " + kFocusReportUnits[f.index];
    }
    return out;
  }
  if (IsBoardEffect(r.effect)) {
    std::string out;
    const double scale = ReportScale(r.effect);
    int board = -1;
    for (const WarpValue& w : r.board_warp) {
      if (w.first_id != board) {
        out += std::string(out.empty() ? "" : "; ") + "board " + std::to_string(w.first_id) + ":";
        board = w.first_id;
      }
      out += " " + w.name + " = " + Fmt("%.3g", w.value * scale) + " +- " +
             Fmt("%.2g", w.sigma * scale) + " " + info.report_units[w.index];
    }
    return out;
  }
  if (!IsKinematic(r.effect)) return "";
  std::string out;
  for (int k = 0; k < r.value.num; ++k) {
    out += (k ? ", " : "") + std::string(info.param_names[k]) + " = " +
           Fmt("%.3g", r.value.value[k]) + " +- " + Fmt("%.2g", r.value.sigma[k]) + " " +
           info.report_units[k];
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
  v.push_back("The model (" + d.model_description + ") fits " + Rms(d.current) + " over " +
              std::to_string(d.current.edm_n + d.current.cam_n) + " records and " +
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
  std::vector<const RankedEffect*> significant;
  for (const RankedEffect& r : d.ranking.entries) {
    if (r.significant) significant.push_back(&r);
  }
  if (significant.empty()) {
    if (incomplete) {
      v.push_back("None of the " + std::to_string(d.ranking.tested) +
                  " catalogue effects tested is significant at the " +
                  Fmt("%g", 100 * d.ranking.level * d.ranking.tested) +
                  "% level: what the model lacks is outside the catalogue (see the structure "
                  "below), or the a-priori sigmas are too small.");
    } else {
      v.push_back("No catalogue effect is missing: none of the " +
                  std::to_string(d.ranking.tested) + " effects tested is significant at the " +
                  Fmt("%g", 100 * d.ranking.level * d.ranking.tested) + "% level.");
    }
  } else {
    const RankedEffect& r = *significant.front();
    std::string s = "Add " + r.name + " next: " + Change(r.before, r.after) + " (delta BIC " +
                    Fmt("%.0f", r.delta_bic) + ")";
    const std::string value = ValueText(r);
    if (!value.empty()) s += "; " + value;
    s += ". Config: " + r.config_line;
    if (!r.identifiable) s += " (note: " + r.note + ")";
    v.push_back(s);
    if (!d.ranking.also_after_best.empty()) {
      std::string also = "Still significant once " + r.name + " is in:";
      for (size_t i = 0; i < d.ranking.also_after_best.size(); ++i) {
        also += (i ? ", " : " ") + d.ranking.also_after_best[i];
      }
      v.push_back(also + " (add one at a time; `rtscalib diagnose --auto` does it).");
    } else if (significant.size() > 1) {
      std::string also;
      for (size_t i = 1; i < significant.size(); ++i)
        also += (i > 1 ? ", " : "") + significant[i]->name;
      v.push_back("Also significant alone, but not once " + r.name + " is in: " + also + ".");
    }
  }
  for (const DistortionTerm* t : d.distortion_terms.Drops()) {
    v.push_back("Drop " + t->name + " of zoom " + std::to_string(t->zoom) +
                " (hold it at 0): " + t->reason + ". Config: " + t->config_line);
  }
  for (const Harmonic& h : d.harmonics.unexplained) {
    v.push_back("Structure outside the catalogue: " + h.description + ".");
  }
  for (const StructureFinding& f : d.structure.unexplained) {
    v.push_back("Structure outside the catalogue: " + f.description +
                (f.points_to.empty() ? "" : "; points to " + f.points_to) + ".");
  }
  // Structure a catalogue effect explains, for the few most significant
  // (what the surveyor would see in the residuals without that effect).
  for (size_t i = 0; i < d.structure.explained.size() && i < 3; ++i) {
    const StructureFinding& f = d.structure.explained[i];
    if (f.explained_by.empty()) continue;
    v.push_back("Structure against " + f.variable + " (" + f.description + ") is what " +
                f.explained_by + " explains.");
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
    if (r.significant && !r.redundant) return &r;
  }
  return nullptr;
}

Diagnosis Diagnose(const Observations& obs, const InstrumentModel& model, const FitContext& fit,
                   const DiagnosisSettings& settings) {
  // The linearisation and the refits see the rows as the fit did (boards and
  // points of unknown position free); everything that reads a row's
  // position sees them at the model's estimate.
  const Observations positions = WithEstimates(obs, model);
  const std::string msg = settings.Check();
  if (!msg.empty()) throw std::invalid_argument(msg);
  const auto t0 = std::chrono::steady_clock::now();
  Diagnosis d;
  d.kinematics = model.kinematics;
  d.effects = model.effects.Names();
  d.model_description = std::string(KinematicsName(model.kinematics)) + ", effects: [";
  for (size_t i = 0; i < d.effects.size(); ++i)
    d.model_description += (i ? ", " : "") + d.effects[i];
  d.model_description += "]";
  for (int g = 0; g < 3; ++g) d.sigma[g] = fit.sigma[g];
  d.coverage = MeasureCoverage(positions, model, fit.options);

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
    lo.variables = SessionVariables(positions, model);
    for (const Probe& p : StructureProbes(lo.variables, positions, model, !camera_only)) {
      lo.probes.push_back(p);
    }
  }
  const Linearization lin = Linearize(obs, model, lo);
  const Reduced red = Reduce(lin);
  d.num_rows = lin.NumRows();
  d.num_parameters = red.Rank();
  d.excluded_critical = lin.excluded_critical;
  d.fit_quality =
      AssessFitQuality(lin, positions, fit.options, d.num_parameters, settings.significance);

  std::vector<const ColumnBlock*> catalogue;
  for (const ColumnBlock& b : lin.blocks) {
    if (!b.is_effect) continue;
    double kept = 0;
    for (int j = b.first; j < b.first + b.size; ++j) kept = std::max(kept, red.kept_fraction[j]);
    if (kept >= kRedundantFraction) catalogue.push_back(&b);
  }
  Projector nuisance(lin.NumRows());
  if (!lo.probes.empty()) {
    const ProbeAnalysis probes =
        AnalyseProbes(lin, red, catalogue, settings.significance, settings.max_unexplained);
    d.harmonics = AnalyseHarmonics(lin, probes);
    d.structure = AnalyseStructure(lin, red, probes, model);
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
  d.ranking = RankEffects(in, ro);
  d.current = d.ranking.current;

  d.distortion_terms = AssessDistortionTerms(lin, model);
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
      for (size_t i = 0; i < obs.pixels.size(); ++i) keep(obs.pixels[i].zoom, v.pixel[i]);
      for (size_t i = 0; i < obs.records.size(); ++i) {
        if (obs.records[i].tool == Tool::kCam) keep(obs.records[i].zoom, v.record[i]);
      }
    }
    d.wild = FindWildParameters(lin, model, d.distortion_terms, nearest);
  }
  if (settings.outliers) {
    d.outliers = TestOutliers(positions, lin, red, ObservationResiduals(positions, model, fit.options),
                              settings.significance, settings.outliers_listed);
  }
  d.verdict = Verdict(d);
  d.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return d;
}

}  // namespace rtscalib

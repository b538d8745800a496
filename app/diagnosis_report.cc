#include "app/diagnosis_report.h"

#include <cmath>
#include <cstdio>
#include <iomanip>
#include <sstream>

#include "libcalib/text/number_text.h"

namespace rtscalib::app {
namespace {

using nlohmann::json;

json GroupJson(const GroupRms& g) {
  json j = json::object();
  if (g.edm_n > 0) j["edm"] = {{"rms_m", g.edm_m}, {"n", g.edm_n}};
  if (g.cam_n > 0) j["cam"] = {{"rms_m", g.cam_m}, {"n", g.cam_n}};
  if (g.edm_n + g.cam_n > 0) j["records"] = {{"rms_m", g.records_m}, {"n", g.edm_n + g.cam_n}};
  if (g.pixels_n > 0) j["pixels"] = {{"rms_px", g.pixels_px}, {"n", g.pixels_n}};
  return j;
}

json ValueJson(Effect e, const EffectReportValue& v) {
  const EffectInfo& info = Info(e);
  json j = json::object();
  for (int k = 0; k < v.num; ++k) {
    j[info.param_names[k]] = {
        {"value", v.value[k]}, {"sigma", v.sigma[k]}, {"unit", info.report_units[k]}};
  }
  return j;
}

json RankedJson(const RankedEffect& r) {
  json j = {{"effect", r.name},
            {"rms_before", r.rms_before},
            {"rms_after", r.rms_after},
            {"rms_unit", r.rms_unit},
            {"delta_bic", r.delta_bic},
            {"significant", r.significant},
            {"gain", r.gain},
            {"worth_adding", r.worthwhile},
            {"recommended", r.recommended},
            {"identifiable", r.identifiable},
            {"redundant", r.redundant},
            {"observable", r.observable},
            {"config_line", r.config_line},
            {"p_value", r.p_value},
            {"wald", r.wald},
            {"num_params", r.num_params},
            {"groups", {{"before", GroupJson(r.before)}, {"after", GroupJson(r.after)}}},
            {"after_from", r.after_source},
            {"refitted", r.after_source == "refined"},
            {"rms_after_linear", r.linear_after.Main()},
            {"needs", r.needs},
            {"aliases", r.aliases},
            {"note", r.note}};
  if (IsKinematic(r.effect) && !r.redundant && r.observable)
    j["value"] = ValueJson(r.effect, r.value);
  if (!r.distortion.empty()) {
    json d = json::array();
    for (const DistortionValue& v : r.distortion) {
      d.push_back({{"zoom", v.zoom},
                   {"coefficient", v.coefficient},
                   {"value", v.value},
                   {"sigma", v.sigma}});
    }
    j["value"] = d;
  }
  if (!r.focus.empty()) {
    json d = json::array();
    for (const FocusValue& v : r.focus) {
      d.push_back({{"zoom", v.zoom},
                   {"parameter", v.name},
                   {"value", v.value * kFocusReportScale[v.index]},
                   {"sigma", v.sigma * kFocusReportScale[v.index]},
                   {"unit", kFocusReportUnits[v.index]}});
    }
    j["value"] = d;
  }
  if (r.has_equivalent) j["equivalent"] = ValueJson(r.effect, r.equivalent);
  if (!r.correlated_with.empty())
    j["correlated_with"] = {{"parameter", r.correlated_with}, {"rho", r.rho}};
  return j;
}

json HarmonicJson(const Harmonic& h) {
  return {{"variable", ReadingName(h.probe.variable)},
          {"harmonic", h.probe.harmonic},
          {"amplitude", h.amplitude},
          {"phase", h.phase_deg},
          {"significant", h.significant},
          {"reading", ReadingName(h.probe.reading)},
          {"face", h.probe.face},
          {"unit", h.unit},
          {"phase_unit", "deg"},
          {"amplitude_sigma", h.amplitude_sigma},
          {"p_value", h.p_value},
          {"gain", h.gain},
          {"material", h.material},
          {"explained_by", h.explained_by.empty() ? json() : json(h.explained_by)},
          {"description", h.description}};
}

json FindingJson(const StructureFinding& f) {
  const char* kinds[] = {"harmonic", "reading_trend", "image_motion", "image_field"};
  const bool image = f.probe.kind == ProbeKind::kImageMotion ||
                     f.probe.kind == ProbeKind::kImageField;
  json j = {{"variable", f.variable},
          {"kind", kinds[static_cast<int>(f.probe.kind)]},
          {"quantity", f.quantity},
          {"form", f.form},
          {"size", f.size},
          {"size_at", image ? "observed points" : "variable range"},
          {"unit", f.unit},
          {"range", {f.lo, f.hi}},
          {"zoom", f.probe.zoom >= 0 ? json(f.probe.zoom) : json()},
          {"p_value", f.p_value},
          {"wald", f.wald},
          {"gain", f.gain},
          {"material", f.material},
          {"unexplained", f.unexplained},
          {"explained_by", f.explained_by.empty() ? json() : json(f.explained_by)},
          {"same_as", f.same_as.empty() ? json() : json(f.same_as)},
          {"points_to", f.points_to},
          {"description", f.description}};
  if (image) j["reach"] = f.reach;
  return j;
}

json FitQualityJson(const FitQuality& q) {
  json cells = json::array();
  for (const FitQualityCell& c : q.cells) {
    // EDM cells have no zoom: the key is left out (no null for a number,
    // docs/conventions.md section 6).
    json cell = {{"kind", GroupName(c.group)},
                 {"name", c.name},
                 {"face", c.face},
                 {"observations", c.observations},
                 {"rms", c.rms},
                 {"apriori_sigma", c.apriori},
                 {"unit", c.unit},
                 {"factor", c.factor},
                 {"chi_square", c.chi2},
                 {"dof", c.dof},
                 {"p_value", c.p_value},
                 {"exceeds", c.exceeds}};
    if (c.zoom >= 0) cell["zoom"] = c.zoom;
    cells.push_back(cell);
  }
  return {{"exceeds", q.Exceeds()},
          {"min_factor", kMinFactor},
          {"test_level", q.level},
          {"cells", cells}};
}

json LadderJson(const std::vector<LadderStep>& ladder) {
  json out = json::array();
  for (const LadderStep& s : ladder) {
    out.push_back({{"added", s.added.empty() ? json() : json(s.added)},
                   {"model", s.model_description},
                   {"effects", s.effects},
                   {"errors", GroupJson(s.rms)},
                   {"bic", s.bic},
                   {"parameters", s.num_parameters}});
  }
  return out;
}

}  // namespace

json DiagnosisJson(const CalibrationResult& r) {
  if (!r.diagnosis) return json();
  const Diagnosis& d = *r.diagnosis;
  json ranking = json::array();
  for (const RankedEffect& e : d.ranking.entries) ranking.push_back(RankedJson(e));
  // SPEC 6's one list of what no catalogue effect explains: the harmonics of
  // phi and theta, then the structure against the session's other variables
  // (drifts against the record or photo order, trends against the target
  // distance, fields over the image position). Every entry has SPEC's
  // `variable`, `harmonic` (0 for a finding that is no harmonic), `amplitude`
  // and `significant`, and its `kind`.
  json unexplained = json::array();
  for (const Harmonic& h : d.harmonics.unexplained) {
    json e = HarmonicJson(h);
    e["kind"] = "harmonic";
    unexplained.push_back(e);
  }
  for (const StructureFinding& f : d.structure.unexplained) {
    json e = FindingJson(f);
    e["harmonic"] = f.probe.kind == ProbeKind::kHarmonic ? f.probe.harmonic : 0;
    e["amplitude"] = f.size;
    e["significant"] = true;  // selected on top of the whole catalogue
    unexplained.push_back(e);
  }
  json harmonics = json::array();
  for (const Harmonic& h : d.harmonics.before_catalogue) harmonics.push_back(HarmonicJson(h));
  json worst = json::array();
  for (const OutlierEntry& o : d.outliers.worst) {
    worst.push_back({{"where", o.where},
                     {"group", GroupName(o.group)},
                     {"index", o.index},
                     {"w", o.w},
                     {"p_value", o.p_value},
                     {"flagged", o.flagged},
                     {"size", o.size},
                     {"unit", o.group == ObsGroup::kPixel ? "px" : "m"}});
  }
  json distortion = json::array();
  json drop = json::array();
  for (const DistortionTerm& t : d.distortion_terms.terms) {
    json e = {{"zoom", t.zoom},
              {"coefficient", t.name},
              {"effect", Info(t.group).name},
              {"value", t.value},
              {"sigma", t.sigma},
              {"corner_sigma_px", t.corner_px},
              {"data_sigma_px", t.data_px},
              {"reach", t.reach},
              {"max_abs_correlation", std::fabs(t.rho)},
              {"correlated_with", t.partner},
              {"drop", t.drop}};
    if (t.drop) {
      e["reason"] = t.reason;
      e["config_line"] = t.config_line;
      drop.push_back({{"zoom", t.zoom},
                      {"coefficient", t.name},
                      {"reason", t.reason},
                      {"config_line", t.config_line}});
    }
    distortion.push_back(e);
  }
  json structure_explained = json::array(), structure_negligible = json::array();
  for (const StructureFinding& f : d.structure.negligible) {
    structure_negligible.push_back(FindingJson(f));
  }
  json negligible_harmonics = json::array();
  for (const Harmonic& h : d.harmonics.negligible) negligible_harmonics.push_back(HarmonicJson(h));
  for (const StructureFinding& f : d.structure.explained) {
    structure_explained.push_back(FindingJson(f));
  }
  json wild = json::array();
  for (const WildParameter& w : d.wild) {
    wild.push_back({{"parameter", w.name},
                    {"zoom", w.zoom >= 0 ? json(w.zoom) : json()},
                    {"value", w.value},
                    {"why", w.why},
                    {"undetermined", w.undetermined}});
  }
  const RankedEffect* next = d.Next();
  json j = {{"model", d.model_description},
            {"verdict", d.verdict},
            {"fit_quality", FitQualityJson(d.fit_quality)},
            {"wild", wild},
            {"structure",
             {{"explained", structure_explained},
              {"negligible", structure_negligible}}},
            {"negligible_harmonics", negligible_harmonics},
            {"min_gain", d.min_gain},
            {"next", next ? json(next->name) : json()},
            {"ranking", ranking},
            {"unexplained", unexplained},
            {"distortion_coefficients", distortion},
            {"drop", drop},
            {"harmonics", harmonics},
            {"outliers",
             {{"critical_w", d.outliers.critical_w},
              {"tested", d.outliers.tested},
              {"flagged", d.outliers.flagged},
              {"worst", worst}}},
            {"current", GroupJson(d.current)},
            {"sigmas", {{"edm_m", d.sigma[0]}, {"cam_m", d.sigma[1]}, {"pixel_px", d.sigma[2]}}},
            {"test_level", {{"ranking", d.ranking.level}, {"harmonics", d.harmonics.level}}},
            {"effects_tested", d.ranking.tested},
            {"residual_rows", d.num_rows},
            {"parameters", d.num_parameters},
            {"seconds", d.seconds}};
  if (d.equivalents.valid) j["equivalents_fit_rms_m"] = d.equivalents.fit_rms_m;
  if (!r.ladder.empty()) {
    j["ladder"] = LadderJson(r.ladder);
    j["ladder_stop"] = r.ladder_stop;
  }
  return j;
}

std::string DiagnosisText(const CalibrationResult& r) {
  if (!r.diagnosis) return "";
  const Diagnosis& d = *r.diagnosis;
  std::ostringstream o;
  o << "Diagnosis\n=========\n";
  for (const std::string& v : d.verdict) o << "  " << v << "\n";
  if (!r.ladder.empty()) {
    o << "\nLadder (forward stepwise, " << r.ladder_stop << ")\n";
    o << "  step  added                   EDM rms [mm]  cam rms [mm]  pixels [px]   BIC\n";
    for (size_t i = 0; i < r.ladder.size(); ++i) {
      const LadderStep& s = r.ladder[i];
      o << "  " << std::setw(4) << i << "  " << std::left << std::setw(22)
        << (s.added.empty() ? "(start)" : s.added) << std::right << "  " << std::setw(12)
        << (s.rms.edm_n ? Fmt("%.4f", s.rms.edm_m * 1e3) : "-") << "  " << std::setw(12)
        << (s.rms.cam_n ? Fmt("%.4f", s.rms.cam_m * 1e3) : "-") << "  " << std::setw(11)
        << (s.rms.pixels_n ? Fmt("%.3f", s.rms.pixels_px) : "-") << "  " << Fmt("%.1f", s.bic)
        << "\n";
    }
  }
  if (!d.fit_quality.cells.empty()) {
    o << "\nFit against the a-priori sigmas (factor = rms / a-priori sigma per coordinate; "
         "flagged above "
      << Fmt("%.2g", kMinFactor) << " when the chi-square test fails)\n";
    o << "  observations                          n        rms          a-priori     factor  "
         "flagged\n";
    for (const FitQualityCell& c : d.fit_quality.cells) {
      const double scale = c.unit == "m" ? 1e3 : 1.0;
      const char* unit = c.unit == "m" ? "mm" : "px";
      o << "  " << std::left << std::setw(34) << c.name << std::right << "  " << std::setw(6)
        << c.observations << "  " << std::setw(9) << Fmt("%.4g", c.rms * scale) << " " << unit
        << "  " << std::setw(9) << Fmt("%.4g", c.apriori * scale) << " " << unit << "  "
        << std::setw(6) << Fmt("%.2f", c.factor) << "  " << (c.exceeds ? "yes" : "no") << "\n";
    }
  }
  o << "\nRanking of the effects not in the model (best first; rms over the fitted rows; "
       "after: refit = a refinement with the effect added, linear = a first-order prediction; "
       "gain: the rms's relative fall, worth adding from "
    << Fmt("%g", 100 * d.min_gain) << " %)\n";
  o << "  effect                  rms before -> after          from     gain    delta BIC   p    "
       "    signif  worth  identif\n";
  for (const RankedEffect& e : d.ranking.entries) {
    const double scale = e.rms_unit == "m" ? 1e3 : 1.0;
    const char* unit = e.rms_unit == "m" ? "mm" : "px";
    o << "  " << std::left << std::setw(22) << e.name << std::right << "  " << std::setw(9)
      << Fmt("%.4g", e.rms_before * scale) << " -> " << std::setw(9)
      << Fmt("%.4g", e.rms_after * scale) << " " << unit << "  " << std::left << std::setw(7)
      << (e.after_source == "refined" ? "refit" : "linear") << std::right << std::setw(6)
      << Fmt("%.2g", 100 * e.gain) << " %  " << std::setw(10) << Fmt("%.1f", e.delta_bic) << "  "
      << std::setw(7) << Fmt("%.1e", e.p_value) << "  " << (e.significant ? "yes" : "no ")
      << "     " << (e.worthwhile ? "yes" : "no ") << "    "
      << (e.redundant      ? "redundant"
          : e.identifiable ? "yes"
                           : "no")
      << "\n";
  }
  if (!d.distortion_terms.terms.empty()) {
    o << "\nFitted distortion coefficients (edge: px the sigma moves the points at the edge of "
         "the data; corner: the same at the image corners, extrapolated where no point was; "
         "rho: largest |correlation| in the zoom)\n";
    o << "  zoom  coef   value         sigma      edge [px]  corner [px]  rho    drop\n";
    for (const DistortionTerm& t : d.distortion_terms.terms) {
      o << "  " << std::setw(4) << t.zoom << "  " << std::left << std::setw(5) << t.name
        << std::right << "  " << std::setw(12) << Fmt("%+.4e", t.value) << "  " << std::setw(9)
        << Fmt("%.2e", t.sigma) << "  " << std::setw(9) << Fmt("%.3g", t.data_px) << "  "
        << std::setw(11) << Fmt("%.3g", t.corner_px) << "  "
        << Fmt("%.3f", std::fabs(t.rho)) << "  " << (t.drop ? "yes: " + t.config_line : "no")
        << "\n";
    }
  }
  if (!d.harmonics.unexplained.empty() || !d.structure.unexplained.empty()) {
    o << "\nStructure outside the catalogue (unexplained)\n";
    for (const Harmonic& h : d.harmonics.unexplained) o << "  " << h.description << "\n";
    for (const StructureFinding& f : d.structure.unexplained) {
      o << "  " << f.description << (f.points_to.empty() ? "" : "; points to " + f.points_to)
        << "\n";
    }
  }
  if (!d.harmonics.negligible.empty() || !d.structure.negligible.empty()) {
    o << "\nStructure outside the catalogue that is significant but within the scatter (each "
         "buys less than "
      << Fmt("%g", 100 * d.min_gain) << " % of the rms)\n";
    for (const Harmonic& h : d.harmonics.negligible) {
      o << "  " << h.description << " (" << Fmt("%.2g", 100 * h.gain) << " %)\n";
    }
    for (const StructureFinding& f : d.structure.negligible) {
      o << "  " << f.description << " (" << Fmt("%.2g", 100 * f.gain) << " %)\n";
    }
  }
  if (!d.structure.explained.empty()) {
    o << "\nStructure significant alone that a catalogue effect or other structure holds\n";
    for (const StructureFinding& f : d.structure.explained) {
      o << "  " << f.description << " ("
        << (f.explained_by.empty() ? "the same structure as " + f.same_as
                                   : "explained by " + f.explained_by)
        << ")\n";
    }
  }
  if (d.outliers.tested > 0) {
    o << "\nOutliers (w-test, critical w = " << Fmt("%.2f", d.outliers.critical_w) << ", "
      << d.outliers.flagged << " of " << d.outliers.tested << " flagged); worst observations:\n";
    for (size_t i = 0; i < d.outliers.worst.size() && i < 5; ++i) {
      const OutlierEntry& e = d.outliers.worst[i];
      o << "  w = " << Fmt("%5.2f", e.w) << (e.flagged ? " FLAGGED " : "         ") << e.where
        << "\n";
    }
  }
  o << "(diagnosis took " << Fmt("%.2f", d.seconds) << " s)\n";
  return o.str();
}

}  // namespace rtscalib::app

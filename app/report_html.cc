#include "app/report_html.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include "app/markup.h"
#include "app/plot/vega.h"
#include "app/reports.h"
#include "libcalib/text/number_text.h"

namespace rtscalib::app {
namespace {

using nlohmann::json;

std::string Mm(double m) { return Fmt("%.4g", m * 1e3); }

const char* kStyle = R"(
body { font-family: -apple-system, "Segoe UI", Helvetica, Arial, sans-serif; color: #222; max-width: 1180px;
       margin: 24px auto; padding: 0 18px; line-height: 1.45; }
h1 { font-size: 26px; margin-bottom: 4px; }
h2 { font-size: 20px; border-bottom: 1px solid #ddd; padding-bottom: 4px; margin-top: 34px; }
h3 { font-size: 16px; margin-top: 22px; }
.meta { color: #666; font-size: 13px; }
.verdict { background: #f4f8fc; border-left: 5px solid #2c6fb7; padding: 10px 18px; margin-top: 18px; }
.verdict.ok { background: #f3faf3; border-left-color: #2c9c2c; }
.verdict .lead { font-size: 17px; font-weight: 600; }
code { background: #eef1f4; padding: 1px 5px; border-radius: 3px; font-size: 13px; }
table { border-collapse: collapse; font-size: 13px; margin: 8px 0 4px 0; max-width: 100%; }
td code { word-break: break-all; }
th, td { border: 1px solid #d6d6d6; padding: 4px 8px; text-align: left; vertical-align: top; }
th { background: #f2f2f2; }
td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
td.est { min-width: 180px; }
td.cfg { min-width: 180px; }
td.cfg code { word-break: normal; overflow-wrap: anywhere; }
td.notes { max-width: 300px; font-size: 12px; color: #555; }
tr.sig td { background: #fff6e0; }
tr.red td { color: #888; }
figure { margin: 14px 0 22px 0; }
figure .plot { overflow-x: auto; }
figure .plot svg { max-width: 100%; height: auto; }
figcaption { font-size: 13px; color: #555; max-width: 1000px; }
.small { font-size: 12px; color: #666; }
)";

// A figure: its Vega spec as JSON data (drawn by the script at the end of the
// page), its caption.
std::string Img(const Figure& f) {
  std::string spec = f.spec.dump();
  // "</" would end the script element early; "<\/" is the same JSON string.
  for (size_t at = spec.find("</"); at != std::string::npos; at = spec.find("</", at + 3))
    spec.replace(at, 2, "<\\/");
  return "<figure class=\"vega\" id=\"fig-" + EscapeMarkup(f.name) + "\" data-figure=\"" + EscapeMarkup(f.name) +
         "\" aria-label=\"" + EscapeMarkup(f.title) +
         "\"><div class=\"plot\"></div><script type=\"application/json\" "
         "id=\"spec-" +
         EscapeMarkup(f.name) + "\">" + spec + "</script><figcaption>" + EscapeMarkup(f.caption) +
         "</figcaption></figure>\n";
}

// The Vega runtime (app/plot/vega.h) and the script that draws every figure of
// the page as SVG; each figure says when it is drawn (data-rendered: the
// number of SVG elements, data-marks: the items of its data marks) or why not
// (data-error), for the checks of scripts/render-report.sh.
std::string FigureScripts() {
  std::string missing;
  const std::string& runtime = VegaRuntime(&missing);
  std::string out;
  if (!runtime.empty()) out += "<script>\n" + runtime + "</script>\n";
  // A JSON string is a JavaScript string literal.
  std::string why = nlohmann::json(missing).dump();
  for (size_t at = why.find("</"); at != std::string::npos; at = why.find("</", at + 3))
    why.replace(at, 2, "<\\/");
  out += "<script>\nvar rtscalibVegaMissing = " + why + ";\n";
  out += R"js((function () {
  var figs = document.querySelectorAll('figure.vega');
  figs.forEach(function (f) {
    var plot = f.querySelector('.plot');
    if (!window.vega) {
      plot.textContent = 'This figure needs the Vega runtime, which was not installed when the ' +
          'report was written (' + rtscalibVegaMissing + '); figures/ holds its spec.';
      f.setAttribute('data-error', 'no vega runtime');
      return;
    }
    try {
      var spec = JSON.parse(document.getElementById('spec-' + f.dataset.figure).textContent);
      new vega.View(vega.parse(spec), {renderer: 'svg', container: plot, hover: true})
        .runAsync()
        .then(function () {
          f.setAttribute('data-rendered', plot.querySelectorAll('svg *').length);
          // Items of the data marks (not axes, legends or titles): a figure
          // with none is blank.
          f.setAttribute('data-marks', plot.querySelectorAll(
              ['symbol', 'rect', 'rule', 'line', 'area', 'image'].map(function (m) {
                return '.role-mark.mark-' + m + ' > *'; }).join(', ')).length);
        })
        .catch(function (e) { f.setAttribute('data-error', String(e)); console.error('figure ' + f.dataset.figure + ': ' + e); });
    } catch (e) {
      f.setAttribute('data-error', String(e));
      console.error('figure ' + f.dataset.figure + ': ' + e);
    }
  });
})();
</script>
)js";
  return out;
}

std::string Figures(const std::vector<Figure>& figs, const std::string& section) {
  std::string out;
  for (const Figure& f : figs) {
    if (f.section == section) out += Img(f);
  }
  return out;
}

std::string GroupCells(const GroupRms& g) {
  return "<td class=num>" + (g.edm_n ? Mm(g.edm_m) : std::string("-")) + "</td><td class=num>" +
         (g.cam_n ? Mm(g.cam_m) : std::string("-")) + "</td><td class=num>" +
         (g.pixels_n ? Fmt("%.4g", g.pixels_px) : std::string("-")) + "</td>";
}

std::string ValueCell(const RankedEffect& r) {
  std::string out;
  const EffectInfo& info = Info(r.effect);
  if (r.has_equivalent) {
    out += "equivalent in the model: ";
    for (int k = 0; k < r.equivalent.num; ++k) {
      out += (k ? ", " : "") + std::string(info.param_names[k]) + " = " +
             Fmt("%.3g", r.equivalent.value[k]) + " " + info.report_units[k];
    }
    return out;
  }
  if (!r.observable || r.redundant) return "-";
  const std::vector<EstimatePart> parts = EstimateParts(r);
  for (size_t i = 0; i < parts.size(); ++i) {
    const EstimatePart& p = parts[i];
    out += (i == 0 ? "" : p.where.empty() ? ", " : "<br>") +
           (p.where.empty() ? "" : p.where + " ") + p.name + " = " + Fmt("%.3g", p.value) +
           " &plusmn; " + Fmt("%.2g", p.sigma) + " " + p.unit;
  }
  if (!parts.empty()) return out;
  for (size_t i = 0; i < r.distortion.size() && i < 8; ++i) {
    const DistortionValue& d = r.distortion[i];
    out += (i ? "<br>" : "") + std::string("zoom ") + std::to_string(d.zoom) + " " + d.coefficient +
           " = " + Fmt("%.3g", d.value) + " &plusmn; " + Fmt("%.2g", d.sigma);
  }
  if (r.distortion.size() > 8) out += "<br>...";
  return out;
}

std::string RankingTable(const Diagnosis& d) {
  std::ostringstream o;
  o << "<table><tr><th>#</th><th>effect</th><th>rms before &rarr; "
       "after</th><th>&Delta;BIC</th><th>p</th>"
       "<th>significant</th><th>identifiable</th><th>estimate (report "
       "units)</th><th>notes</th><th>config line</th></tr>\n";
  int i = 0;
  for (const RankedEffect& r : d.ranking.entries) {
    const bool mm = r.rms_unit == "m";
    o << "<tr class=\""
      << (r.recommended                  ? "sig"
          : r.redundant || !r.observable ? "red"
                                         : "")
      << "\"><td class=num>" << ++i << "</td><td><b>" << EscapeMarkup(r.name) << "</b><br><span class=small>"
      << EscapeMarkup(Info(r.effect).signature) << "</span></td><td class=num>"
      << Fmt("%.4g", r.rms_before * (mm ? 1e3 : 1)) << " &rarr; "
      << Fmt("%.4g", r.rms_after * (mm ? 1e3 : 1)) << (mm ? " mm" : " px")
      << "<br><span class=small>" << (r.after_source == "refined" ? "refit" : EscapeMarkup(r.after_source))
      << ", gain " << Fmt("%.2g", 100 * r.gain) << " %"
      << (r.significant && !r.worthwhile ? " (not worth adding)" : "")
      << "</span></td><td class=num>"
      << Fmt("%.1f", r.delta_bic) << "</td><td class=num>"
      << (r.p_value > 0 ? Fmt("%.2g", r.p_value) : std::string("&lt;1e-300")) << "</td><td>"
      << (r.significant ? "<b>yes</b>" : "no") << "</td><td>"
      << (r.redundant      ? "redundant"
          : !r.observable  ? "not seen"
          : r.identifiable ? "yes"
                           : "no")
      << "</td><td class=est>" << ValueCell(r) << "</td><td class=notes>";
    std::vector<std::string> notes;
    if (!r.note.empty()) notes.push_back(EscapeMarkup(r.note));
    if (!r.aliases.empty()) {
      std::string a = "same structure as: ";
      for (size_t k = 0; k < r.aliases.size(); ++k) a += (k ? ", " : "") + r.aliases[k];
      notes.push_back(EscapeMarkup(a));
    }
    if (!r.needs.empty()) {
      std::string n = "would help: ";
      for (size_t k = 0; k < r.needs.size(); ++k) n += (k ? "; " : "") + r.needs[k];
      notes.push_back(EscapeMarkup(n));
    }
    for (size_t k = 0; k < notes.size(); ++k) o << (k ? "<br>" : "") << notes[k];
    o << "</td><td class=cfg><code>" << EscapeMarkup(r.config_line) << "</code></td></tr>\n";
  }
  o << "</table><p class=small>Sorted best first: the effects worth adding (significant and "
       "buying at least "
    << Fmt("%g", 100 * d.min_gain)
    << " % of the rms: highlighted), then the other significant ones, then the rest, each by "
       "&Delta;BIC. "
    << "&Delta;BIC = &sum;<sub>g</sub> n<sub>g</sub> "
       "log(RSS<sub>g,after</sub>/RSS<sub>g,before</sub>) + k log n "
    << "over the observation groups; p from a cluster-robust Wald test, significant below "
    << Fmt("%.2g", d.ranking.level) << " ("
    << Fmt("%g", 100 * d.ranking.level * std::max(d.ranking.tested, 1)) << "% over the "
    << d.ranking.tested << " effects tested). rms over the rows the fit uses; "
    << "&ldquo;refit&rdquo;: after a refinement with the effect added (what the next run "
       "shows), &ldquo;linearised&rdquo;: predicted "
    << "from the Jacobian at the fitted model; gain: the rms's relative fall. "
       "docs/diagnostics.md explains every column.</p>\n";
  return o.str();
}

std::string HarmonicTable(const std::vector<Harmonic>& hs, bool explained, double unit_length) {
  std::ostringstream o;
  o << "<table><tr><th>structure</th><th>reading in "
       "error</th><th>face</th><th>amplitude</th><th>phase [deg]</th>"
       "<th>p</th>"
    << (explained ? "<th>explained by</th>" : "") << "</tr>\n";
  for (const Harmonic& h : hs) {
    o << "<tr><td>" << EscapeMarkup(HarmonicName(h.probe, unit_length)) << "</td><td>"
      << ReadingName(h.probe.reading) << "</td><td class=num>" << h.probe.face
      << "</td><td class=num>" << Fmt("%.3g", h.amplitude) << " &plusmn; "
      << Fmt("%.2g", h.amplitude_sigma) << " " << EscapeMarkup(h.unit) << "</td><td class=num>"
      << Fmt("%.0f", h.phase_deg) << "</td><td class=num>" << Fmt("%.2g", h.p_value) << "</td>";
    if (explained)
      o << "<td>"
        << (h.explained_by.empty() ? "<b>nothing in the catalogue</b>" : EscapeMarkup(h.explained_by))
        << "</td>";
    o << "</tr>\n";
  }
  o << "</table>\n";
  return o.str();
}

}  // namespace

std::string Base64(const std::vector<unsigned char>& bytes) {
  static const char* kTable = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (bytes[i] << 16) | (bytes[i + 1] << 8) | bytes[i + 2];
    out += kTable[(v >> 18) & 63];
    out += kTable[(v >> 12) & 63];
    out += kTable[(v >> 6) & 63];
    out += kTable[v & 63];
  }
  if (i < bytes.size()) {
    const unsigned v = (bytes[i] << 16) | (i + 1 < bytes.size() ? bytes[i + 1] << 8 : 0);
    out += kTable[(v >> 18) & 63];
    out += kTable[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? kTable[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

std::string ReportHtml(const RunConfig& config, const PipelineResult& r, const json& report,
                       const std::vector<Figure>& figs) {
  std::ostringstream o;
  const std::string run =
      report.contains("rtscalib") ? report["rtscalib"].value("run", std::string()) : "";
  o << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
    << "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
    << "<title>rtscalib report " << EscapeMarkup(run) << "</title><style>" << kStyle
    << "</style></head><body>\n";
  o << "<h1>rtscalib report</h1><p class=meta>run " << EscapeMarkup(run) << " &middot; config <code>"
    << EscapeMarkup(config.config_path) << "</code> &middot; ";
  if (!r.obs.records.empty() || r.obs.pixels.empty()) {
    o << r.obs.records.size() << " records (" << EscapeMarkup(r.obs.records_source) << "), ";
  }
  o << r.obs.pixels.size() << " image points"
    << (r.obs.pixels.empty() ? "" : " (" + EscapeMarkup(r.obs.pixels_source) + ")");
  if (r.calibration.model.kinematics != Kinematics::kNone) {
    o << " &middot; readings given in " << AngleUnitName(r.obs.angle_unit);
  }
  o
    << (r.simulated ? " &middot; simulated data" : "") << "</p>\n";

  // 1. Verdict.
  if (r.calibration.diagnosis) {
    const Diagnosis& d = *r.calibration.diagnosis;
    const RankedEffect* next = d.Next();
    const bool ok = !next && d.harmonics.unexplained.empty() && d.structure.unexplained.empty() &&
                    !d.fit_quality.Exceeds() && d.wild.empty();
    o << "<section class=\"verdict" << (ok ? " ok" : "")
      << "\" id=\"verdict\"><h2 style=\"border:none;margin-top:4px\">Verdict</h2>\n";
    for (size_t i = 0; i < d.verdict.size(); ++i) {
      o << "<p" << (i == 1 ? " class=lead" : "") << ">" << EscapeMarkup(d.verdict[i]) << "</p>\n";
    }
    if (next) {
      o << "<p>Add it with this line in the config, then run again:<br><code>"
        << EscapeMarkup(next->config_line) << "</code></p>\n";
    }
    o << "</section>\n";
  } else {
    o << "<section class=verdict><p>The diagnosis is switched off (<code>diagnose.enabled: "
         "false</code>).</p></section>\n";
  }

  // 2. The ladder.
  const bool has_history =
      report.contains("history") && report["history"].is_array() && !report["history"].empty();
  if (!r.calibration.ladder.empty() || has_history) {
    o << "<h2 id=\"ladder\">Watch the error fall</h2>\n";
    if (!r.calibration.ladder.empty()) {
      o << "<h3>This run: forward stepwise (" << EscapeMarkup(r.calibration.ladder_stop)
        << ")</h3><table><tr><th>step</th><th>added</th>"
           "<th>model</th><th>EDM rms [mm]</th><th>camera rms [mm]</th><th>pixels rms "
           "[px]</th><th>BIC</th></tr>\n";
      for (size_t i = 0; i < r.calibration.ladder.size(); ++i) {
        const LadderStep& s = r.calibration.ladder[i];
        o << "<tr><td class=num>" << i << "</td><td>" << EscapeMarkup(s.added.empty() ? "(start)" : s.added)
          << "</td><td>" << EscapeMarkup(s.model_description) << "</td>" << GroupCells(s.rms)
          << "<td class=num>" << Fmt("%.1f", s.bic) << "</td></tr>\n";
      }
      o << "</table>\n";
    }
    if (has_history) {
      o << "<h3>Runs in this output folder</h3><table><tr><th>run</th><th>model</th><th>EDM rms "
           "[mm]</th>"
           "<th>camera rms [mm]</th><th>pixels rms [px]</th></tr>\n";
      auto row = [&](const std::string& name, const std::string& kin, const json& effects,
                     const json& final) {
        auto rms = [&](const char* tool) {
          if (!final.contains("records") || !final["records"].contains(tool))
            return std::string("-");
          const json& t = final["records"][tool];
          return t.value("n", 0) > 0 ? Mm(t.value("rms_m", 0.0)) : std::string("-");
        };
        std::string eff;
        for (const auto& e : effects) eff += (eff.empty() ? "" : ", ") + e.get<std::string>();
        const std::string px = final.contains("pixels") && final["pixels"].value("n", 0) > 0
                                   ? Fmt("%.4g", final["pixels"].value("rms_px", 0.0))
                                   : "-";
        o << "<tr><td>" << EscapeMarkup(name) << "</td><td>" << EscapeMarkup(kin) << ", effects: [" << EscapeMarkup(eff)
          << "]</td><td class=num>" << rms("edm") << "</td><td class=num>" << rms("cam")
          << "</td><td class=num>" << px << "</td></tr>\n";
      };
      for (const json& h : report["history"]) {
        const std::string status = h.value("status", std::string("complete"));
        row(h.value("run", std::string("?")) + (status == "complete" ? "" : " (" + status + ")"),
            h.value("kinematics", std::string("?")), h.value("effects", json::array()),
            h.value("final", json::object()));
      }
      row(run + " (this run)", KinematicsName(r.calibration.model.kinematics),
          r.calibration.model.effects.Names(), report.value("final", json::object()));
      o << "</table>\n";
    }
    o << Figures(figs, "ladder");
  }

  // 3. Maps.
  const bool camera_only = r.calibration.model.kinematics == Kinematics::kNone;
  const std::string maps = Figures(figs, "maps");
  o << "<h2 id=\"maps\">Where the model fails</h2>\n";
  if (!maps.empty()) {
    o << maps;
  } else if (camera_only) {
    o << "<p>A camera on its own has no angle readings, so there are no maps over phi and "
         "theta: <a href=\"#image\">the image residuals</a> show where the model fails over "
         "the image, <a href=\"#photos\">the worst photos</a> where it fails on a board.</p>\n";
  } else {
    o << "<p>No map was drawn (figures are off or their renderer failed: see the run's "
         "log).</p>\n";
  }

  // 4. Tables.
  if (r.calibration.diagnosis) {
    const Diagnosis& d = *r.calibration.diagnosis;
    o << "<h2 id=\"ranking\">Which effect is missing</h2>\n" << RankingTable(d);
    o << "<h2 id=\"structure\">Structure outside the catalogue</h2>\n";
    if (!d.structure.unexplained.empty() || !d.structure.explained.empty()) {
      o << "<p>Against the session's other variables (target distance, photo and record order, "
           "covariate columns, placements and boards, image position and radius):</p>\n"
        << "<table><tr><th>structure</th><th>p</th><th>explained by</th><th>points to</th></tr>\n";
      for (const auto* list : {&d.structure.unexplained, &d.structure.explained}) {
        for (const StructureFinding& f : *list) {
          o << "<tr><td>" << EscapeMarkup(f.description) << "</td><td>" << Fmt("%.1e", f.p_value)
            << "</td><td>" << EscapeMarkup(f.explained_by.empty() ? "-" : f.explained_by) << "</td><td>"
            << EscapeMarkup(f.unexplained ? f.points_to : "-") << "</td></tr>\n";
        }
      }
      o << "</table>\n";
    }
    if (camera_only) {
      // No readings: there is no phi, theta or distance to look for harmonics in.
    } else if (d.harmonics.unexplained.empty()) {
      o << "<p>No harmonic of the phi, theta or distance readings (1 to 4 per turn, or of "
           "the EDM unit "
           "length) is significant once every catalogue effect is allowed for.</p>\n";
    } else {
      o << "<p>Significant once every catalogue effect is allowed for; reported as what they are, "
           "not under an "
           "effect's name (error = amplitude &middot; sin(k x &minus; phase)):</p>\n"
        << HarmonicTable(d.harmonics.unexplained, false,
                         r.calibration.model.edm_cyclic_unit_length);
    }
    if (!d.harmonics.before_catalogue.empty()) {
      o << "<h3>Harmonics in the residuals of this model</h3>\n"
        << HarmonicTable(d.harmonics.before_catalogue, true,
                         r.calibration.model.edm_cyclic_unit_length);
    }
    o << "<h2 id=\"outliers\">Outliers (w-test)</h2>\n<p>" << d.outliers.flagged << " of "
      << d.outliers.tested
      << " observations flagged; critical w = " << Fmt("%.2f", d.outliers.critical_w)
      << " (Bonferroni over all observations). Worst "
         "observations:</p>\n<table><tr><th>w</th><th>flagged</th>"
         "<th>observation</th><th>|residual|</th></tr>\n";
    for (const OutlierEntry& e : d.outliers.worst) {
      const bool px = e.group == ObsGroup::kPixel;
      o << "<tr><td class=num>" << Fmt("%.2f", e.w) << "</td><td>"
        << (e.flagged ? "<b>yes</b>" : "no") << "</td><td>" << EscapeMarkup(e.where) << "</td><td class=num>"
        << (px ? Fmt("%.3g px", e.size) : Fmt("%.3g mm", e.size * 1e3)) << "</td></tr>\n";
    }
    o << "</table>\n";
  }
  o << "<h2 id=\"final\">Final errors (all rows, SPEC "
       "6)</h2>\n<table><tr><th>group</th><th>mean</th><th>std</th>"
       "<th>rms</th><th>n</th></tr>\n";
  auto stats = [&](const char* name, const ErrorStats& s) {
    if (s.n == 0) return;
    o << "<tr><td>" << name << "</td><td class=num>" << Mm(s.mean_m) << " mm</td><td class=num>"
      << Mm(s.std_m) << " mm</td><td class=num>" << Mm(s.rms_m) << " mm</td><td class=num>" << s.n
      << "</td></tr>\n";
  };
  stats("EDM points", r.calibration.final_errors.edm);
  stats("camera points", r.calibration.final_errors.cam);
  if (r.calibration.final_errors.pixels.n > 0) {
    o << "<tr><td>image points</td><td class=num>"
      << Fmt("%.4g", r.calibration.final_errors.pixels.mean_px) << " px</td><td></td><td class=num>"
      << Fmt("%.4g", r.calibration.final_errors.pixels.rms_px) << " px</td><td class=num>"
      << r.calibration.final_errors.pixels.n << "</td></tr>\n";
  }
  o << "</table>\n<p class=small>Refinement "
    << (r.calibration.fit.converged ? "converged" : "did NOT converge") << " in "
    << r.calibration.fit.iterations << " iterations; " << r.calibration.fit.excluded_critical
    << " rows in the critical regions excluded. " << EscapeMarkup(FitSigmasText(r.calibration.fit, !r.obs.records.empty()))
    << "</p>\n";

  const Coverage& cov = r.calibration.coverage;
  if (!cov.images.empty()) {
    o << "<h2 id=\"coverage\">Image coverage</h2>\n<table><tr><th>zoom</th><th>image "
         "px</th><th>points</th><th>image covered</th><th>farthest point, of the "
         "half-diagonal</th><th>corners</th></tr>\n";
    for (const ImageCoverage& c : cov.images) {
      o << "<tr><td>" << c.zoom << "</td><td class=num>" << c.width << " x " << c.height
        << "</td><td class=num>" << c.points << "</td><td class=num>"
        << Fmt("%.0f", 100 * c.covered_fraction) << " %</td><td class=num>"
        << Fmt("%.0f", 100 * cov.corner_fraction[c.zoom]) << " %</td><td>"
        << (c.corners_covered ? "covered" : "<b>NOT covered</b>") << "</td></tr>\n";
    }
    o << "</table>\n";
    if (!r.calibration.coverage_warnings.empty()) {
      o << "<ul>";
      for (const std::string& w : r.calibration.coverage_warnings) o << "<li>" << EscapeMarkup(w) << "</li>";
      o << "</ul>\n";
    }
    if (const std::string hint = PlanHint(config, r); !hint.empty()) {
      o << "<p>" << EscapeMarkup(hint) << "</p>\n";
    }
  }
  if (!r.uncertainty_maps.empty()) {
    o << "<h2 id=\"uncertainty\">Projection uncertainty</h2>\n<table><tr><th>zoom</th><th>min "
         "px</th><th>median px</th><th>max px</th><th>max inside the points' hull px</th><th>cells "
         "outside</th></tr>\n";
    for (const UncertaintyMap& m : r.uncertainty_maps) {
      if (!m.determined) continue;
      o << "<tr><td>" << m.zoom << "</td><td class=num>" << Fmt("%.3g", m.min_px)
        << "</td><td class=num>" << Fmt("%.3g", m.median_px) << "</td><td class=num>"
        << Fmt("%.3g", m.max_px) << "</td><td class=num>" << Fmt("%.3g", m.inside_max_px)
        << "</td><td class=num>" << m.cells_outside << " of " << m.cols * m.rows << "</td></tr>\n";
    }
    const UncertaintyMapOptions& u = r.uncertainty_options;
    const bool up_to_rotation = r.uncertainty_maps.front().up_to_rotation;
    o << "</table>\n<p class=small>1 sigma, worst direction, of the pixel where "
      << EscapeMarkup(MapSubject(r.uncertainty_maps.front(), u)) << " is seen, from the "
      << (r.full_covariance ? "fit's full covariance" : "sigmas alone (no full covariance)")
      << (up_to_rotation
              ? " of the camera's intrinsics and distortion, less what a turn of the camera undoes "
                "(a camera on its own has no other frame)"
              : " of the zoom's camera and the kinematic chain")
      << "; hatched cells lie outside the convex "
         "hull of the calibration's image points (extrapolated). docs/output.md tells how to "
         "read the maps.</p>\n"
      << Figures(figs, "uncertainty");
  }
  o << "<h2 id=\"image\">Image residuals</h2>\n" << Figures(figs, "image");
  if (!Figures(figs, "photos").empty()) {
    o << "<h2 id=\"photos\">The worst photos of each zoom</h2>\n<p class=small>Any photo: "
         "<code>rtscalib show --output OUT --shot ID</code>.</p>\n"
      << Figures(figs, "photos");
  }
  o << "<h2 id=\"variables\">Residuals against the variables</h2>\n" << Figures(figs, "variables");
  o << "<h2 id=\"histograms\">Residual distributions</h2>\n" << Figures(figs, "histograms");
  if (!r.calibration.gross_rows.empty()) {
    o << "<h2 id=\"gross\">Gross errors</h2>\n<pre class=small>" << EscapeMarkup(GrossRowsText(r))
      << "</pre>\n";
  }
  std::vector<std::string> notes = r.notes;
  if (report.contains("figures") && report["figures"].contains("note"))
    notes.push_back(report["figures"]["note"].get<std::string>());
  if (!notes.empty()) {
    o << "<h2>Notes</h2><ul class=small>";
    for (const std::string& n : notes) o << "<li>" << EscapeMarkup(n) << "</li>";
    o << "</ul>\n";
  }
  o << "<p class=small>rtscalib 0.1.0 &middot; report.json holds every number of this "
       "page, residuals.csv every residual, figures/*.vg.json every figure's data (Vega 5).</p>\n"
    << FigureScripts() << "</body></html>\n";
  return o.str();
}

std::string FigurePage(const Figure& f) {
  return "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" + EscapeMarkup(f.title) +
         "</title><style>" + kStyle + "</style></head><body>\n" + Img(f) + FigureScripts() +
         "</body></html>\n";
}

}  // namespace rtscalib::app

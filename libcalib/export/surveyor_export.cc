#include "libcalib/export/surveyor_export.h"

#include <cmath>
#include <functional>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>

#include "libcalib/diagnose/equivalents.h"
#include "libcalib/text/number_text.h"

namespace rtscalib {
namespace {

constexpr const char* kNotAvailable = "sigma not available";

bool UsableSigma(double s) { return std::isfinite(s) && s > 0.0; }

// Report-unit scale of a one-parameter effect (value per SI unit).

// The four terms a dh model holds in its links and tools.
constexpr Effect kDhTerms[4] = {Effect::kCollimation, Effect::kTiltingAxis, Effect::kVerticalIndex,
                                Effect::kEdmOffset};

bool IsDhTerm(Effect e) {
  for (Effect t : kDhTerms) {
    if (t == e) return true;
  }
  return false;
}

SurveyorTerm NewTerm(Effect e, int param) {
  SurveyorTerm t;
  t.effect = e;
  t.symbol = Info(e).param_names[param];
  t.unit = Info(e).report_units[param];
  return t;
}

// Terms of one effect read from its parameters and stored covariance.
void AddFromEffect(const InstrumentModel& model, Effect e, SurveyorConstants* out) {
  const EffectInfo& info = Info(e);
  const bool on = model.effects.Has(e);
  const EffectReportValue r =
      ToReportUnits(e, model.EffectValue(e), model.sigmas.effect_cov[static_cast<int>(e)]);
  for (int i = 0; i < info.num_params; ++i) {
    SurveyorTerm t = NewTerm(e, i);
    if (!on) {
      t.source = "not in the model (taken as 0)";
      t.sigma_note = kNotAvailable;
    } else {
      t.available = true;
      t.value = r.value[i];
      t.source = "effect parameter";
      if (!model.sigmas.valid) {
        t.sigma_note = std::string(kNotAvailable) + " (the model has no uncertainties)";
      } else if (!UsableSigma(r.sigma[i])) {
        t.sigma_note = std::string(kNotAvailable) + " (no covariance for it)";
      } else {
        t.sigma = r.sigma[i];
        t.sigma_note = "from the fit's covariance";
      }
    }
    out->terms.push_back(t);
  }
}

// First-order sigmas of the dh equivalents from the stored marginal sigmas
// (header). Returns false when no usable sigma was stored.
bool PropagateDhSigmas(const InstrumentModel& dh, const FitOptions& fit,
                       std::array<double, kNumKinematicEffects>* sigma, std::string* why) {
  using Perturb = std::function<void(double sign, InstrumentModel*)>;
  std::vector<Perturb> moves;
  const ModelSigmas& s = dh.sigmas;
  for (int k = 0; k < 2; ++k) {
    for (int j = 0; j < 4; ++j) {
      const double sj = s.links[k][j];
      if (UsableSigma(sj)) {
        moves.push_back(
            [k, j, sj](double sign, InstrumentModel* m) { m->links[k].p[j] += sign * sj; });
      }
    }
  }
  for (int a = 0; a < 3; ++a) {
    // Rotation sigmas are about the block's local axes (instrument.h).
    const double sr = s.edm.rotation[a];
    if (UsableSigma(sr)) {
      moves.push_back([a, sr](double sign, InstrumentModel* m) {
        Rigid3 p = m->edm.ToRigid();
        p.rotation = p.rotation * Eigen::AngleAxisd(sign * sr, Eigen::Vector3d::Unit(a)).matrix();
        m->edm = PoseBlock::FromRigid(p);
      });
    }
    const double st = s.edm.t[a];
    if (UsableSigma(st)) {
      moves.push_back([a, st](double sign, InstrumentModel* m) { m->edm.t[a] += sign * st; });
    }
  }
  if (moves.empty()) {
    *why = "the model stores no usable sigma of the DH links or the EDM pose";
    return false;
  }
  sigma->fill(0.0);
  for (const Perturb& move : moves) {
    EquivalentTerms side[2];
    for (int k = 0; k < 2; ++k) {
      InstrumentModel m = dh;
      move(k == 0 ? 1.0 : -1.0, &m);
      side[k] = EquivalentSurveyingTerms(m, fit);
      if (!side[k].valid) {
        *why = "an equivalents fit of a perturbed model failed: " + side[k].message;
        return false;
      }
    }
    for (Effect e : kDhTerms) {
      const int i = static_cast<int>(e);
      const double d = 0.5 * (side[0].value[i][0] - side[1].value[i][0]);
      (*sigma)[i] += d * d;
    }
  }
  for (double& v : *sigma) v = std::sqrt(v);
  return true;
}

std::string Fixed(double x, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << x;
  return s.str();
}

}  // namespace

double ArcsecToMgon(double arcsec) { return arcsec / 3.24; }
double DegToGon(double deg) { return deg / 0.9; }

SurveyorConstants ComputeSurveyorConstants(const InstrumentModel& model, const FitOptions& fit) {
  SurveyorConstants out;
  out.kinematics = model.kinematics;
  const bool dh = model.kinematics == Kinematics::kDh;

  EquivalentTerms eq;
  std::array<double, kNumKinematicEffects> eq_sigma{};
  bool have_eq_sigma = false;
  std::string sigma_why;
  if (dh) {
    eq = EquivalentSurveyingTerms(model, fit);
    if (eq.valid) {
      out.notes.push_back(
          "c, i, v0 and k0 are the dh model's equivalents: a spherical model with these terms "
          "fitted to the dh model's EDM predictions (both faces) reproduces them to " +
          Significant(eq.fit_rms_m, 2) +
          " m RMS (what remains is geometry these terms cannot express, such as a DH link "
          "offset).");
      if (model.sigmas.valid) {
        have_eq_sigma = PropagateDhSigmas(model, fit, &eq_sigma, &sigma_why);
      } else {
        sigma_why = "the model has no uncertainties";
      }
      if (have_eq_sigma) {
        out.notes.push_back(
            "Sigmas of the dh equivalents: first-order propagation of the stored marginal sigmas "
            "of the DH links and the EDM pose; model.yaml holds no correlations, so they are "
            "ignored and these sigmas are a rough scale only.");
      }
    } else {
      out.notes.push_back("the dh equivalents could not be computed: " + eq.message);
    }
  }

  for (const EffectInfo& info : EffectCatalogue()) {
    const Effect e = info.effect;
    if (!IsKinematic(e)) continue;
    if (!(dh && IsDhTerm(e))) {
      AddFromEffect(model, e, &out);
      continue;
    }
    SurveyorTerm t = NewTerm(e, 0);
    if (!eq.valid) {
      t.source = "dh equivalent not available";
      t.sigma_note = kNotAvailable;
    } else {
      const int i = static_cast<int>(e);
      t.available = true;
      t.value = eq.value[i][0] * ReportScale(e);
      t.source = "dh equivalent";
      if (have_eq_sigma && UsableSigma(eq_sigma[i])) {
        t.sigma = eq_sigma[i] * ReportScale(e);
        t.sigma_note = "first order from marginal sigmas, correlations ignored";
      } else {
        t.sigma_note =
            std::string(kNotAvailable) + (sigma_why.empty() ? "" : " (" + sigma_why + ")");
      }
    }
    out.terms.push_back(t);
  }
  return out;
}

std::string SurveyorText(const SurveyorConstants& c) {
  std::ostringstream s;
  s << "Instrument constants (rtscalib, " << KinematicsName(c.kinematics) << " model)\n";
  s << "Signs and definitions: docs/effects.md (SPEC 4). 1 mgon = 3.24 arcsec, 1 gon = 0.9 "
       "deg.\n\n";
  s << std::left << std::setw(17) << "effect" << std::setw(8) << "term" << std::right
    << std::setw(14) << "value" << std::setw(14) << "sigma"
    << "  " << std::left << std::setw(7) << "unit" << std::right << std::setw(12) << "value"
    << std::setw(12) << "sigma"
    << "  " << std::left << std::setw(5) << "unit"
    << "source\n";
  for (const SurveyorTerm& t : c.terms) {
    const bool angle = t.unit == "arcsec", phase = t.unit == "deg";
    const int digits = t.unit == "ppm" ? 2 : 3;
    s << std::left << std::setw(17) << Info(t.effect).name << std::setw(8) << t.symbol
      << std::right;
    if (!t.available) {
      s << std::setw(14) << "-" << std::setw(14) << "-"
        << "  " << std::left << std::setw(7) << t.unit << std::right << std::setw(12) << ""
        << std::setw(12) << ""
        << "  " << std::setw(5) << "" << t.source << "\n";
      continue;
    }
    s << std::setw(14) << Fixed(t.value, digits) << std::setw(14)
      << (t.sigma ? Fixed(*t.sigma, digits) : "n/a") << "  " << std::left << std::setw(7) << t.unit
      << std::right;
    if (angle || phase) {
      const double k = angle ? ArcsecToMgon(1.0) : DegToGon(1.0);
      s << std::setw(12) << Fixed(t.value * k, angle ? 3 : 4) << std::setw(12)
        << (t.sigma ? Fixed(*t.sigma * k, angle ? 3 : 4) : "n/a") << "  " << std::left
        << std::setw(5) << (angle ? "mgon" : "gon") << std::right;
    } else {
      s << std::setw(12) << "" << std::setw(12) << ""
        << "  " << std::setw(5) << "";
    }
    s << t.source;
    if (!t.sigma) s << "; " << t.sigma_note;
    s << "\n";
  }
  if (!c.notes.empty()) s << "\n";
  for (const std::string& n : c.notes) s << "Note: " << n << "\n";
  return s.str();
}

std::string SurveyorJson(const SurveyorConstants& c) {
  nlohmann::ordered_json j;
  j["format"] = "rtscalib-surveyor-constants";
  j["version"] = 1;
  j["kinematics"] = KinematicsName(c.kinematics);
  nlohmann::ordered_json terms = nlohmann::ordered_json::array();
  for (const SurveyorTerm& t : c.terms) {
    nlohmann::ordered_json o;
    o["effect"] = Info(t.effect).name;
    o["term"] = t.symbol;
    o["unit"] = t.unit;
    o["available"] = t.available;
    o["value"] = t.available ? nlohmann::ordered_json(t.value) : nlohmann::ordered_json(nullptr);
    o["sigma"] = t.sigma ? nlohmann::ordered_json(*t.sigma) : nlohmann::ordered_json(nullptr);
    if (t.available && t.unit == "arcsec") {
      o["value_mgon"] = ArcsecToMgon(t.value);
      o["sigma_mgon"] = t.sigma ? nlohmann::ordered_json(ArcsecToMgon(*t.sigma))
                                : nlohmann::ordered_json(nullptr);
    }
    if (t.available && t.unit == "deg") {
      o["value_gon"] = DegToGon(t.value);
      o["sigma_gon"] =
          t.sigma ? nlohmann::ordered_json(DegToGon(*t.sigma)) : nlohmann::ordered_json(nullptr);
    }
    o["source"] = t.source;
    o["sigma_note"] = t.sigma_note;
    terms.push_back(o);
  }
  j["terms"] = terms;
  j["notes"] = c.notes;
  return j.dump(2) + "\n";
}

}  // namespace rtscalib

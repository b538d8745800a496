// The instrument's constants in a surveyor's terms, read off a model: the
// catalogue's kinematic and EDM effects (SPEC 4, effects.h) with their sigmas.
//
//   collimation c, tilting_axis i, vertical_index v0     arcsec (and mgon, 1 mgon = 3.24")
//   hz/v_eccentricity e, phase                          arcsec, deg (and gon)
//   hz/v_scale s, edm_scale m                           ppm
//   axis_wobble w, phi_w                                arcsec, deg
//   edm_offset k0, edm_cyclic A, psi                    mm, deg
// Sources:
//   spherical  the effect parameters, sigmas from the model's stored covariances.
//   dh         c, i, v0, k0 live in the links and tools (redundant in dh, SPEC 4):
//              their equivalents come from EquivalentSurveyingTerms. Their sigmas
//              are propagated to first order from the model's stored marginal sigmas of the
//              DH links and the EDM pose (central differences of +-1 sigma per parameter,
//              root sum of squares). model.yaml holds no cross-covariances, so correlations
//              are ignored: a rough scale, not the fit's covariance; said so in the output.
//              Base pose sigmas are left out: a base change moves the instrument rigidly
//              and the equivalent spherical form's own base absorbs it exactly. The dh
//              model's other effects are read like spherical ones.
// A sigma that is missing, NaN or zero (a parameter held in the fit) is
// reported as not available, never as 0.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "libcalib/fit/refine.h"
#include "libcalib/model/instrument.h"

namespace rtscalib {

struct SurveyorTerm {
  Effect effect;
  std::string symbol;  // c, i, v0, e, phi_e, ...
  std::string unit;    // report unit: arcsec, deg, mm, ppm
  bool available = false;
  double value = 0;             // report units; valid when available
  std::optional<double> sigma;  // report units
  std::string source;           // "effect parameter", "dh equivalent", "not in the model", ...
  std::string sigma_note;       // how the sigma was obtained, or why there is none
};

struct SurveyorConstants {
  Kinematics kinematics = Kinematics::kDh;
  std::vector<SurveyorTerm> terms;  // every kinematic/EDM effect of the catalogue, in its order
  std::vector<std::string> notes;
};

// `fit` supplies the zenith limits of the dh equivalents (their defaults are the run's).
SurveyorConstants ComputeSurveyorConstants(const InstrumentModel& model,
                                           const FitOptions& fit = FitOptions());

// Plain text table (surveyor.txt) and JSON (surveyor.json) of the same content.
std::string SurveyorText(const SurveyorConstants& constants);
std::string SurveyorJson(const SurveyorConstants& constants);

// 1 mgon = 3.24 arcsec; 1 gon = 0.9 deg.
double ArcsecToMgon(double arcsec);
double DegToGon(double deg);

}  // namespace rtscalib

// Diagnosis of a fitted model: where it fails, which catalogue effect is
// missing, what structure lies outside the catalogue, which observations are
// outliers. docs/diagnostics.md explains every number.
//
//   Linearize (one Jacobian at the fitted model)  ->  Reduce (project out the fit)
//     -> AssessFitQuality (each kind of observation against its a-priori sigma)
//     -> AnalyseProbes (structure outside the catalogue: harmonics of phi and
//        theta, trends against the session's variables, image motions and
//        fields; the nuisance for the ranking) -> AnalyseHarmonics, AnalyseStructure
//     -> RankEffects (every effect not in the model; best ones confirmed by Refine)
//     -> TestOutliers (w-test per observation)
//     -> AssessDistortionTerms (fitted distortion coefficients to drop)
//     -> FindWildParameters (a fit that went wild)
//     -> verdict (the sentences a report opens with: first whether the model
//        fits its a-priori sigmas, then wild parameters, then the ranking)
// Nothing here writes files; app/ turns a Diagnosis into report.json and report.html.
#pragma once

#include <string>
#include <vector>

#include "libcalib/diagnose/coverage.h"
#include "libcalib/diagnose/distortion_terms.h"
#include "libcalib/diagnose/equivalents.h"
#include "libcalib/diagnose/fit_quality.h"
#include "libcalib/diagnose/harmonics.h"
#include "libcalib/diagnose/outliers.h"
#include "libcalib/diagnose/ranking.h"
#include "libcalib/diagnose/residuals.h"
#include "libcalib/diagnose/structure.h"
#include "libcalib/diagnose/wild_fit.h"

namespace rtscalib {

// How Diagnose (and ForwardStepwise, stepwise.h) test. Not the config's
// `diagnose` section (DiagnoseOptions, libcalib/calibrate/options.h: whether
// Calibrate diagnoses, whether it adds effects): Calibrate passes that
// section's significance on and leaves the rest at these defaults.
struct DiagnosisSettings {
  double significance = 0.01;  // family-wise level of each of: ranking, harmonics, outliers
  int refine_top = 2;          // best significant effects confirmed by a refinement
  bool harmonics = true;
  int max_harmonic = 4;
  int max_unexplained = 6;
  bool outliers = true;
  int outliers_listed = 12;
  // Structure beyond phi and theta (structure.h): trends against the
  // session's variables, image motions and fields.
  bool structure = true;
  // Catalogue effects the ranking leaves out (neither ranked nor used to
  // explain structure): what the diagnosis says of data whose effect the
  // catalogue lacks (tests).
  std::vector<Effect> untested;
  std::string Check() const;
};

// What the fit used and found: the options (fit_intrinsics as decided) and
// the a-posteriori sigmas that whiten the residuals.
struct FitContext {
  FitOptions options;
  double sigma[3] = {1e-5, 1e-5, 0.5};  // edm [m], cam [m], pixel [px]
};
FitContext ContextOf(const FitOptions& used, const FitSummary& summary);

struct Diagnosis {
  std::string model_description;  // "dh, effects: [hz_eccentricity]"
  std::vector<std::string> effects;
  Kinematics kinematics = Kinematics::kDh;
  GroupRms current;
  // Each kind of observation (per zoom and face) against its a-priori sigma.
  FitQuality fit_quality;
  Ranking ranking;
  HarmonicAnalysis harmonics;
  StructureAnalysis structure;
  // Parameters the data do not hold or no instrument has (a fit gone wild).
  std::vector<WildParameter> wild;
  OutlierReport outliers;
  // Fitted distortion coefficients, and those to drop with their config line.
  DistortionTerms distortion_terms;
  Coverage coverage;
  EquivalentTerms equivalents;
  double sigma[3] = {0, 0, 0};                 // whitening sigmas (fitted noise per group)
  int num_rows = 0, num_parameters = 0;
  int excluded_critical = 0;
  std::vector<std::string> verdict;  // most important first
  double seconds = 0;

  // The first significant effect, if any (what to add next).
  const RankedEffect* Next() const;
};

// `obs`: the rows the fit used, as it used them (boards of estimated pose
// and points of unknown position are the model's, free in the
// linearisation and in the refits of the ranking: Linearize).
Diagnosis Diagnose(const Observations& obs, const InstrumentModel& model, const FitContext& fit,
                   const DiagnosisSettings& settings);

}  // namespace rtscalib

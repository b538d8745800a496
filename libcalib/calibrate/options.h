// Options of the whole calibration (libcalib/calibrate/calibrate.h): what to
// fit (the config's `model` section), how to fit it (FitOptions, the `fit`
// section), what to diagnose afterwards (the `diagnose` section) and how to
// screen the observations before (ScreenOptions, the `screen` section). Every
// key is documented in docs/config.md.
#pragma once

#include <string>
#include <vector>

#include "libcalib/fit/options.h"
#include "libcalib/model/effects.h"
#include "libcalib/model/instrument.h"
#include "libcalib/screen/options.h"

namespace rtscalib {

// Whether face 1 and face 2 share one model or get one each.
enum class FaceMode { kJoint, kSeparate };
// Camera intrinsics: kAuto = fit them when the camera data span the image
// (Calibrate decides), kFit = always fit, kFixed = keep model.cameras.
enum class IntrinsicsMode { kAuto, kFit, kFixed };

// The `model` section: what to fit.
struct ModelSettings {
  Kinematics kinematics = Kinematics::kDh;
  EffectSet effects;
  double edm_cyclic_unit_length = 1.5;  // U of edm_cyclic [m]
  FaceMode faces = FaceMode::kJoint;
  IntrinsicsMode intrinsics = IntrinsicsMode::kAuto;
  // Starting (or, with kFixed, final) size, intrinsics and distortion per
  // zoom level; index = zoom. Empty when the config gives none. The
  // flange_from_cam poses are not configured (extraction finds them).
  std::vector<CameraTool> cameras;
  // model.<distortion group>: {coefficients: [...], zooms: {z: [...]}}: the
  // coefficients of enabled groups that are fitted (libcalib/fit/options.h);
  // at most one per group, each for a group in `effects`.
  std::vector<DistortionChoice> distortion_choices;
};

// The `diagnose` section.
struct DiagnoseOptions {
  bool enabled = true;         // rank missing effects and look for unexplained patterns
  bool auto_add = false;       // key `auto`: add significant effects and refit
  // Test level for "significant" (Calibrate passes it on as
  // DiagnosisSettings::significance, libcalib/diagnose/diagnose.h).
  double significance = 0.01;
};

// What a fit's outcome must satisfy to be a model (libcalib/calibrate/validate.h;
// Check() is defined there).
struct FitChecks {
  // The a-priori sigmas are the user's statement of the instrument's noise.
  // Misjudging them by a factor of a few, or effects the diagnosis still has
  // to find, give sigma0 of a few to tens; 100 times the stated noise is a
  // gross error (a wrong unit, a wrong row, a wrong local minimum).
  double max_sigma0 = 100;
  int max_rows_named = 20;
  // Empty if valid, else what is wrong.
  std::string Check() const;
};

struct CalibrationOptions {
  ModelSettings model;
  // fit.fit_intrinsics is not read: Calibrate decides it from model.intrinsics
  // and the data (FitIntrinsics, libcalib/calibrate/intrinsics.h;
  // CalibrationResult::intrinsics_fitted says what was decided).
  FitOptions fit;
  DiagnoseOptions diagnose;
  // Checked by Calibrate's screening (ScreenObservations), which rejects
  // invalid values itself.
  ScreenOptions screen;
  FitChecks checks;  // key fit.max_sigma0
  // Empty if valid, else what is wrong (the option's name, what it must be).
  std::string Check() const;
};

}  // namespace rtscalib

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
};

// The `diagnose` section.
struct DiagnoseOptions {
  bool enabled = true;         // rank missing effects and look for unexplained patterns
  bool auto_add = false;       // key `auto`: add significant effects and refit
  double significance = 0.01;  // test level for "significant"
};

struct CalibrationOptions {
  ModelSettings model;
  // fit.fit_intrinsics is not read: model.intrinsics decides it
  // (CalibrationResult::intrinsics_fitted says what was decided).
  FitOptions fit;
  DiagnoseOptions diagnose;
  // Checked by Calibrate's screening (ScreenObservations), which rejects
  // invalid values itself.
  ScreenOptions screen;
  // Empty if valid, else what is wrong (the option's name, what it must be).
  std::string Check() const;
};

}  // namespace rtscalib

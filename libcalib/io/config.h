// The run configuration (SPEC 5; every key is documented in docs/config.md):
// one YAML file -> the library's option structs.
//
// Rules:
//   - unknown keys anywhere are errors naming the key path, file and line;
//   - relative paths are relative to the config file's folder;
//   - values are checked where they are read, so each message points at the
//     offending key (negative sigmas, zenith limits out of order, effects not
//     in the catalogue, distortion longer than 14, non-positive image sizes...);
//   - the `render` section belongs to the render module: it is kept as YAML
//     text and its keys are checked there.
// io does not depend on sim or fit code, only on their option structs, so
// the simulated truth of Klug's instrument (PaperTruth, libcalib/sim) is not
// built here: `truth_from_paper` tells the caller to build it.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "libcalib/fit/refine.h"
#include "libcalib/model/effects.h"
#include "libcalib/model/instrument.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib {

// Whether face 1 and face 2 share one model or get one each.
enum class FaceMode { kJoint, kSeparate };
// Camera intrinsics: kAuto = fit them when the camera data span the image
// (the caller decides), kFit = always fit, kFixed = keep model.cameras.
enum class IntrinsicsMode { kAuto, kFit, kFixed };

const char* FaceModeName(FaceMode m);
const char* IntrinsicsModeName(IntrinsicsMode m);

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

struct RunConfig {
  std::string config_path;   // absolute, normalised
  std::string config_dir;    // its folder; relative paths start here
  std::string records_path;  // absolute, "" when the config names no records file
  std::string pixels_path;   // absolute, "" when the config names no pixels file
  ModelSettings model;
  // model.intrinsics kFit sets fit.fit_intrinsics; kAuto leaves it false for
  // the caller to decide from the data.
  FitOptions fit;
  // Present when the config has a `simulate` section. Used only when there
  // are no data files (then it is required).
  std::optional<SimulationOptions> simulate;
  // simulate.truth absent: the caller sets simulate->truth =
  // PaperTruth(PlanNumZooms(simulate->plan)) (libcalib/sim/simulator.h).
  bool truth_from_paper = false;
  std::string render_yaml;  // the `render` section as YAML text; "" when absent
  DiagnoseOptions diagnose;
  std::string output_dir;          // absolute; default <config_dir>/out
  std::vector<std::string> notes;  // things worth a line in the run log
};

// Number of zoom levels a plan uses: the largest zoom + 1.
int PlanNumZooms(const AcquisitionPlan& plan);

// Throws InputError for anything wrong with the file (see above).
RunConfig LoadConfig(const std::string& path);

// The effective config as YAML, every default written out, paths absolute,
// numbers with 17 significant digits: loading it gives the same run
// (--write-config). The simulated truth's rotations are written as Euler
// angles, as the config takes them.
std::string DumpConfig(const RunConfig& config);

}  // namespace rtscalib

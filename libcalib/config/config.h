// The run configuration (SPEC 5; every key is documented in docs/config.md):
// one YAML file -> the library's option structs.
//
// This layer sits above every module whose options it fills (calibrate, fit,
// screen, sim, and api's uncertainty maps) and below the binary; io beneath
// it gives the strict YAML reader and writer. Every section of libcalib is
// read and dumped in this folder, and only here: `simulate` in
// simulate_section.h, every other one in config.cc, with the values they
// share (checked numbers, poses, cameras) in fields.h. A module outside
// libcalib reads its own section through a ConfigSection
// (libcalib/io/config_section.h): `render` (render/settings.h).
//
// Rules:
//   - unknown keys anywhere are errors naming the key path, file and line;
//   - relative paths are relative to the config file's folder;
//   - values are checked where they are read, so each message points at the
//     offending key (negative sigmas, zenith limits out of order, effects not
//     in the catalogue, distortion longer than 14, non-positive image sizes,
//     fit.threads beyond 4 x the machine's hardware threads, simulated plans
//     beyond AcquisitionPlan::Check()'s bounds...).
// The config reads option structs, not the code that uses them: the
// simulated truth of Klug's instrument (PaperTruth, libcalib/sim) is not
// built here; `truth_from_paper` tells the caller to build it.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "libcalib/api/uncertainty_map.h"
#include "libcalib/calibrate/options.h"
#include "libcalib/io/config_section.h"
#include "libcalib/model/angle_unit.h"
#include "libcalib/sim/options.h"

namespace rtscalib {

const char* FaceModeName(FaceMode m);
const char* IntrinsicsModeName(IntrinsicsMode m);

struct RunConfig {
  std::string config_path;   // absolute, normalised
  std::string config_dir;    // its folder; relative paths start here
  std::string records_path;  // absolute, "" when the config names no records file
  std::string pixels_path;   // absolute, "" when the config names no pixels file
  // SPEC 7: a photo session (shots.csv + its images) and the boards in the
  // photos (targets.yaml); absolute, both given or neither.
  std::string shots_path;
  std::string targets_path;
  // data.angle_unit: the unit of phi, theta in records.csv, pixels.csv and
  // shots.csv; the readers convert to radians (libcalib/model/angle_unit.h).
  AngleUnit angle_unit = AngleUnit::kRad;
  int detect_jobs = 1;  // detect.jobs: threads detecting the photos
  // The `model`, `fit`, `diagnose` and `screen` sections: the options of the
  // calibration itself (Calibrate, libcalib/calibrate), passed as they are.
  // fit.max_sigma0 is calibration.checks.max_sigma0
  // (libcalib/calibrate/validate.h).
  CalibrationOptions calibration;
  // Present when the config has a `simulate` section. Used only when there
  // are no data files (then it is required).
  std::optional<SimulationOptions> simulate;
  // simulate.truth absent: the caller sets simulate->truth =
  // PaperTruth(PlanNumZooms(simulate->plan)) (libcalib/sim/simulator.h).
  bool truth_from_paper = false;
  // report.uncertainty_map: the options of the report's projection
  // uncertainty maps (libcalib/api/uncertainty_map.h), passed as they are.
  UncertaintyMapOptions uncertainty_map;
  std::string output_dir;          // absolute; default <config_dir>/out
  std::vector<std::string> notes;  // things worth a line in the run log
};

// Throws InputError for anything wrong with the file (see above). A top-level
// key that is neither a section of this reader nor one of `sections` is an
// unknown key.
RunConfig LoadConfig(const std::string& path, const std::vector<ConfigSection>& sections = {});

// The effective config as YAML, every default written out, paths absolute,
// numbers with 17 significant digits: loading it gives the same run
// (--write-config). The simulated truth's rotations are written as quaternions,
// which read back bit for bit. `sections` as for LoadConfig.
std::string DumpConfig(const RunConfig& config, const std::vector<ConfigSection>& sections = {});

}  // namespace rtscalib

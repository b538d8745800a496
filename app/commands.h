// The subcommands of the rtscalib binary (a flat table in main.cc). Each
// returns the process exit code and reports bad input as one clear message.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "libcalib/model/angle_unit.h"

namespace rtscalib::app {

// The unit an --angle-unit option names (main.cc checks the names already;
// this is for callers of the Run* functions).
inline AngleUnit AngleUnitArg(const std::string& command, const std::string& name) {
  const std::optional<AngleUnit> unit = AngleUnitFromName(name);
  if (!unit) {
    throw std::invalid_argument(command + ": --angle-unit: expected rad, deg or gon, got '" + name +
                                "'");
  }
  return *unit;
}

struct RunArgs {
  std::string config;
  std::string output;        // overrides the config's output folder
  std::string write_config;  // write the effective config here and continue
  bool quiet = false;
  bool diagnose = false;       // `rtscalib diagnose`: diagnosis on, print it instead of the tables
  bool diagnose_auto = false;  // --auto: forward stepwise (diagnose.auto)
  int jobs = 0;                // --jobs: detection threads for data.shots (0 = detect.jobs)
};
int RunCalibration(const RunArgs& args);
// `rtscalib diagnose --config X [--auto]` (app/diagnose_command.cc).
int RunDiagnose(RunArgs args);

struct PredictArgs {
  std::string model;
  std::string records;
  std::string pixels;
  std::string out;
  bool force = false;     // allow replacing an existing --out file
  bool skip_bad = false;  // leave out rows the model cannot predict (listed on stderr)
  // --angle-unit: phi, theta of --records/--pixels (and of --out) in rad, deg
  // or gon (libcalib/model/angle_unit.h), as data.angle_unit of a config.
  std::string angle_unit = "rad";
};
int RunPredict(const PredictArgs& args);

// `rtscalib export --model M --format opencv|urdf|surveyor` (app/export_command.cc).
struct ExportArgs {
  std::string model;
  std::string format;
  std::string out;     // default: the model's folder + /export/
  bool force = false;  // allow replacing existing files
};
int RunExport(const ExportArgs& args);

// `rtscalib detect` (app/detect_command.cc): photos of shots.csv -> pixels.csv.
struct DetectArgs {
  std::string shots;
  std::string targets;
  std::string out;
  int jobs = 1;
  bool keep_unrefined = false;
  bool force = false;  // allow replacing existing output files
  bool quiet = false;
  // --angle-unit: phi, theta of --shots in rad, deg or gon; pixels.csv is
  // written in the same unit.
  std::string angle_unit = "rad";
};
int RunDetect(const DetectArgs& args);

// `rtscalib compare A/model.yaml B/model.yaml [--output DIR]`
// (app/compare_command.cc, docs/compare.md).
struct CompareArgs {
  std::string a, b;    // the two model.yaml files
  std::string output;  // "" = print only
  int cols = 24, rows = 18;
};
int RunCompare(const CompareArgs& args);

// `rtscalib show --output OUT --shot ID [--out DIR]` (app/show_command.cc):
// one photo of a run with its corners and residual arrows, as
// photo_<ID>.{html, vg.json, svg, png} in DIR.
struct ShowArgs {
  std::string output;  // the run's output folder (or one history entry)
  std::string shot;
  std::string out = ".";
  bool force = false;  // allow replacing existing files
};
int RunShow(const ShowArgs& args);

// `rtscalib plan --config X [--output DIR]` or `rtscalib plan --from OUT`
// (app/plan_command.cc, SPEC 8, docs/plan.md): the shots to take, plan.csv
// and plan.json, written without replacing any file that exists.
struct PlanArgs {
  std::string config;
  std::string from;    // an earlier run's output folder: the shots to add
  std::string output;  // overrides the config's output folder
  bool quiet = false;
  // Goals beside the config's plan.goal (the command line wins for a name
  // both give): "NAME=SIGMA" in the constant's report unit, and the worst
  // projection sigma [px] (0: the config's).
  std::vector<std::string> goals;
  double projection_px = 0;
};
int RunPlan(const PlanArgs& args);

}  // namespace rtscalib::app

// rtscalib: calibration of robotic total stations. One binary, a flat table of
// subcommands; each parses straight into the library's option structs.
#include <CLI/CLI.hpp>
#include <iostream>

#include "app/commands.h"

int main(int argc, char** argv) {
  CLI::App app{"rtscalib - kinematic and camera calibration of robotic total stations"};
  app.require_subcommand(0, 1);

  rtscalib::app::RunArgs run;
  app.add_option("--config", run.config, "run the pipeline a config describes (configs/*.yaml)");
  app.add_option("--output", run.output, "output folder (overrides the config's `output`)");
  app.add_option("--write-config", run.write_config,
                 "also write the effective config to this new file");
  app.add_flag("--quiet", run.quiet, "no progress lines on stderr");

  rtscalib::app::PredictArgs predict;
  CLI::App* pred =
      app.add_subcommand("predict", "predict records (x, y, z) or pixels (u, v) with a model");
  pred->add_option("--model", predict.model, "model.yaml written by a run")->required();
  pred->add_option("--records", predict.records, "records.csv whose x, y, z are predicted");
  pred->add_option("--pixels", predict.pixels, "pixels.csv whose u, v are predicted");
  pred->add_option("--out", predict.out, "output CSV")->required();
  pred->add_flag("--force", predict.force, "replace --out if it exists");
  pred->add_flag("--skip-bad", predict.skip_bad,
                 "leave out rows the model cannot predict and list them (default: stop at the "
                 "first, naming its line)");

  rtscalib::app::RunArgs diag;
  CLI::App* dg = app.add_subcommand(
      "diagnose", "run the pipeline and rank the catalogue effects the model lacks, best first");
  dg->add_option("--config", diag.config, "the run's config")->required();
  dg->add_option("--output", diag.output, "output folder (overrides the config's `output`)");
  dg->add_flag("--auto", diag.diagnose_auto,
               "add significant effects one at a time and refit (the ladder)");
  dg->add_flag("--quiet", diag.quiet, "no progress lines on stderr");

  rtscalib::app::ExportArgs exp;
  CLI::App* ex = app.add_subcommand(
      "export", "write a model for other tools: OpenCV cameras, a URDF, surveyor's constants");
  ex->add_option("--model", exp.model, "model.yaml written by a run")->required();
  ex->add_option("--format", exp.format, "opencv | urdf | surveyor")
      ->required()
      ->check(CLI::IsMember({"opencv", "urdf", "surveyor"}));
  ex->add_option("--out", exp.out, "output folder (default: the model's folder + /export/)");
  ex->add_flag("--force", exp.force, "replace files that exist");

  rtscalib::app::DetectArgs detect;
  CLI::App* det = app.add_subcommand(
      "detect", "detect the AprilTags of targets.yaml's boards in the photos of shots.csv");
  det->add_option("--shots", detect.shots, "shots.csv: one photo per row (SPEC 7)")->required();
  det->add_option("--targets", detect.targets, "targets.yaml: the boards")->required();
  det->add_option("--out", detect.out, "pixels.csv to write (and <out>.summary.csv)")->required();
  det->add_option("--jobs", detect.jobs, "detection threads")->check(CLI::PositiveNumber);
  det->add_flag("--keep-unrefined", detect.keep_unrefined,
                "keep tags whose sub-pixel refinement failed (libapriltag's corners)");
  det->add_flag("--force", detect.force, "replace --out if it exists");
  det->add_flag("--quiet", detect.quiet, "no progress lines on stderr");

  CLI11_PARSE(app, argc, argv);
  try {
    if (pred->parsed()) return rtscalib::app::RunPredict(predict);
    if (dg->parsed()) return rtscalib::app::RunDiagnose(diag);
    if (ex->parsed()) return rtscalib::app::RunExport(exp);
    if (det->parsed()) return rtscalib::app::RunDetect(detect);
    if (run.config.empty()) {
      std::cerr << app.help();
      return 2;
    }
    return rtscalib::app::RunCalibration(run);
  } catch (const std::exception& e) {
    std::cerr << "rtscalib: error: " << e.what() << "\n";
    return 1;
  }
}

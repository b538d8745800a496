// rtscalib: calibration of robotic total stations. One binary, a flat table of
// subcommands; each parses straight into the library's option structs.
#include <CLI/CLI.hpp>
#include <iostream>
#include <stdexcept>

#include "app/commands.h"
#include "libcalib/calibrate/validate.h"
#include "libcalib/extract/options.h"
#include "libcalib/io/safe_write.h"
#include "libcalib/text/errors.h"
#include "libcalib/text/number_text.h"

namespace {

// Exit codes (docs/conventions.md section 5; also in --help).
constexpr int kExitInput = 1;     // bad config or data, a file that cannot be read or written
constexpr int kExitUsage = 2;     // bad command line
constexpr int kExitFit = 3;       // the data do not support a model (CalibrationFailure)
constexpr int kExitInternal = 4;  // anything else: a bug in rtscalib

constexpr const char* kExitCodes =
    "Exit codes:\n"
    "  0  success\n"
    "  1  input error: bad config or data (file:line, key, expected, got), data the\n"
    "     extraction cannot use, a file that cannot be read or written\n"
    "  2  usage error: bad command line\n"
    "  3  fit failure: the fit's outcome is not finite, not converged or far beyond\n"
    "     the stated sigmas; the worst rows are named; nothing is published\n"
    "  4  internal error: an unexpected exception (please report it)\n";

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rtscalib - kinematic and camera calibration of robotic total stations"};
  app.require_subcommand(0, 1);
  app.footer(kExitCodes);

  rtscalib::app::RunArgs run;
  app.add_option("--config", run.config, "run the pipeline a config describes (configs/*.yaml)");
  app.add_option("--output", run.output, "output folder (overrides the config's `output`)");
  app.add_option("--write-config", run.write_config,
                 "also write the effective config to this new file");
  app.add_flag("--quiet", run.quiet, "no progress lines on stderr");
  app.add_option("--jobs", run.jobs,
                 "threads detecting the photos of data.shots (overrides detect.jobs)")
      ->check(CLI::PositiveNumber);

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
  pred->add_option("--angle-unit", predict.angle_unit,
                   "unit of phi, theta in the input (and the output): rad | deg | gon, as the "
                   "config's data.angle_unit (default rad)")
      ->check(CLI::IsMember({"rad", "deg", "gon"}));

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
  det->add_option("--angle-unit", detect.angle_unit,
                  "unit of phi, theta in shots.csv (pixels.csv is written in the same unit): rad "
                  "| deg | gon, as the config's data.angle_unit (default rad)")
      ->check(CLI::IsMember({"rad", "deg", "gon"}));

  rtscalib::app::CompareArgs cmp;
  CLI::App* cm = app.add_subcommand(
      "compare",
      "compare two calibrations: projection differences per zoom, parameter differences / sigma");
  cm->add_option("a", cmp.a, "first model.yaml")->required();
  cm->add_option("b", cmp.b, "second model.yaml")->required();
  cm->add_option("--output", cmp.output,
                 "also write compare.txt, compare.json and figures/ into this folder");

  rtscalib::app::PlanArgs plan;
  CLI::App* pl = app.add_subcommand(
      "plan", "plan a session before it is measured: the shots that reach the sigmas asked for");
  pl->add_option("--config", plan.config, "config with a `plan` section (configs/plan.yaml)");
  pl->add_option("--from", plan.from,
                 "an earlier run's output folder: propose the shots to add where its diagnosis "
                 "found an effect it could not determine");
  pl->add_option("--output", plan.output,
                 "folder for plan.csv, plan.json and figures/ (default: the config's output)");
  pl->add_option("--goal", plan.goals,
                 "a constant's sigma to reach, NAME=SIGMA in its report unit (cam[0].fx=0.3, "
                 "hz_eccentricity.e=1); repeatable; beside the config's plan.goal.sigmas")
      ->check(CLI::Validator(
          [](std::string& goal) -> std::string {
            const size_t eq = goal.find('=');
            const std::optional<double> sigma =
                eq == std::string::npos ? std::nullopt
                                        : rtscalib::ParseFiniteDouble(goal.substr(eq + 1));
            if (eq == 0 || !sigma || !(*sigma > 0)) {
              return "expected NAME=SIGMA with a sigma > 0 (cam[0].fx=0.3), got '" + goal + "'";
            }
            return "";
          },
          "NAME=SIGMA"));
  pl->add_option("--projection-px", plan.projection_px,
                 "the worst projection sigma per zoom to reach [px] (plan.goal.projection_px)")
      ->check(CLI::PositiveNumber);
  pl->add_flag("--quiet", plan.quiet, "no summary on stdout");

  rtscalib::app::ShowArgs show;
  CLI::App* sh = app.add_subcommand(
      "show", "draw one photo of a run with its corners and residual arrows (photo_<ID>.html/png)");
  sh->add_option("--output", show.output, "the run's output folder (or one history entry)")
      ->required();
  sh->add_option("--shot", show.shot, "shot id (shots.csv; default the image file's stem)")
      ->required();
  sh->add_option("--out", show.out, "folder for photo_<ID>.{html, vg.json, svg, png} (default .)");
  sh->add_flag("--force", show.force, "replace files that exist");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help is a ParseError with exit code 0.
    return app.exit(e) == 0 ? 0 : kExitUsage;
  }
  try {
    if (pred->parsed()) return rtscalib::app::RunPredict(predict);
    if (dg->parsed()) return rtscalib::app::RunDiagnose(diag);
    if (ex->parsed()) return rtscalib::app::RunExport(exp);
    if (det->parsed()) return rtscalib::app::RunDetect(detect);
    if (cm->parsed()) return rtscalib::app::RunCompare(cmp);
    if (sh->parsed()) return rtscalib::app::RunShow(show);
    if (pl->parsed()) return rtscalib::app::RunPlan(plan);
    if (run.config.empty()) {
      std::cerr << app.help();
      return kExitUsage;
    }
    return rtscalib::app::RunCalibration(run);
  } catch (const rtscalib::CalibrationFailure& e) {
    std::cerr << "rtscalib: calibration failed (" << rtscalib::FailureKindName(e.kind)
              << "): " << e.what() << "\n";
    return kExitFit;
  } catch (const rtscalib::InputError& e) {
    std::cerr << "rtscalib: error: " << e.what() << "\n";
    return kExitInput;
  } catch (const rtscalib::WriteError& e) {
    std::cerr << "rtscalib: error: " << e.what() << "\n";
    return kExitInput;
  } catch (const rtscalib::ExtractionError& e) {
    std::cerr << "rtscalib: error: " << e.what() << "\n";
    return kExitInput;
  } catch (const std::invalid_argument& e) {
    // The library's and the commands' rejections of arguments and data.
    std::cerr << "rtscalib: error: " << e.what() << "\n";
    return kExitInput;
  } catch (const std::exception& e) {
    std::cerr << "rtscalib: internal error: " << e.what() << "\n";
    return kExitInternal;
  }
}

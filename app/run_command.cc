#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>

#include "app/commands.h"
#include "app/diagnosis_report.h"
#include "app/figures.h"
#include "app/output_folder.h"
#include "app/pipeline.h"
#include "app/plot/vega.h"
#include "app/progress.h"
#include "app/report_html.h"
#include "app/reports.h"
#include "libcalib/config/config.h"
#include "libcalib/fit/parameter_layout.h"
#include "libcalib/io/covariance_io.h"
#include "libcalib/io/model_io.h"
#include "libcalib/io/records.h"
#include "libcalib/io/safe_write.h"

namespace rtscalib::app {
namespace {

// Everything a run writes, into its own history entry; then publishing.
int RunInto(const RunArgs& args, RunSettings settings, OutputFolder& out, Progress& progress) {
  RunConfig& config = settings.config;
  out.Write("config.yaml", DumpRunSettings(settings));

  if (args.diagnose) config.calibration.diagnose.enabled = true;
  if (args.diagnose_auto) config.calibration.diagnose.auto_add = true;
  // The figures need the calibrated model, its residuals and uncertainty
  // maps but not its diagnosis. Their renderer (app/plot/vega.h) starts now,
  // beside the reading of the observations, so that its threads wait with
  // librsvg loaded when the model is fitted; each spec goes to it as soon as
  // it is made, the uncertainty maps' once the maps are computed, and
  // they are drawn on threads of their own while the diagnosis runs and
  // the model and the reports are written. report.json and report.html,
  // which list the figure files, come last: the run ends once its figures
  // are drawn, and says how long it waited for them.
  using Clock = std::chrono::steady_clock;
  std::vector<Figure> figures;
  std::vector<std::vector<std::string>> figure_files;
  std::string figures_note;
  Clock::time_point figures_start;
  nlohmann::json history;  // earlier runs, for the figures and report.json
  VegaRenderer renderer;
  // Declared after the renderer: ends (waits for) the drawing before it.
  std::optional<FigureFiles> files;
  size_t made = 0;
  // The histograms (a small figure) wait for the uncertainty maps'
  // figures: the last figure drawn, which the run's end waits for, is then
  // a small one. Every other figure is drawn as soon as it is made.
  std::optional<std::pair<size_t, Figure>> small;
  auto hand_over = [&](Figure f) {
    if (f.section == "histograms" && !small) {
      small.emplace(made++, std::move(f));
    } else {
      files->Add(made++, std::move(f));
    }
  };
  const PipelineResult result = RunPipeline(
      settings, out.run_dir(), &progress,
      [&](const PipelineResult& fitted) {
        figures_start = Clock::now();
        history = HistoryJson(out);
        files.emplace(out.RunFile("figures"), &renderer);
        MakeFigures(fitted, history, hand_over);
      },
      [&](const PipelineResult& mapped) {
        if (!files) return;
        for (Figure& f : MakeUncertaintyFigures(mapped)) files->Add(made++, std::move(f));
        if (small) files->Add(small->first, std::move(small->second));
        small.reset();
        files->End();
      });
  progress.Step("writing the model and the reports");
  if (result.simulated) {
    WriteFileAtomicWith(out.RunFile("records.csv"),
                        [&](const std::string& tmp) {
                          WriteRecords(tmp, result.obs.records, AngleUnit::kRad,
                                       result.obs.record_covariates);
                        });
    if (!result.obs.pixels.empty()) {
      WriteFileAtomicWith(out.RunFile("pixels.csv"),
                          [&](const std::string& tmp) {
                            WritePixels(tmp, result.obs.pixels, AngleUnit::kRad, {},
                                        result.obs.pixel_covariates);
                          });
    }
    if (result.truth) {
      WriteFileAtomicWith(out.RunFile("truth.yaml"), [&](const std::string& tmp) {
        WriteModelYaml(tmp, *result.truth, {{"what", "simulated truth"}});
      });
    }
  }
  ModelMetadata meta = {{"program", "rtscalib 0.1.0"},
                        {"config", config.config_path},
                        {"run", out.run().name},
                        {"records", result.obs.records_source},
                        {"pixels", result.obs.pixels_source}};
  WriteFileAtomicWith(out.RunFile("model.yaml"), [&](const std::string& tmp) {
    WriteModelYaml(tmp, result.calibration.model, meta);
    // Where each zoom's width/height came from (SPEC 7): a YAML comment, so
    // that model.yaml's readers are unaffected.
    std::ofstream f(tmp, std::ios::app);
    for (const auto& [z, source] : result.calibration.size_source) {
      f << "# cameras[" << z << "] size_source: " << source
        << (source == "estimated" ? " (width/height guessed: no photos, no model.cameras)" : "")
        << "\n";
    }
    f.close();
    if (!f) throw std::runtime_error("could not write " + tmp);
  });
  // The full parameter covariance beside model.yaml (docs/library.md): the
  // API's uncertainties use it, correlations included.
  const InstrumentModel& fitted = result.calibration.model;
  if (fitted.sigmas.covariance.rows() == LayoutSize(ParameterLayout(fitted)) &&
      fitted.sigmas.covariance.rows() > 0) {
    WriteFileAtomicWith(out.RunFile("covariance.yaml"),
                        [&](const std::string& tmp) { WriteCovarianceYaml(tmp, fitted); });
  } else {
    progress.Note("no full parameter covariance (the fit computed none): no covariance.yaml");
  }
  nlohmann::json report = ReportJson(config, result, out, history);
  out.Write("residuals.csv", ResidualsCsv(result));
  const std::string text = ReportText(config, result) +
                           HistoryText(report.value("history", nlohmann::json::array())) + "\n" +
                           DiagnosisText(result.calibration);
  out.Write("report.txt", text);
  if (files) {
    const Clock::time_point waited = Clock::now();
    figure_files = files->Finish(&figures_note, &figures);
    const Clock::time_point figures_end = files->drawn_at();
    char drawn[160];
    std::snprintf(drawn, sizeof drawn,
                  "drew %zu figures in %.2f s, beside the diagnosis and the reports; waited "
                  "%.2f s for them",
                  figures.size(),
                  std::chrono::duration<double>(figures_end - figures_start).count(),
                  std::chrono::duration<double>(std::max(waited, figures_end) - waited).count());
    progress.Note(drawn);
    if (!figures_note.empty()) progress.Note(figures_note);
  }
  report["figures"] = FiguresJson(figures, figure_files, figures_note);
  out.Write("report.json", report.dump(2) + "\n");
  out.Write("report.html", ReportHtml(config, result, report, figures));
  out.MarkComplete();
  const std::vector<std::string> kept = out.Publish();
  progress.Done();
  std::cout << (args.diagnose ? DiagnosisText(result.calibration) : text);
  std::cout << "\nwritten: " << out.run_dir()
            << "/{model.yaml, covariance.yaml, report.json, residuals.csv, report.txt, "
               "report.html, figures/}\nshown at the top of "
            << out.root() << " (symlinks through " << out.root() << "/latest)\n";
  for (const std::string& f : kept) {
    std::cout << "kept your file " << out.root() << "/figures/" << f << "; this run's " << f
              << " is only in " << out.run_dir() << "/figures/\n";
  }
  return 0;
}

}  // namespace

int RunCalibration(const RunArgs& args) {
  RunSettings settings = LoadRunSettings(args.config);
  RunConfig& config = settings.config;
  if (!args.output.empty()) config.output_dir = std::filesystem::absolute(args.output).string();
  if (args.jobs > 0) config.detect_jobs = args.jobs;
  if (!args.write_config.empty()) {
    if (std::filesystem::exists(args.write_config)) {
      throw std::invalid_argument("--write-config: '" + args.write_config +
                                  "' exists; rtscalib does not overwrite files you have");
    }
    WriteFileAtomic(args.write_config, DumpRunSettings(settings), Existing::kKeep);
  }
  Progress progress(args.quiet);
  OutputFolder out(config.output_dir);
  progress.Note("output: " + out.root() + " (this run: history/" + out.run().name + ")");
  try {
    return RunInto(args, settings, out, progress);
  } catch (const std::exception& e) {
    out.MarkFailed(e.what());
    throw;
  } catch (...) {
    out.MarkFailed("an exception that is not a std::exception");
    throw;
  }
}

}  // namespace rtscalib::app

#include <filesystem>
#include <fstream>
#include <iostream>

#include "app/commands.h"
#include "app/diagnosis_report.h"
#include "app/output_folder.h"
#include "app/pipeline.h"
#include "app/progress.h"
#include "app/report_html.h"
#include "app/reports.h"
#include "libcalib/io/config.h"
#include "libcalib/io/model_io.h"
#include "libcalib/io/records.h"

namespace rtscalib::app {
namespace {

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write '" + path + "'");
  out << text;
}

}  // namespace

int RunCalibration(const RunArgs& args) {
  RunSettings settings = LoadRunSettings(args.config);
  RunConfig& config = settings.config;
  if (!args.output.empty()) config.output_dir = std::filesystem::absolute(args.output).string();
  if (!args.write_config.empty()) {
    if (std::filesystem::exists(args.write_config)) {
      throw std::runtime_error("--write-config: '" + args.write_config +
                               "' exists; rtscalib does not overwrite files you have");
    }
    WriteText(args.write_config, DumpRunSettings(settings));
  }
  Progress progress(args.quiet);
  OutputFolder out(config.output_dir);
  progress.Note("output: " + out.root() + " (this run: history/" + out.run().name + ")");
  WriteText(out.RunFile("config.yaml"), DumpRunSettings(settings));

  if (args.diagnose) config.diagnose.enabled = true;
  if (args.diagnose_auto) config.diagnose.auto_add = true;
  const PipelineResult result = RunPipeline(settings, out.run_dir(), &progress);

  progress.Step("writing the model and the reports");
  if (result.simulated) {
    WriteRecords(out.RunFile("records.csv"), result.obs.records);
    if (!result.obs.pixels.empty()) WritePixels(out.RunFile("pixels.csv"), result.obs.pixels);
    if (result.truth)
      WriteModelYaml(out.RunFile("truth.yaml"), *result.truth, {{"what", "simulated truth"}});
  }
  ModelMetadata meta = {{"program", "rtscalib 0.1.0"},
                        {"config", config.config_path},
                        {"run", out.run().name},
                        {"records", result.obs.records_source},
                        {"pixels", result.obs.pixels_source}};
  WriteModelYaml(out.RunFile("model.yaml"), result.calibration.model, meta);
  const nlohmann::json report = ReportJson(config, result, out);
  WriteText(out.RunFile("report.json"), report.dump(2));
  WriteReportHtml(config, result, report, out);
  const std::string text = ReportText(config, result) + "\n" + DiagnosisText(result.calibration);
  WriteText(out.RunFile("report.txt"), text);
  out.Publish({"model.yaml", "report.json", "report.txt", "report.html", "figures"});
  progress.Done();
  std::cout << (args.diagnose ? DiagnosisText(result.calibration) : text);
  std::cout << "\nwritten: " << out.root()
            << "/{model.yaml, report.json, report.txt, report.html, figures/}\n";
  return 0;
}

}  // namespace rtscalib::app

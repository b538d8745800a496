// The demo's photo session as a user runs it (README, "Speed"): once, in a
// temporary copy of the repository's layout, `rtscalib --config
// configs/zoom3.yaml` renders its 92 photos (3 zooms at fx 1500, 3000 and 6000
// px, 4 boards of 48 tag36h11, 1280 x 960, supersample 2, sensor noise of 1
// grey level) into out/zoom3/latest/photos/; then
//   BM_PhotoSessionDetect/jobs:N/noise_threshold:T  detects that folder
//                                 (detect::DetectPhotos, as data.shots does)
//                                 with N threads; T = 0: libapriltag's own
//                                 segmentation threshold of 5 grey levels
//                                 instead of 10 noise sigmas (detector.h);
//   BM_PhotoSessionRun            the whole `rtscalib --config
//                                 configs/photos.yaml` in process (the
//                                 shipped config: detection with 2 jobs,
//                                 calibration, diagnosis, reports);
//   BM_PhotoPng/level:L/part:P    one photo of that folder as PNG at
//                                 RenderShotsOptions::png_compression L
//                                 (-1: the render stage's speed setting),
//                                 encoded (P = 0) or decoded (P = 1), per
//                                 photo, cycling through the folder;
//   BM_OneBoardCalibrate/gross:G  the one-board session's calibration
//                                 without its diagnosis, gross-error
//                                 handling off (0) or on (1).
//
//   build/bench/photo_session_benchmark --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <unistd.h>

#include <filesystem>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <string>

#include "app/commands.h"
#include "app/pipeline.h"
#include "app/progress.h"
#include "bench/quiet_stdout.h"
#include "detect/photos.h"
#include "libcalib/io/shots.h"
#include "libcalib/io/targets_io.h"
#include "render/shots.h"

namespace rtscalib::app {
namespace {

namespace fs = std::filesystem;

using bench::QuietStdout;

// <tmp>/configs/{zoom3,photos}.yaml copied from the source tree, and the
// demo's output in <tmp>/out/zoom3 (the configs' relative paths hold).
class DemoFolder {
 public:
  DemoFolder() {
    char dir[] = "/tmp/rtscalib-photo-session-XXXXXX";
    if (::mkdtemp(dir) == nullptr) throw std::runtime_error("mkdtemp failed");
    root_ = dir;
    fs::create_directories(root_ / "configs");
    for (const char* name : {"zoom3.yaml", "photos.yaml"}) {
      fs::copy_file(fs::path(RTSCALIB_SOURCE_DIR) / "configs" / name, root_ / "configs" / name);
    }
    RunArgs demo;
    demo.config = (root_ / "configs" / "zoom3.yaml").string();
    demo.quiet = true;
    const QuietStdout quiet;
    if (RunCalibration(demo) != 0) throw std::runtime_error("the zoom3 demo failed");
  }
  ~DemoFolder() { fs::remove_all(root_); }

  fs::path root() const { return root_; }
  fs::path photos() const { return root_ / "out" / "zoom3" / "latest" / "photos"; }

 private:
  fs::path root_;
};

const DemoFolder& Demo() {
  static const DemoFolder demo;
  return demo;
}

void BM_PhotoSessionDetect(benchmark::State& state) {
  const DemoFolder& demo = Demo();
  const std::map<std::string, int> families = detect::DetectableCodeCounts();
  const TargetScene targets = ReadTargets((demo.photos() / "targets.yaml").string(), &families);
  const ShotsFile shots = ReadShots((demo.photos() / "shots.csv").string());
  detect::PhotoDetectionOptions options;
  options.jobs = static_cast<int>(state.range(0));
  if (state.range(1) == 0) options.detector.segmentation_noise_multiple = 0;
  options.progress = false;
  size_t tags = 0;
  for (auto _ : state) {
    const detect::PhotoDetectionResult r = detect::DetectPhotos(shots, targets, options);
    tags = 0;
    for (const detect::PhotoDetection& p : r.photos) tags += p.tags.size();
  }
  state.counters["photos"] = static_cast<double>(shots.shots.size());
  state.counters["tags"] = static_cast<double>(tags);
  state.counters["images/s"] = benchmark::Counter(
      static_cast<double>(state.iterations() * shots.shots.size()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_PhotoSessionDetect)
    ->ArgNames({"jobs", "noise_threshold"})
    ->Args({1, 0})
    ->Args({1, 1})
    ->Args({2, 0})
    ->Args({2, 1})
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

void BM_PhotoSessionRun(benchmark::State& state) {
  const DemoFolder& demo = Demo();
  RunArgs run;
  run.config = (demo.root() / "configs" / "photos.yaml").string();
  run.quiet = true;
  const QuietStdout quiet;
  for (auto _ : state) {
    if (RunCalibration(run) != 0) {
      state.SkipWithError("rtscalib --config configs/photos.yaml failed");
      return;
    }
  }
}
BENCHMARK(BM_PhotoSessionRun)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

void BM_PhotoPng(benchmark::State& state) {
  const DemoFolder& demo = Demo();
  const int level = static_cast<int>(state.range(0));
  const bool decode = state.range(1) != 0;
  static const std::vector<cv::Mat> photos = [&] {
    std::vector<cv::Mat> out;
    for (const PhotoShot& s : ReadShots((demo.photos() / "shots.csv").string()).shots) {
      out.push_back(cv::imread(s.image_path, cv::IMREAD_UNCHANGED));
    }
    return out;
  }();
  std::vector<std::vector<unsigned char>> encoded(photos.size());
  double bytes = 0;
  for (size_t i = 0; i < photos.size(); ++i) {
    if (!render::EncodePhotoPng(photos[i], level, &encoded[i])) {
      state.SkipWithError("OpenCV could not encode a photo");
      return;
    }
    bytes += static_cast<double>(encoded[i].size());
  }
  size_t i = 0;
  std::vector<unsigned char> out;
  for (auto _ : state) {
    if (decode) {
      benchmark::DoNotOptimize(cv::imdecode(encoded[i], cv::IMREAD_UNCHANGED));
    } else {
      render::EncodePhotoPng(photos[i], level, &out);
      benchmark::DoNotOptimize(out.data());
    }
    i = (i + 1) % photos.size();
  }
  state.counters["kB/photo"] = bytes / static_cast<double>(photos.size()) / 1000.0;
}
BENCHMARK(BM_PhotoPng)
    ->ArgNames({"level", "part"})
    ->Args({-1, 0})
    ->Args({1, 0})
    ->Args({-1, 1})
    ->Args({1, 1})
    ->Unit(benchmark::kMillisecond);

// The one-board session (configs/one_board.yaml: 136 photos, 22,888
// corners, no records), rendered and detected once; then its calibration
// with the gross-error handling on (gross:1) and off (gross:0). Its renders
// hold mis-detected corners, so the robust fit from the start runs, and
// keeps each photo in one residual block (libcalib/fit/observation_loss.h):
// the difference of the two is what finding them costs.
struct OneBoardSession {
  OneBoardSession() {
    char dir[] = "/tmp/rtscalib-one-board-XXXXXX";
    if (::mkdtemp(dir) == nullptr) throw std::runtime_error("mkdtemp failed");
    root = dir;
    settings = LoadRunSettings(std::string(RTSCALIB_SOURCE_DIR) + "/configs/one_board.yaml");
    Progress quiet(true);
    PipelineResult r;
    obs = LoadObservations(settings, root.string(), &r, &quiet);
  }
  ~OneBoardSession() { fs::remove_all(root); }
  fs::path root;
  RunSettings settings;
  Observations obs;
};

void BM_OneBoardCalibrate(benchmark::State& state) {
  static const OneBoardSession session;
  CalibrationOptions options = session.settings.config.calibration;
  options.diagnose.enabled = false;
  options.fit.gross_errors.enabled = state.range(0) != 0;
  size_t gross = 0;
  for (auto _ : state) gross = Calibrate(session.obs, options).gross_rows.size();
  state.counters["corners"] = static_cast<double>(session.obs.pixels.size());
  state.counters["gross_rows"] = static_cast<double>(gross);
}
BENCHMARK(BM_OneBoardCalibrate)
    ->ArgName("gross")
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

}  // namespace
}  // namespace rtscalib::app

BENCHMARK_MAIN();

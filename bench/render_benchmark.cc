// Rendering and detection throughput at 1280 x 960 (docs/rendering.md lists
// the measured figures). Runs headless: an Xvfb is started when DISPLAY is
// unset.
//
//   build/bench/render_benchmark --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <Eigen/Geometry>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <opencv2/imgcodecs.hpp>

#include "detect/detector.h"
#include "detect/photos.h"
#include "libcalib/io/shots.h"
#include "render/headless.h"
#include "render/scene_renderer.h"
#include "render/shots.h"

namespace rtscalib::render {
namespace {

HeadlessDisplay& Display() {
  static HeadlessDisplay display;
  return display;
}

// A 5 x 7 board of 8 cm tag36h11 2 m in front of a 1280 x 960 camera with the
// distortion of the accuracy tests, seen slightly from the side.
struct Fixture {
  TargetScene scene;
  CameraTool cam;
  Rigid3 pose;

  Fixture() {
    TagBoard b;
    b.rows = 5;
    b.cols = 7;
    const double w = b.cols * b.tag_size + (b.cols - 1) * b.spacing;
    const double h = b.rows * b.tag_size + (b.rows - 1) * b.spacing;
    b.ref_from_board.translation = Eigen::Vector3d(-w / 2, -h / 2, 2.0);
    scene.boards.push_back(b);
    cam.intrinsics = {1000.0, 1000.0, 640.3, 479.6};
    cam.distortion[kK1] = -0.1;
    cam.distortion[kK2] = 0.05;
    cam.distortion[kP1] = 1e-4;
    pose.rotation = Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY()).toRotationMatrix();
    pose.translation = Eigen::Vector3d(0.2, 0.0, 0.0);
  }
};

void BM_Render(benchmark::State& state) {
  Display();
  Fixture f;
  RenderOptions options;
  options.supersample = static_cast<int>(state.range(0));
  options.noise_sigma = state.range(1) != 0 ? 2.0 : 0.0;
  SceneRenderer renderer(f.scene, options);
  renderer.Render(f.pose, f.cam);  // distortion map and texture upload, once
  std::uint64_t seed = 0;
  for (auto _ : state) {
    Rigid3 pose = f.pose;
    pose.translation.x() += 1e-4 * (seed % 16);  // a new pose every time
    benchmark::DoNotOptimize(renderer.Render(pose, f.cam, ++seed).data);
  }
  state.counters["images/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Render)
    ->ArgNames({"supersample", "noise"})
    ->Args({1, 0})
    ->Args({2, 0})
    ->Args({2, 1})
    ->Args({3, 0})
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()  // llvmpipe and OpenCV threads included
    ->UseRealTime();

// A camera that refocuses (SPEC 4.1): every photo has its own intrinsics (fx
// 1 ppm longer each time), so the renderer builds the distortion map of each
// photo instead of reusing the last one, as the render stage does for a
// session with focus in its truth.
void BM_RenderRefocusing(benchmark::State& state) {
  Display();
  Fixture f;
  RenderOptions options;
  options.supersample = static_cast<int>(state.range(0));
  SceneRenderer renderer(f.scene, options);
  renderer.Render(f.pose, f.cam);  // texture upload, once
  std::uint64_t seed = 0;
  CameraTool cam = f.cam;
  for (auto _ : state) {
    cam.intrinsics[0] *= 1.000001;
    benchmark::DoNotOptimize(renderer.Render(f.pose, cam, ++seed).data);
  }
  state.counters["images/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_RenderRefocusing)
    ->ArgNames({"supersample"})
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

void BM_Detect(benchmark::State& state) {
  Display();
  Fixture f;
  SceneRenderer renderer(f.scene);
  const cv::Mat img = renderer.Render(f.pose, f.cam);
  detect::DetectorOptions options;
  options.threads = static_cast<int>(state.range(0));
  options.refine_corners = state.range(1) != 0;
  detect::TagDetector detector(options);
  size_t found = 0;
  for (auto _ : state) found = detector.Detect(img).size();
  state.counters["tags"] = static_cast<double>(found);
  state.counters["images/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Detect)
    ->ArgNames({"threads", "refine"})
    ->Args({1, 0})
    ->Args({1, 1})
    ->Args({2, 1})
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()  // llvmpipe and OpenCV threads included
    ->UseRealTime();

// A user's photo folder read back and detected (detect/photos.h, as
// `rtscalib detect` and `data.shots` do): 16 PNG photos of the board (8-bit
// grey, from slightly different poses) at 1280 x 960 (size 0) or
// 2592 x 1944 (size 1, a 5 MP camera: the same view at 2.025x the focal
// length), decoded and detected by `jobs` threads.
void BM_DetectPhotos(benchmark::State& state) {
  Display();
  Fixture f;
  const bool large = state.range(0) != 0;
  if (large) {
    const double k = 2592.0 / 1280.0;
    f.cam.width = 2592;
    f.cam.height = 1944;
    f.cam.intrinsics = {1000.0 * k, 1000.0 * k, 1295.7, 971.8};
  }
  char dir[] = "/tmp/rtscalib-bench-XXXXXX";
  if (::mkdtemp(dir) == nullptr) {
    state.SkipWithError("mkdtemp failed");
    return;
  }
  {
    SceneRenderer renderer(f.scene);
    std::ofstream csv(std::string(dir) + "/shots.csv");
    csv << "face,zoom,phi,theta,image\n";
    for (int i = 0; i < 16; ++i) {
      Rigid3 pose = f.pose;
      pose.translation.x() += 0.002 * i;
      const std::string name = "p" + std::to_string(i) + ".png";
      cv::imwrite(std::string(dir) + "/" + name, renderer.Render(pose, f.cam, i + 1));
      csv << "1,0,0.1,1.5," << name << "\n";
    }
  }
  const ShotsFile shots = ReadShots(std::string(dir) + "/shots.csv");
  detect::PhotoDetectionOptions options;
  options.jobs = static_cast<int>(state.range(1));
  options.progress = false;
  size_t tags = 0;
  for (auto _ : state) {
    const detect::PhotoDetectionResult r = detect::DetectPhotos(shots, f.scene, options);
    tags = 0;
    for (const detect::PhotoDetection& p : r.photos) tags += p.tags.size();
  }
  std::filesystem::remove_all(dir);
  state.counters["tags"] = static_cast<double>(tags);
  state.counters["images/s"] = benchmark::Counter(
      static_cast<double>(state.iterations() * shots.shots.size()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_DetectPhotos)
    ->ArgNames({"5MP", "jobs"})
    ->Args({0, 1})
    ->Args({0, 2})
    ->Args({1, 1})
    ->Args({1, 2})
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

// RenderShots of `shots` into a temporary folder, `state.range(0)` jobs;
// `scenes` is one TargetScene or the PlacedScenes of a moved board.
template <typename Scenes>
void TimeRenderShots(benchmark::State& state, const Scenes& scenes,
                     const std::vector<Shot>& shots) {
  char dir[] = "/tmp/rtscalib-bench-XXXXXX";
  if (::mkdtemp(dir) == nullptr) {
    state.SkipWithError("mkdtemp failed");
    return;
  }
  RenderShotsOptions options;
  options.out_dir = dir;
  options.jobs = static_cast<int>(state.range(0));
  options.progress = false;
  for (auto _ : state) RenderShots(scenes, shots, options);
  std::filesystem::remove_all(dir);
  state.counters["images/s"] = benchmark::Counter(
      static_cast<double>(state.iterations() * shots.size()), benchmark::Counter::kIsRate);
}

// The whole shot pipeline: render, encode and write 16 PNGs, in `jobs`
// worker processes (fork; each worker sets up its own renderer per call).
void BM_RenderShots(benchmark::State& state) {
  Display();
  Fixture f;
  std::vector<Shot> shots;
  for (int i = 0; i < 16; ++i) {
    Shot s;
    s.id = "b" + std::to_string(i);
    s.cam = f.cam;
    s.ref_from_cam = f.pose;
    s.ref_from_cam.translation.x() += 0.002 * i;
    shots.push_back(s);
  }
  TimeRenderShots(state, f.scene, shots);
}
BENCHMARK(BM_RenderShots)
    ->ArgNames({"jobs"})
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

// One board moved to four placements (SPEC 7.1), 16 shots in the
// simulator's order (the placement changes from shot to shot): one window
// per worker holds all four scenes.
void BM_RenderShotsPlacements(benchmark::State& state) {
  Display();
  Fixture f;
  PlacedScenes scenes;
  std::vector<Shot> shots;
  for (int p = 0; p < 4; ++p) {
    TargetScene scene = f.scene;
    scene.boards[0].ref_from_board.translation.x() += 0.05 * p;
    scenes["p" + std::to_string(p)] = scene;
  }
  for (int i = 0; i < 16; ++i) {
    Shot s;
    s.id = "b" + std::to_string(i);
    s.placement = "p" + std::to_string(i % 4);
    s.cam = f.cam;
    s.ref_from_cam = f.pose;
    s.ref_from_cam.translation.x() += 0.002 * i + 0.05 * (i % 4);
    shots.push_back(s);
  }
  TimeRenderShots(state, scenes, shots);
}
BENCHMARK(BM_RenderShotsPlacements)
    ->ArgNames({"jobs"})
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

}  // namespace
}  // namespace rtscalib::render

BENCHMARK_MAIN();

// Joint refinement speed: 7 zoom levels x 2 faces x ~50 shots x
// ~110 AprilTag corners (~70,000 pixel observations) in under 5 s on 2 cores,
// and the cost against the number of observations (several sizes: it should
// grow linearly).
//
// Each size: a dh truth near Klug's PLT 300 with 7 cameras (640 x 480 px,
// f = 800 * 1.4^z px, radial + tangential distortion), boards from ZoomScene
// (5 x 5 tags = 100 corners each), pixels with 0.2 px noise, no records. The
// timed part is Refine (intrinsics, distortion, covariance, variance
// re-estimation: the pipeline's settings) from InitFromPixels' start, which
// is computed once outside the timing loop. Counters: observations
// (corners), residuals, shots, seconds per 1,000 observations.
//
//   build-joint/bench/joint_refine_benchmark --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <memory>

#include "libcalib/eval/error_measures.h"
#include "libcalib/fit/init_from_pixels.h"
#include "libcalib/fit/refine.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib {
namespace {

constexpr int kZooms = 7;

InstrumentModel Truth() {
  InstrumentModel m = PaperTruth(kZooms);
  for (int z = 0; z < kZooms; ++z) {
    CameraTool& c = m.cams[z];
    c.width = 640;
    c.height = 480;
    const double f = 800.0 * std::pow(1.4, z);
    c.intrinsics = {f, f * (1 + 3e-4), 324.0 - z, 237.0 + 0.5 * z};
    c.distortion.fill(0.0);
    c.distortion[kK1] = -0.1 / (1 + z);
    c.distortion[kK2] = 0.05 / (1 + z);
    c.distortion[kP1] = 5e-4;
    c.distortion[kP2] = -3e-4;
  }
  m.effects.Add(Effect::kRadialDistortion);
  m.effects.Add(Effect::kTangentialDistortion);
  return m;
}

struct Problem {
  Observations obs;
  InstrumentModel start;
  int shots = 0;
};

// One problem per shots_per_board, built once (simulation and OpenCV start).
const Problem& ProblemFor(int shots_per_board) {
  static std::map<int, std::unique_ptr<Problem>> cache;
  auto& slot = cache[shots_per_board];
  if (slot) return *slot;
  slot = std::make_unique<Problem>();
  SimulationOptions o;
  o.seed = 42;
  o.truth = Truth();
  o.targets = ZoomScene(o.truth, 5, 5, 4.0);
  o.shots.shots_per_board = shots_per_board;
  o.shots.fill = 0.3;  // the whole board (100 corners) stays in most images
  o.plan.faces = {1, 2};
  o.plan.zooms.clear();
  for (int z = 0; z < kZooms; ++z) o.plan.zooms.push_back(z);
  o.noise.pixel_px = 0.2;
  SimulatedData data = Simulate(o);
  data.obs.records.clear();
  slot->obs = data.obs;
  std::map<std::string, int> shots;
  for (const PixelObservation& p : data.obs.pixels) shots[p.shot] = 1;
  slot->shots = static_cast<int>(shots.size());
  InitFromPixelsOptions io;
  io.kinematics = Kinematics::kDh;
  io.distortion.radial = io.distortion.tangential = true;
  for (const CameraTool& c : o.truth.cams) {
    CameraTool size;
    size.width = c.width;
    size.height = c.height;
    io.cameras.push_back(size);
  }
  slot->start = InitFromPixels(data.obs.pixels, io).model;
  slot->start.effects.Add(Effect::kRadialDistortion);
  slot->start.effects.Add(Effect::kTangentialDistortion);
  return *slot;
}

void BM_JointRefine(benchmark::State& state) {
  const Problem& p = ProblemFor(static_cast<int>(state.range(0)));
  FitOptions fo;
  fo.fit_intrinsics = true;
  fo.sigma_pixel_px = 0.2;
  fo.num_threads = 2;
  FitSummary s;
  for (auto _ : state) {
    InstrumentModel model = p.start;
    s = Refine(p.obs, fo, &model);
    benchmark::DoNotOptimize(model.cams[0].intrinsics[0]);
  }
  const double n = static_cast<double>(p.obs.pixels.size());
  state.counters["observations"] = n;
  state.counters["shots"] = p.shots;
  state.counters["iterations"] = s.iterations;
  state.counters["converged"] = s.converged;
  state.counters["corners_per_shot"] = n / p.shots;
}
// Argument: shots per usable board, zoom and face. About 5 boards suit each
// zoom, so 5 gives ~50 shots per zoom and face (~720 shots, ~80,000 corners).
BENCHMARK(BM_JointRefine)
    ->Arg(1)
    ->Arg(2)
    ->Arg(3)
    ->Arg(4)
    ->Arg(5)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1)
    ->Repetitions(2);

// Cost per observation at a fixed amount of work: exactly 5 Levenberg-
// Marquardt iterations (one variance round, no covariance). The full fits
// above take 6 to 18 iterations depending on the start; this isolates how
// one iteration (Jacobian evaluation + linear solve) grows with the data.
void BM_JointRefineFiveIterations(benchmark::State& state) {
  const Problem& p = ProblemFor(static_cast<int>(state.range(0)));
  FitOptions fo;
  fo.fit_intrinsics = true;
  fo.sigma_pixel_px = 0.2;
  fo.num_threads = 2;
  fo.max_iterations = 5;
  fo.reestimate_sigmas = false;
  fo.compute_covariance = false;
  for (auto _ : state) {
    InstrumentModel model = p.start;
    Refine(p.obs, fo, &model);
    benchmark::DoNotOptimize(model.cams[0].intrinsics[0]);
  }
  state.counters["observations"] = static_cast<double>(p.obs.pixels.size());
  state.counters["shots"] = p.shots;
}
BENCHMARK(BM_JointRefineFiveIterations)
    ->Arg(1)
    ->Arg(2)
    ->Arg(3)
    ->Arg(4)
    ->Arg(5)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1)
    ->Repetitions(2);

}  // namespace
}  // namespace rtscalib

BENCHMARK_MAIN();

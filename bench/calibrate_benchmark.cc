// The whole calibration as a library call (libcalib/calibrate), clean and
// with gross errors (goal: a run with 5 % gross rows takes at most twice a
// clean one, bench/goals.yaml), and a million records read from a file, screened
// and calibrated (time and peak memory).
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <string>

#include "libcalib/calibrate/calibrate.h"
#include "libcalib/io/records.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib {
namespace {

// The scene of tests/calibrate/gross_errors_test.cc: PLT 300-like truth,
// 2 faces x 2 zooms, sweeps and an 8 x 5 grid (3,680 records).
SimulationOptions Scene() {
  SimulationOptions sim;
  sim.seed = 31;
  sim.truth = PaperTruth(2);
  sim.plan.grid_phi_steps = 8;
  sim.plan.grid_theta_steps = 5;
  sim.plan.zooms = {0, 1};
  sim.plan.faces = {1, 2};
  sim.noise.point_m = 2e-5;
  sim.noise.angle_rad = 1.0 / 206265.0;
  return sim;
}

CalibrationOptions Options(const SimulationOptions& sim) {
  CalibrationOptions o;
  o.model.cameras = sim.truth.cams;
  for (CameraTool& c : o.model.cameras) c.flange_from_cam = PoseBlock();
  o.fit.sigma_edm_m = o.fit.sigma_cam_m = 2e-5;
  o.diagnose.enabled = false;
  return o;
}

// 5 % of the records with their point moved by 1 cm to 1 km (log-uniform).
void AddGrossErrors(Observations* obs) {
  std::mt19937_64 rng(77);
  std::normal_distribution<double> n;
  std::uniform_real_distribution<double> exponent(-2, 3);
  for (size_t i = 0; i < obs->records.size(); i += 20) {
    obs->records[i].x +=
        std::pow(10.0, exponent(rng)) * Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
  }
}

void Run(benchmark::State& state, bool gross, bool handling = true) {
  const SimulationOptions sim = Scene();
  SimulatedData data = Simulate(sim);
  if (gross) AddGrossErrors(&data.obs);
  CalibrationOptions options = Options(sim);
  options.screen.gross_errors.enabled = options.fit.gross_errors.enabled = handling;
  size_t taken_out = 0;
  for (auto _ : state) {
    const CalibrationResult r = Calibrate(data.obs, options);
    taken_out = r.gross_rows.size();
    benchmark::DoNotOptimize(r.model.links[0].p[0]);
  }
  state.counters["records"] = static_cast<double>(data.obs.records.size());
  state.counters["gross_rows"] = static_cast<double>(taken_out);
}

void BM_CalibrateClean(benchmark::State& state) { Run(state, false); }
BENCHMARK(BM_CalibrateClean)->Unit(benchmark::kMillisecond);

// What the gross-error handling costs a clean run.
void BM_CalibrateCleanWithoutGrossErrorHandling(benchmark::State& state) {
  Run(state, false, false);
}
BENCHMARK(BM_CalibrateCleanWithoutGrossErrorHandling)->Unit(benchmark::kMillisecond);

void BM_CalibrateFivePercentGross(benchmark::State& state) { Run(state, true); }
BENCHMARK(BM_CalibrateFivePercentGross)->Unit(benchmark::kMillisecond);

// A million records (both faces, one zoom, a 214 x 106 grid: 998,000 rows with the sweeps) written
// to a CSV, then read, screened and calibrated. Peak resident memory of the whole process
// (getrusage) as a counter [MB].
void BM_MillionRecordsFromFile(benchmark::State& state) {
  SimulationOptions sim = Scene();
  sim.truth = PaperTruth(1);
  sim.plan.zooms = {0};
  sim.plan.grid_phi_steps = 214;
  sim.plan.grid_theta_steps = 106;
  const std::string path =
      (std::filesystem::temp_directory_path() / "rtscalib_bench_million.csv").string();
  size_t rows = 0;
  {
    const SimulatedData data = Simulate(sim);
    rows = data.obs.records.size();
    WriteRecords(path, data.obs.records);
  }
  for (auto _ : state) {
    Observations obs;
    obs.records = ReadRecords(path).records;
    obs.records_source = path;
    const CalibrationResult r = Calibrate(obs, Options(sim));
    benchmark::DoNotOptimize(r.model.links[0].p[0]);
  }
  std::filesystem::remove(path);
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  state.counters["records"] = static_cast<double>(rows);
  state.counters["peak_MB"] = static_cast<double>(usage.ru_maxrss) / 1024.0;
}
BENCHMARK(BM_MillionRecordsFromFile)->Unit(benchmark::kSecond)->Iterations(1);

}  // namespace
}  // namespace rtscalib

BENCHMARK_MAIN();

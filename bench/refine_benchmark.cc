// Refinement speed (Klug Sec. 4.3; the paper's SQP took 1,326 s in MATLAB).
// Goals on 2 cores: paper-size problem < 20 ms; a 100x larger grid < 2 s.
#include <benchmark/benchmark.h>

#include <random>

#include "libcalib/fit/refine.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib {
namespace {

// The truth moved by ~1 mm / 1 mrad (PerturbedStart): a good extraction.
InstrumentModel StartModel(const InstrumentModel& truth) { return PerturbedStart(truth, 3); }

void Run(benchmark::State& state, const SimulationOptions& o) {
  const SimulatedData data = Simulate(o);
  FitOptions fo;
  fo.sigma_edm_m = fo.sigma_cam_m = 1e-5;
  for (auto _ : state) {
    InstrumentModel model = StartModel(o.truth);
    const FitSummary s = Refine(data.obs, fo, &model);
    benchmark::DoNotOptimize(s.final_cost);
  }
  state.counters["records"] = static_cast<double>(data.obs.records.size());
}

// The paper's data set: 15 points per sweep, EDM at 1 and 2 m, three camera
// rays per pose, one zoom, one face (150 records).
void BM_RefinePaperSize(benchmark::State& state) {
  SimulationOptions o;
  o.truth = PaperTruth(1);
  o.noise.point_m = 1e-5;
  Run(state, o);
}
BENCHMARK(BM_RefinePaperSize)->Unit(benchmark::kMillisecond);

// About 100x more records: a 50 x 30 grid with the same tool calls.
void BM_RefineGrid100x(benchmark::State& state) {
  SimulationOptions o;
  o.truth = PaperTruth(1);
  o.noise.point_m = 1e-5;
  o.plan.sweeps = true;
  o.plan.grid_phi_steps = 50;
  o.plan.grid_theta_steps = 30;
  o.plan.grid_edm_distances = {1.0, 2.0};
  o.plan.grid_cam_ray_lengths = {1.0};
  o.plan.grid_pixels_per_axis = 3;
  Run(state, o);
}
BENCHMARK(BM_RefineGrid100x)->Unit(benchmark::kMillisecond)->Iterations(2);

}  // namespace
}  // namespace rtscalib

BENCHMARK_MAIN();

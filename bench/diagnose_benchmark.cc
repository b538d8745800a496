// Diagnosis speed. Goal on 2 cores: the full ranking of every catalogue
// effect (with harmonics, outliers and the dh equivalents) under 1 s on
// paper-size records.
//   BM_DiagnosePaperSize     the paper's data set: 150 records, one face, one zoom
//   BM_DiagnosePaperConfig   configs/paper.yaml: sweeps + 24 x 12 grid (6486 records)
//   BM_RankOnlyPaperConfig   the same, ranking only (no harmonics, no outliers)
//   BM_DiagnoseThreeZoomPixels  three zoom levels, both faces, records and
//                               AprilTag pixels (a stand-in for the zoom3 demo)
#include <benchmark/benchmark.h>

#include <random>

#include "libcalib/diagnose/diagnose.h"
#include "libcalib/fit/refine.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib {
namespace {

// The truth moved by ~1 mm / 1 mrad (PerturbedStart): a good extraction.
InstrumentModel StartModel(const InstrumentModel& truth) { return PerturbedStart(truth, 3); }

struct Problem {
  SimulatedData data;
  InstrumentModel model;
  FitOptions options;
  FitSummary fit;
};

Problem Fit(const SimulationOptions& o, bool fit_intrinsics) {
  Problem p;
  p.data = Simulate(o);
  p.model = StartModel(o.truth);
  p.options.fit_intrinsics = fit_intrinsics;
  p.fit = Refine(p.data.obs, p.options, &p.model);
  return p;
}

void Run(benchmark::State& state, const Problem& p, const DiagnosisSettings& s) {
  const FitContext ctx = ContextOf(p.options, p.fit);
  for (auto _ : state) {
    const Diagnosis d = Diagnose(p.data.obs, p.model, ctx, s);
    benchmark::DoNotOptimize(d.ranking.entries.data());
  }
  state.counters["records"] = static_cast<double>(p.data.obs.records.size());
  state.counters["pixels"] = static_cast<double>(p.data.obs.pixels.size());
}

SimulationOptions PaperNoise(SimulationOptions o) {
  o.noise.angle_rad = 1.0 / 206264.806;
  o.noise.distance_m = 1e-5;
  o.noise.point_m = 5e-6;
  return o;
}

void BM_DiagnosePaperSize(benchmark::State& state) {
  SimulationOptions o;
  o.truth = PaperTruth(1);
  static const Problem p = Fit(PaperNoise(o), false);
  Run(state, p, DiagnosisSettings{});
}
BENCHMARK(BM_DiagnosePaperSize)->Unit(benchmark::kMillisecond);

SimulationOptions PaperConfig() {
  SimulationOptions o;
  o.seed = 2018;
  o.truth = PaperTruth(1);
  o.plan.grid_phi_steps = 24;
  o.plan.grid_theta_steps = 12;
  return PaperNoise(o);
}

void BM_DiagnosePaperConfig(benchmark::State& state) {
  static const Problem p = Fit(PaperConfig(), true);
  Run(state, p, DiagnosisSettings{});
}
BENCHMARK(BM_DiagnosePaperConfig)->Unit(benchmark::kMillisecond);

void BM_RankOnlyPaperConfig(benchmark::State& state) {
  static const Problem p = Fit(PaperConfig(), true);
  DiagnosisSettings s;
  s.harmonics = false;
  s.outliers = false;
  Run(state, p, s);
}
BENCHMARK(BM_RankOnlyPaperConfig)->Unit(benchmark::kMillisecond);

void BM_DiagnoseThreeZoomPixels(benchmark::State& state) {
  SimulationOptions o;
  o.truth = PaperTruth(3);
  o.plan.faces = {1, 2};
  o.plan.zooms = {0, 1, 2};
  o.plan.grid_phi_steps = 12;
  o.plan.grid_theta_steps = 6;
  TagBoard board;
  board.rows = 6;
  board.cols = 8;
  board.tag_size = 0.05;
  board.spacing = 0.0125;
  for (int i = 0; i < 4; ++i) {
    TagBoard b = board;
    b.first_id = i * board.NumTags();
    const double yaw = M_PI / 2 * i;
    // Boards 4 m away around the station, facing it.
    b.ref_from_board =
        Rigid3::FromEuler({M_PI / 2, 0.0, yaw}, {4.0 * std::sin(yaw), 4.0 * std::cos(yaw), 0.0});
    o.targets.boards.push_back(b);
  }
  o.shots.shots_per_board = 6;
  o = PaperNoise(o);
  o.noise.pixel_px = 0.3;
  static const Problem p = Fit(o, true);
  Run(state, p, DiagnosisSettings{});
}
BENCHMARK(BM_DiagnoseThreeZoomPixels)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace rtscalib

BENCHMARK_MAIN();

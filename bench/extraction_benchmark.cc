// Geometric extraction speed (Klug Sec. 3; docs/extraction.md).
// Goal on 2 cores: the paper-size data set < 1 ms.
#include <benchmark/benchmark.h>

#include "libcalib/extract/extract.h"
#include "libcalib/extract/simplify.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib {
namespace {

// Noise-free records of the plan for the PLT 300-like truth (Klug Tables 6/7).
void Run(benchmark::State& state, const AcquisitionPlan& plan, int num_zooms) {
  const InstrumentModel truth = PaperTruth(num_zooms);
  const std::vector<Record> records = PlanRecords(plan, truth);
  for (auto _ : state) {
    const ExtractionResult r = ExtractDhModel(records, truth.cams);
    benchmark::DoNotOptimize(r.model.links[0].p[0]);
  }
  state.counters["records"] = static_cast<double>(records.size());
}

// The paper's data set: 15 points per sweep, EDM at 1 and 2 m, three camera
// rays per pose, one zoom, one face (150 records).
void BM_ExtractPaperSize(benchmark::State& state) { Run(state, AcquisitionPlan(), 1); }
BENCHMARK(BM_ExtractPaperSize)->Unit(benchmark::kMicrosecond);

// The same with the PLT 300's seven zoom levels (690 records).
void BM_ExtractPaperSizeSevenZooms(benchmark::State& state) {
  AcquisitionPlan plan;
  plan.zooms = {0, 1, 2, 3, 4, 5, 6};
  Run(state, plan, 7);
}
BENCHMARK(BM_ExtractPaperSizeSevenZooms)->Unit(benchmark::kMicrosecond);

// Sweeps plus a 24 x 12 grid in both faces (~11,000 records): the sweep search
// and the tool alignments over every pose.
void BM_ExtractWithGrid(benchmark::State& state) {
  AcquisitionPlan plan;
  plan.faces = {1, 2};
  plan.grid_phi_steps = 24;
  plan.grid_theta_steps = 12;
  Run(state, plan, 1);
}
BENCHMARK(BM_ExtractWithGrid)->Unit(benchmark::kMillisecond);

// Sec. 4.1 on the extracted model (the Euler-form table is built on first use).
void BM_Simplify(benchmark::State& state) {
  const InstrumentModel truth = PaperTruth(1);
  const ExtractionResult r = ExtractDhModel(PlanRecords(AcquisitionPlan(), truth), truth.cams);
  for (auto _ : state) {
    const SimplifiedModel s = Simplify(r.model);
    benchmark::DoNotOptimize(s.rotation.exact);
  }
}
BENCHMARK(BM_Simplify)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace rtscalib

BENCHMARK_MAIN();

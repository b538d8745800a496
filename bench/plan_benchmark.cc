// Planning speed: `rtscalib plan` on a zoom3-size session (configs/plan.yaml:
// three zooms, both faces, four surveyed boards, 288 candidate photos, the
// records of a tracker session as fixed data). Goal on 2 cores: under 2 s,
// so that a surveyor can re-plan on site.
//   BM_PlanZoom3Projection  goal: worst projection sigma 0.03 px per zoom
//   BM_PlanZoom3Constants   goal: hz_eccentricity.e and every zoom's fx, k1
//   BM_PlanCameraOnItsOwn   configs/plan_camera.yaml: where to hold a
//       chessboard for a camera on its own (its candidate poses, fx 0.3 px,
//       projection 0.4 px)
#include <benchmark/benchmark.h>

#include <string>

#include "libcalib/config/config.h"
#include "libcalib/plan/planner.h"
#include "libcalib/plan/session.h"
#include "libcalib/plan/settings.h"
#include "render/settings.h"

namespace rtscalib {
namespace {

struct Loaded {
  PlanSession session;
  PlanOptions options;
};

Loaded Load(const std::string& name = "plan.yaml") {
  render::RenderSettings render;
  PlanSettings settings;
  const std::string dir = std::string(RTSCALIB_SOURCE_DIR) + "/configs";
  const RunConfig config = LoadConfig(
      dir + "/" + name, {render::RenderConfigSection(&render), PlanConfigSection(&settings, dir)});
  return {SessionFromConfig(config, settings), settings.options};
}

void Run(benchmark::State& state, const PlanOptions& o, const PlanSession& session) {
  size_t shots = 0;
  int candidates = 0;
  for (auto _ : state) {
    const PlanResult r = PlanShots(session, o);
    shots = r.shots.size();
    candidates = r.candidates;
    benchmark::DoNotOptimize(r.goal_met);
  }
  state.counters["shots"] = static_cast<double>(shots);
  state.counters["candidates"] = candidates;
}

void BM_PlanZoom3Projection(benchmark::State& state) {
  Loaded l = Load();
  l.options.goal.sigmas.clear();
  l.options.goal.projection_px = 0.03;
  Run(state, l.options, l.session);
}
BENCHMARK(BM_PlanZoom3Projection)->Unit(benchmark::kMillisecond);

void BM_PlanZoom3Constants(benchmark::State& state) {
  Loaded l = Load();
  l.options.goal.projection_px = 0;
  l.options.goal.sigmas = {{"hz_eccentricity.e", 0.0125}};
  for (int z = 0; z < 3; ++z) {
    const std::string c = "cam[" + std::to_string(z) + "].";
    l.options.goal.sigmas.push_back({c + "fx", 0.05 * (z + 1)});
    l.options.goal.sigmas.push_back({c + "k1", 0.002 * (z + 1) * (z + 1)});
  }
  Run(state, l.options, l.session);
}
BENCHMARK(BM_PlanZoom3Constants)->Unit(benchmark::kMillisecond);

void BM_PlanCameraOnItsOwn(benchmark::State& state) {
  const Loaded l = Load("plan_camera.yaml");
  Run(state, l.options, l.session);
}
BENCHMARK(BM_PlanCameraOnItsOwn)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace rtscalib

BENCHMARK_MAIN();

// The figures of a camera on a bench: the seven figures that
// `rtscalib --config configs/bench.yaml` draws (OpenCV's 13 sample photos;
// two photos with their residuals, the image residuals, the residuals
// against the variables, the histograms, the uncertainty map and the ladder
// of runs). One run of the config in this process, before the benchmarks,
// writes their Vega specs and SVG files; the benchmarks draw them again.
//
//   BM_BenchFiguresDraw  app::VegaRenderer::Draw of the seven specs: each
//       spec's SVG (app/plot/vega_svg.h) and its PNG (librsvg) on the renderer's
//       two threads, up to the last PNG (what a run waits for after its
//       specs are made). The threads' start (librsvg opened, fonts loaded)
//       is outside the timing: a run starts them while it reads its photos.
//       Counter: figures.
//   BM_BenchFiguresSvg  app::vega::DrawSvg alone: the seven specs to SVG on
//       one thread. Counter: ms_per_figure.
//   BM_BenchFiguresPng  librsvg and libdeflate alone: each of the seven SVG files
//       to its PNG, on a thread that has drawn before. Counter: ms_per_figure.
//   BM_FirstPngOfAThread  one figure (the largest photo figure) drawn twice
//       on a new thread: pango's font map, which librsvg's text goes
//       through, is made per thread at its first text. Manual time: the
//       first drawing; counter second_ms: the second.
//
//   build/bench/figures_benchmark --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "app/commands.h"
#include "app/plot/svg_raster.h"
#include "app/plot/vega.h"
#include "app/plot/vega_svg.h"
#include "bench/quiet_stdout.h"

namespace rtscalib::bench {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

std::string ReadFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The specs and SVG files of one run of configs/bench.yaml, largest SVG
// first.
struct BenchFigures {
  std::vector<nlohmann::json> specs;
  std::vector<std::string> svgs;

  BenchFigures() {
    std::string tmpl = (fs::temp_directory_path() / "rtscalib-figures-bench-XXXXXX").string();
    if (::mkdtemp(tmpl.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
    const fs::path dir = tmpl;
    app::RunArgs args;
    args.config = std::string(RTSCALIB_SOURCE_DIR) + "/configs/bench.yaml";
    args.output = (dir / "out").string();
    args.quiet = true;
    int code = 0;
    {
      const QuietStdout quiet;
      code = app::RunCalibration(args);
      // A second run: the first has no earlier run to draw the ladder of.
      if (code == 0) code = app::RunCalibration(args);
    }
    if (code != 0) throw std::runtime_error("rtscalib --config configs/bench.yaml failed");
    std::vector<std::pair<size_t, fs::path>> files;
    for (const fs::directory_entry& e : fs::directory_iterator(dir / "out" / "latest" / "figures")) {
      if (e.path().extension() == ".svg") files.emplace_back(fs::file_size(e.path()), e.path());
    }
    std::sort(files.rbegin(), files.rend());
    for (const auto& [bytes, svg] : files) {
      svgs.push_back(ReadFile(svg));
      fs::path spec = svg;
      spec.replace_extension(".vg.json");
      specs.push_back(nlohmann::json::parse(ReadFile(spec)));
    }
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
};

const BenchFigures& Figures() {
  static const BenchFigures figures;
  return figures;
}

void BM_BenchFiguresDraw(benchmark::State& state) {
  const BenchFigures& f = Figures();
  for (auto _ : state) {
    state.PauseTiming();
    auto renderer = std::make_unique<app::VegaRenderer>();
    renderer->WaitUntilReady();
    state.ResumeTiming();
    std::string note;
    const std::vector<app::RenderedFigure> drawn = renderer->Draw(f.specs, &note);
    state.PauseTiming();
    renderer.reset();  // the threads' end
    state.ResumeTiming();
    if (!note.empty() || drawn.size() != f.specs.size()) {
      state.SkipWithError(("figures not drawn: " + note).c_str());
      return;
    }
  }
  state.counters["figures"] = static_cast<double>(f.specs.size());
}
BENCHMARK(BM_BenchFiguresDraw)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

void BM_BenchFiguresSvg(benchmark::State& state) {
  const BenchFigures& f = Figures();
  double seconds = 0;
  for (auto _ : state) {
    const Clock::time_point t = Clock::now();
    for (const nlohmann::json& spec : f.specs) benchmark::DoNotOptimize(app::vega::DrawSvg(spec));
    seconds += std::chrono::duration<double>(Clock::now() - t).count();
  }
  state.counters["ms_per_figure"] =
      1e3 * seconds / static_cast<double>(state.iterations() * f.specs.size());
}
BENCHMARK(BM_BenchFiguresSvg)->Unit(benchmark::kMillisecond)->UseRealTime();

// The process's rasterizer, or null with the benchmark skipped when
// librsvg is missing.
const app::SvgRasterizer* Rasterizer(benchmark::State& state) {
  const app::SvgRasterizer& raster = app::SvgRasterizer::Get();
  if (raster.missing().empty()) return &raster;
  state.SkipWithError(raster.missing().c_str());
  return nullptr;
}

void BM_BenchFiguresPng(benchmark::State& state) {
  const BenchFigures& f = Figures();
  const app::SvgRasterizer* found = Rasterizer(state);
  if (found == nullptr) return;
  const app::SvgRasterizer& raster = *found;
  std::vector<unsigned char> png;
  std::string error;
  raster.ToPng(f.svgs.back(), &png, &error);  // this thread's font map
  double seconds = 0;
  for (auto _ : state) {
    const Clock::time_point t = Clock::now();
    for (const std::string& svg : f.svgs) {
      if (!raster.ToPng(svg, &png, &error)) {
        state.SkipWithError(error.c_str());
        return;
      }
    }
    seconds += std::chrono::duration<double>(Clock::now() - t).count();
  }
  state.counters["ms_per_figure"] =
      1e3 * seconds / static_cast<double>(state.iterations() * f.svgs.size());
}
BENCHMARK(BM_BenchFiguresPng)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_FirstPngOfAThread(benchmark::State& state) {
  const BenchFigures& f = Figures();
  const app::SvgRasterizer* found = Rasterizer(state);
  if (found == nullptr) return;
  const app::SvgRasterizer& raster = *found;
  double second_s = 0;
  for (auto _ : state) {
    double first = 0, second = 0;
    std::thread([&] {
      std::vector<unsigned char> png;
      std::string error;
      Clock::time_point t = Clock::now();
      raster.ToPng(f.svgs.front(), &png, &error);
      first = std::chrono::duration<double>(Clock::now() - t).count();
      t = Clock::now();
      raster.ToPng(f.svgs.front(), &png, &error);
      second = std::chrono::duration<double>(Clock::now() - t).count();
    }).join();
    state.SetIterationTime(first);
    second_s += second;
  }
  state.counters["second_ms"] = 1e3 * second_s / static_cast<double>(state.iterations());
}
BENCHMARK(BM_FirstPngOfAThread)->Unit(benchmark::kMillisecond)->UseManualTime();

}  // namespace
}  // namespace rtscalib::bench

BENCHMARK_MAIN();

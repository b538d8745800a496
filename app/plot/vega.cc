#include "app/plot/vega.h"

#include "app/plot/svg_raster.h"
#include "app/plot/vega_svg.h"

#include <algorithm>
#include <condition_variable>
#include <cstdlib>
#include <deque>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>
#include <tuple>

namespace rtscalib::app {
namespace {

namespace fs = std::filesystem;

// The modules a figure needs (parser, view, SVG renderer, scales, encoders
// and the data transforms), in an order where each one's dependencies come
// first; vega-functions asks for "vega-selections", Debian's file is
// vega-selection.
const char* const kModules[] = {
    "vega-util",       "vega-canvas",         "vega-time",      "vega-format",
    "vega-loader",     "vega-dataflow",       "vega-scale",     "vega-statistics",
    "vega-transforms", "vega-scenegraph",     "vega-encode",    "vega-view-transforms",
    "vega-expression", "vega-event-selector", "vega-selection", "vega-functions",
    "vega-runtime",    "vega-view",           "vega-parser"};

std::string ReadText(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) return "";
  return std::string(std::istreambuf_iterator<char>(in), {});
}

std::string BuildRuntime(std::string* missing) {
  const fs::path dir = VegaModuleDir();
  std::ostringstream o;
  o << "(function(){var defs={},cache={};"
       "function req(n){if(n==='vega-selections')n='vega-selection';var m=cache[n];"
       "if(m)return m.exports;if(!defs[n])throw new Error('vega runtime: no module '+n);"
       "m=cache[n]={exports:{}};defs[n].call(m.exports,m,m.exports,req);return m.exports;}\n";
  for (const char* m : kModules) {
    std::string src = ReadText(dir / (std::string(m) + ".min.js"));
    if (src.empty()) {
      *missing = (dir / (std::string(m) + ".min.js")).string() + " (Debian package libjs-vega)";
      return "";
    }
    // The source map is not shipped beside the page: no reference to it.
    for (size_t at = src.find("//# sourceMappingURL="); at != std::string::npos;
         at = src.find("//# sourceMappingURL=", at)) {
      src.replace(at, 3, "// ");
    }
    // "</script" inside a module would end the inline script of report.html.
    for (size_t at = src.find("</script"); at != std::string::npos; at = src.find("</script", at)) {
      src.replace(at, 2, "<\\/");
    }
    o << "defs['" << m << "']=function(module,exports,require){" << src << "\n};\n";
  }
  // Vega parses every expression of a spec (each axis's, legend's and
  // mark's, written out again for every panel and figure) character by
  // character and generates its code, which no figure changes: the syntax
  // tree of each expression text, and the code of each tree, are kept and
  // reused. vega-functions reads both through vega-expression's exports at
  // each call, and makes its code generator once, when it is loaded: the
  // wrappers go in before it is.
  o << "var ve=req('vega-expression'),parse=ve.parseExpression,trees=new Map();"
       "ve.parseExpression=function(s){var t=trees.get(s);"
       "if(t===undefined){t=parse(s);trees.set(s,t);}return t;};"
       "var codegen=ve.codegenExpression;ve.codegenExpression=function(opt){"
       "var g=codegen(opt),made=new WeakMap(),f=function(t){var c=made.get(t);"
       "if(c===undefined){c=g(t);made.set(t,c);}return c;};"
       "for(var k in g)f[k]=g[k];return f;};\n";
  // What the `vega` index module does: register the data transforms, export
  // the parser, the view and the helpers under one name.
  o << "var df=req('vega-dataflow');"
       "['vega-transforms','vega-view-transforms','vega-encode'].forEach(function(n){"
       "var t=req(n);for(var k in t)df.transforms[k]=t[k];});"
       "var v={};['vega-util','vega-scale','vega-scenegraph','vega-dataflow','vega-view',"
       "'vega-parser','vega-functions','vega-format'].forEach(function(n){var t=req(n);"
       "for(var k in t)if(!(k in v))v[k]=t[k];});"
       "(typeof globalThis!=='undefined'?globalThis:this).vega=v;})();\n";
  return o.str();
}

}  // namespace

std::string VegaModuleDir() {
  const char* env = std::getenv("RTSCALIB_VEGA_DIR");
  return env && *env ? env : "/usr/share/javascript/vega";
}

const std::string& VegaRuntime(std::string* missing) {
  static std::once_flag once;
  static std::string runtime, why;
  std::call_once(once, [] { runtime = BuildRuntime(&why); });
  if (missing) *missing = why;
  return runtime;
}

struct VegaRenderer::State {
  explicit State(size_t threads) : threads(threads) {}
  const size_t threads;
  std::mutex mutex;  // guards the rest
  std::condition_variable wake;
  std::deque<std::pair<size_t, const nlohmann::json*>> queue;
  std::set<size_t> added;
  std::map<size_t, RenderedFigure> drawn;
  bool ended = false;
  bool collecting = false;
  Drawn on_drawn;
  std::exception_ptr failed;  // the first thing on_drawn threw
  std::vector<std::thread> workers;
  size_t busy = 0;   // figures being drawn
  size_t ready = 0;  // threads that have warmed up

  // One worker: warms up librsvg's text on its thread while the figures
  // are made, then draws each spec it takes, SVG then PNG, and hands the
  // figure over on this thread.
  void Work(const SvgRasterizer* raster) {
    if (raster != nullptr) raster->WarmUp();
    {
      const std::lock_guard<std::mutex> lock(mutex);
      ++ready;
    }
    wake.notify_all();
    for (;;) {
      size_t i = 0;
      const nlohmann::json* spec = nullptr;
      {
        std::unique_lock<std::mutex> lock(mutex);
        wake.wait(lock, [this] { return !queue.empty() || ended; });
        if (queue.empty()) return;
        std::tie(i, spec) = queue.front();
        queue.pop_front();
        ++busy;
      }
      RenderedFigure fig;
      try {
        fig.svg = vega::DrawSvg(*spec);
      } catch (const std::exception& e) {
        // Outside the drawn part of Vega (SubsetError), or a malformed spec
        // (nlohmann's type errors): this figure has no files, the run goes on.
        fig.error = e.what();
      }
      if (!fig.svg.empty() && raster != nullptr && !raster->ToPng(fig.svg, &fig.png, &fig.error)) {
        fig.png.clear();
      }
      std::unique_lock<std::mutex> lock(mutex);
      // Handed over once the run collects: it writes the files there.
      wake.wait(lock, [this] { return collecting; });
      if (on_drawn && !failed && !fig.svg.empty()) {
        lock.unlock();
        try {
          on_drawn(i, fig);
        } catch (...) {
          lock.lock();
          if (!failed) failed = std::current_exception();
          lock.unlock();
        }
        lock.lock();
      }
      drawn[i] = std::move(fig);
      --busy;
      wake.notify_all();
    }
  }
};

VegaRenderer::VegaRenderer(size_t threads)
    : state_(std::make_unique<State>(std::max<size_t>(1, threads))) {
  State* s = state_.get();
  // librsvg is opened (and each thread's fonts loaded) while the run reads
  // its photos; a machine without it still gets the SVG files.
  for (size_t t = 0; t < s->threads; ++t) {
    s->workers.emplace_back([s] {
      const SvgRasterizer& raster = SvgRasterizer::Get();
      s->Work(raster.missing().empty() ? &raster : nullptr);
    });
  }
}

VegaRenderer::~VegaRenderer() {
  {
    const std::lock_guard<std::mutex> lock(state_->mutex);
    state_->ended = true;
    state_->collecting = true;
  }
  state_->wake.notify_all();
  for (std::thread& t : state_->workers) t.join();
}

void VegaRenderer::WaitUntilReady() {
  std::unique_lock<std::mutex> lock(state_->mutex);
  state_->wake.wait(lock, [this] { return state_->ready == state_->threads; });
}

void VegaRenderer::Add(size_t index, const nlohmann::json& spec) {
  State& s = *state_;
  {
    const std::lock_guard<std::mutex> lock(s.mutex);
    if (s.ended || !s.added.insert(index).second) {
      throw std::logic_error("VegaRenderer::Add: spec " + std::to_string(index) +
                             (s.ended ? " after End" : " added twice"));
    }
    s.queue.emplace_back(index, &spec);
  }
  s.wake.notify_all();
}

void VegaRenderer::End() {
  {
    const std::lock_guard<std::mutex> lock(state_->mutex);
    state_->ended = true;
  }
  state_->wake.notify_all();
}

std::vector<RenderedFigure> VegaRenderer::Collect(std::string* note, const Drawn& drawn) {
  State& s = *state_;
  std::unique_lock<std::mutex> lock(s.mutex);
  s.on_drawn = drawn;
  s.collecting = true;
  s.wake.notify_all();
  s.wake.wait(lock, [&s] {
    return s.ended && s.queue.empty() && s.busy == 0 && s.drawn.size() == s.added.size();
  });
  if (s.failed) std::rethrow_exception(s.failed);
  note->clear();
  const SvgRasterizer& raster = SvgRasterizer::Get();
  if (!raster.missing().empty()) {
    *note =
        "figures: no PNG files written (the SVG files, report.html and figures/*.vg.json "
        "have them): " +
        raster.missing() + "; scripts/install-deps.sh installs it";
  }
  std::vector<RenderedFigure> out(s.added.empty() ? 0 : *s.added.rbegin() + 1);
  for (size_t i = 0; i < out.size(); ++i) {
    const auto a = s.drawn.find(i);
    if (a != s.drawn.end()) {
      out[i] = std::move(a->second);
    } else {
      out[i].error = "not handed to the renderer";
    }
  }
  return out;
}

std::vector<RenderedFigure> VegaRenderer::Draw(const std::vector<nlohmann::json>& specs,
                                               std::string* note, const Drawn& drawn) {
  std::vector<size_t> bytes;
  for (const nlohmann::json& spec : specs) bytes.push_back(spec.dump().size());
  for (size_t i : LargestFirst(bytes)) Add(i, specs[i]);
  End();
  return Collect(note, drawn);
}

std::vector<size_t> LargestFirst(const std::vector<size_t>& bytes) {
  std::vector<size_t> order(bytes.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return bytes[a] > bytes[b]; });
  return order;
}

}  // namespace rtscalib::app

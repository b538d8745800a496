// The plotting library of rtscalib's figures: Vega 5 (a declarative
// grammar of graphics: a figure is a JSON spec of data, scales, axes and
// marks; Vega draws the axes, ticks, legends and colour schemes). Chosen
// because Debian packages it (libjs-vega: the browser modules, no network
// at run time), because one spec gives both pictures a person needs (SVG in
// report.html, crisp at any zoom, with tooltips naming shot, target and
// value; SVG and PNG files drawn from the same spec), and because the spec is
// plain data that anyone can re-plot (docs/output.md, "Figures").
//
// Debian ships Vega as separate UMD modules, not one bundle; their
// browser-global fallback overwrites `vega` per module, so VegaRuntime()
// joins them through a small CommonJS registry instead (each module's
// `require('vega-util')` answered from the registry). The text is inlined in
// report.html (and run by node in the tests, against vega_svg.h).
//
// Files: each figure's SVG is drawn from its spec in this process
// (vega_svg.h, by Vega's rules, the part of Vega the figures use), and its
// PNG from that SVG by librsvg (svg_raster.h), on a few threads of their own
// while the run goes on. Without librsvg the run writes the SVG files and
// says so; without the Vega modules report.html cannot draw its figures and
// says so. A run never fails for either.
#pragma once

#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace rtscalib::app {

// Where the Vega modules are: $RTSCALIB_VEGA_DIR, else Debian's
// /usr/share/javascript/vega.
std::string VegaModuleDir();

// The joined runtime (sets the global `vega`), or "" with *missing naming
// what is not installed. Read once per process.
const std::string& VegaRuntime(std::string* missing = nullptr);

struct RenderedFigure {
  std::string svg;                 // empty when this spec failed: `error` says why
  // Empty when svg is, without librsvg, or when librsvg refused the SVG
  // (`error` says why).
  std::vector<unsigned char> png;
  std::string error;
};

// The SVG and PNG drawing of figures, started before the figures exist:
// librsvg is opened and each drawing thread's fonts are loaded from the
// constructor on, while the run reads its photos and fits. Each figure is
// drawn as soon as it is added, on one of `threads` threads, and handed to
// Collect's callback on that thread.
class VegaRenderer {
 public:
  explicit VegaRenderer(size_t threads = 2);
  // Ends the drawing (End) and waits for the threads.
  ~VegaRenderer();
  // Waits until every thread has opened librsvg and loaded its fonts (a
  // run need not: its first figure waits for it if it must).
  void WaitUntilReady();
  VegaRenderer(const VegaRenderer&) = delete;
  VegaRenderer& operator=(const VegaRenderer&) = delete;

  // Called with a figure's index and its SVG and PNG as soon as they are
  // drawn, on the thread that drew them (several at once): the run writes
  // the files there. What it throws, Collect throws.
  using Drawn = std::function<void(size_t, const RenderedFigure&)>;

  // SVG and PNG of each spec (in order); a figure that could not be drawn
  // has its `error` (a spec outside vega_svg.h's part of Vega, librsvg's
  // message); *note says what is missing for every figure (librsvg). Once
  // per renderer, on the calling thread, the largest spec first.
  std::vector<RenderedFigure> Draw(const std::vector<nlohmann::json>& specs, std::string* note,
                                   const Drawn& drawn = nullptr);

  // The same with the specs handed over one at a time, while the next ones
  // are made: Add gives spec `index` (any order; `spec` stays where it is
  // until Collect returns), End says that no more come. Collect, called
  // once, returns when every spec added before End is drawn: one
  // RenderedFigure per index up to the largest added (indices never added
  // have an error). `drawn` is called from the moment Collect is called
  // (figures drawn before wait for it). Add and End come from one thread.
  void Add(size_t index, const nlohmann::json& spec);
  void End();
  std::vector<RenderedFigure> Collect(std::string* note, const Drawn& drawn = nullptr);

  struct State;  // vega.cc: the threads and their queue

 private:
  std::unique_ptr<State> state_;
};

// The order in which to hand specs to the renderer: the largest first,
// which take longest to draw, so that the last one drawn is a small one.
// `bytes`: each spec's size as JSON text.
std::vector<size_t> LargestFirst(const std::vector<size_t>& bytes);

}  // namespace rtscalib::app

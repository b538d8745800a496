// The plotting library of rtscalib's figures: Vega 5 (a declarative
// grammar of graphics: a figure is a JSON spec of data, scales, axes and
// marks; Vega draws the axes, ticks, legends and colour schemes). Chosen
// because Debian packages it (libjs-vega: the browser modules, no network
// at run time), because one spec gives both pictures a person needs (SVG in
// report.html, crisp at any zoom, with tooltips naming shot, target and
// value; PNG files through the same spec headless), and because the spec is
// plain data that anyone can re-plot (docs/output.md, "Figures").
//
// Debian ships Vega as separate UMD modules, not one bundle; their
// browser-global fallback overwrites `vega` per module, so VegaRuntime()
// joins them through a small CommonJS registry instead (each module's
// `require('vega-util')` answered from the registry). The same text runs in
// the browser (inlined in report.html) and in node (the PNG files).
//
// PNG files: node runs the runtime headless (renderer "none", View.toSVG) on
// every spec in one process, librsvg draws each SVG in this process
// (svg_raster.h) while node draws the next. Without node, the Vega modules
// or librsvg, the run still writes the specs and report.html (which draws
// them in the browser) and says which program is missing; it never fails
// for it.
//
// Node's start: node starts, then reads and compiles the runtime, and the
// first figures cost more than later ones while node compiles the code they
// run. A start-up snapshot (node's --build-snapshot: the heap after the
// runtime is loaded and a few warm-up specs are drawn, their compiled code
// included) holds both: node starts from it barely slower than its own
// start, and draws the first figure as fast as the next
// (opencv_bench_side_by_side_benchmark's run of configs/bench.yaml includes
// its figures). It is built once, by the first
// renderer that finds it missing (about half a second, on the renderer's
// own thread), into the user's cache folder (VegaSnapshotPath), and named
// after everything it depends on (node's binary, its flags, the runtime
// and the scripts), so that a changed node or runtime gets a snapshot of
// its own. A snapshot node cannot read is removed and node reads the
// runtime as without one; a run never fails for the snapshot.
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
  std::string svg;  // empty when this spec failed: `error` says why
  std::vector<unsigned char> png;  // empty when svg is
  std::string error;
};

// Node's start-up snapshot of the Vega runtime for the node program at
// `node` (a path): vega-<hash>.blob in $XDG_CACHE_HOME/rtscalib, else in
// ~/.cache/rtscalib; "" when neither variable is set or node or the runtime
// is missing. The file may not exist yet.
std::string VegaSnapshotPath(const std::string& node);

// The SVG and PNG drawing of figures, started before the figures exist.
// Node's start (from the snapshot, built first when missing) and the
// opening of librsvg happen on a thread of their own from the constructor
// on: a run starts its renderer when it has read its config, and Draw()
// finds node waiting for specs. Node then draws one SVG after the other
// (its start is paid once per run) and this process draws each one's PNG on
// a thread of its own as soon as node has written it, while node draws the
// next.
class VegaRenderer {
 public:
  VegaRenderer();
  // Ends node (if Draw did not) and removes its temporary folder.
  ~VegaRenderer();
  VegaRenderer(const VegaRenderer&) = delete;
  VegaRenderer& operator=(const VegaRenderer&) = delete;

  // Called with a figure's index and its SVG and PNG as soon as the PNG is
  // drawn, on the thread that drew it (several at once): the run writes
  // the files there, while node draws the next spec. What it throws, Draw
  // throws.
  using Drawn = std::function<void(size_t, const RenderedFigure&)>;

  // SVG and PNG of each spec (in order), each figure that Vega or librsvg
  // could not draw with its `error`; *note says why a figure is missing
  // beyond that (node ended early: its own message). An empty vector and
  // *note saying why when nothing can be drawn (a missing program). Once
  // per renderer: Add, End and Collect on the calling thread, the largest
  // spec first.
  std::vector<RenderedFigure> Draw(const std::vector<nlohmann::json>& specs, std::string* note,
                                   const Drawn& drawn = nullptr);

  // The same with the specs handed over one at a time, while the next ones
  // are made: Add gives node spec `index` (any order; node draws the specs
  // in the order they come), End says that no more come. Collect, called
  // once, on a thread of its own from before the first Add or after End,
  // hands over each drawing as it comes and returns when node has drawn
  // every spec added before End: one RenderedFigure per index up to the
  // largest added (indices never added have an error). Add and End come
  // from one thread.
  void Add(size_t index, const std::string& spec);  // the spec as JSON text
  void End();
  std::vector<RenderedFigure> Collect(std::string* note, const Drawn& drawn = nullptr);

  // How node was started ("started from the snapshot <path>", "built the
  // snapshot <path>", "read the runtime (no snapshot...)"); "" when it was
  // not (Draw's note says why). Waits for the start.
  const std::string& how();

  struct State;  // vega.cc: node's process, its folder, what is missing

 private:
  std::unique_ptr<State> state_;
};

// The order in which to hand specs to node: the largest first. Their SVG
// files are the largest too, and the PNG of the last SVG, drawn after node
// is done, is then a small one.
// `bytes`: each spec's size as JSON text.
std::vector<size_t> LargestFirst(const std::vector<size_t>& bytes);

}  // namespace rtscalib::app

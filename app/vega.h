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
#pragma once

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
  std::vector<unsigned char> png;
  std::string error;
};

// The SVG and PNG drawing of figures, started before the figures exist.
// Node's start and its reading of the Vega runtime (about 75 ms of CPU,
// whatever the figures), and the opening of librsvg, happen on a thread of
// their own from the constructor on: a run starts its renderer when the
// calibration starts, which keeps one core busy, and Draw() finds node
// waiting for specs. Node then draws one SVG after the other (its start is
// paid once per run) and this process draws each one's PNG on a thread of
// its own as soon as node has written it, while node draws the next.
class VegaRenderer {
 public:
  VegaRenderer();
  // Ends node (if Draw did not) and removes its temporary folder.
  ~VegaRenderer();
  VegaRenderer(const VegaRenderer&) = delete;
  VegaRenderer& operator=(const VegaRenderer&) = delete;

  // SVG and PNG of each spec (in order), or an empty vector and *note saying
  // why not (a missing program, or the renderer's own error message). Once
  // per renderer.
  std::vector<RenderedFigure> Draw(const std::vector<nlohmann::json>& specs, std::string* note);

  struct State;  // vega.cc: node's process, its folder, what is missing

 private:
  std::unique_ptr<State> state_;
};

// One VegaRenderer's Draw (node started now).
std::vector<RenderedFigure> RenderFigures(const std::vector<nlohmann::json>& specs,
                                          std::string* note);

}  // namespace rtscalib::app

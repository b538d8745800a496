#include "app/vega.h"

#include "app/svg_raster.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <condition_variable>
#include <deque>
#include <exception>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <future>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <tuple>
#include <mutex>
#include <sstream>
#include <string_view>
#include <thread>

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
  // wrappers go in before it is. Node's snapshot keeps what its warm-up
  // parsed.
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

// The node side, a server on stdin and stdout: it answers "ready" once the
// runtime is loaded and the warm-up drawn, then for each line "<i>" draws
// spec_<i>.json of its folder to fig_<i>.svg (or error_<i>.txt) and
// answers "<i>", one spec after the other; a line "end" is answered "end"
// once every spec before it is drawn; it ends when its input ends.
// Node compiles a function's bytecode when it first runs, which for Vega's
// parser, dataflow and SVG writer costs about as much as drawing a figure,
// and V8's inline caches learn the shapes of Vega's objects as it runs: the
// warm-up specs (the marks, scales, axes, legends, layouts, transforms and
// expressions the figures use) are drawn before the first figure. A
// snapshot (below) keeps the compiled code but not what the caches learnt,
// so node started from one draws the warm-up again, while the run reads its
// photos (figures_benchmark's BM_BenchFiguresDraw times the figures drawn
// after such a start).
constexpr const char* kServerScript = R"js(
// Vega's renderer waits for its images by asking every 10 ms whether they
// are loaded. Node has no image decoder: the load fails at once (the SVG
// keeps the image's address) and a figure with a photo would sit idle for
// the 10 ms. Asking again at the next turn of node's event loop gives the same
// SVG without the wait.
vega.ResourceLoader.prototype.ready = function() {
  const loader = this;
  return new Promise(accept => {
    (function poll(redraw) {
      if (!loader.pending()) accept(redraw);
      else setImmediate(() => poll(true));
    })(false);
  });
};
// Node has no canvas to measure text with, and Vega then takes every
// character as 0.8 em wide, about 1.4 times DejaVu Sans's mean: a figure
// with a long subtitle would come out up to a quarter wider than what it
// draws, white on the right. The widths here are DejaVu Sans's advances (what
// fontconfig gives librsvg for sans-serif on Debian), in 1/2048 em, for
// ASCII 32-126, book and bold; another character counts as a digit.
const kBookWidths = [
  651, 821, 942, 1716, 1303, 1946, 1597, 563, 799, 799, 1024, 1716, 651, 739, 651, 690, 1303, 1303,
  1303, 1303, 1303, 1303, 1303, 1303, 1303, 1303, 690, 690, 1716, 1716, 1716, 1087, 2048, 1401,
  1405, 1430, 1577, 1294, 1178, 1587, 1540, 604, 604, 1343, 1141, 1767, 1532, 1612, 1235, 1612,
  1423, 1300, 1251, 1499, 1401, 2025, 1403, 1251, 1403, 799, 690, 799, 1716, 1024, 1024, 1255,
  1300, 1126, 1300, 1260, 721, 1300, 1298, 569, 569, 1186, 569, 1995, 1298, 1253, 1300, 1300, 842,
  1067, 803, 1298, 1212, 1675, 1212, 1212, 1075, 1303, 690, 1303, 1716];
const kBoldWidths = [
  713, 934, 1067, 1716, 1425, 2052, 1786, 627, 936, 936, 1071, 1716, 778, 850, 778, 748, 1425,
  1425, 1425, 1425, 1425, 1425, 1425, 1425, 1425, 1425, 819, 819, 1716, 1716, 1716, 1188, 2048,
  1585, 1561, 1503, 1700, 1399, 1399, 1681, 1714, 762, 762, 1587, 1305, 2038, 1714, 1741, 1501,
  1741, 1577, 1475, 1397, 1663, 1585, 2259, 1579, 1483, 1485, 936, 748, 936, 1716, 1024, 1024,
  1382, 1466, 1214, 1466, 1389, 891, 1466, 1458, 702, 702, 1362, 702, 2134, 1458, 1407, 1466, 1466,
  1010, 1219, 979, 1458, 1335, 1892, 1321, 1335, 1192, 1458, 748, 1458, 1716];
vega.textMetrics.width = function(item, text) {
  const t = text == null ? '' : String(text).trim();
  const size = item.fontSize != null ? +item.fontSize || 0 : 11;
  const weight = item.fontWeight;
  const table = weight === 'bold' || weight === 'bolder' || +weight >= 600 ? kBoldWidths
                                                                          : kBookWidths;
  let units = 0;
  for (let i = 0; i < t.length; ++i) {
    const c = t.charCodeAt(i);
    units += c >= 32 && c < 127 ? table[c - 32] : table[16];
  }
  const width = units * size / 2048;
  return item.limit > 0 ? Math.min(width, +item.limit) : width;
};
async function svg(spec) {
  const view = new vega.View(vega.parse(spec), {renderer: 'none'});
  view.logLevel(vega.Error);
  const out = await view.toSVG();
  view.finalize();
  return out;
}
async function draw(dir, i) {
  try {
    const spec = JSON.parse(fs.readFileSync(path.join(dir, 'spec_' + i + '.json'), 'utf8'));
    fs.writeFileSync(path.join(dir, 'fig_' + i + '.svg'), await svg(spec));
  } catch (e) {
    fs.writeFileSync(path.join(dir, 'error_' + i + '.txt'), String(e).slice(0, 400));
  }
}
const xy = {x: {scale: 'x', field: 'x'}, y: {scale: 'y', field: 'y'}};
const points = [{x: 1, y: 2, g: 'a'}, {x: 2, y: 1, g: 'b'}, {x: 3, y: 3, g: 'a'}];
function panel(type) {
  return {type: 'group', encode: {enter: {width: {value: 60}, height: {value: 40}}},
    data: [{name: 'p', values: points, transform: [{type: 'filter', expr: 'datum.y > 0'}]}],
    scales: [
      {name: 'x', type: type, domain: {data: 'p', field: 'x'}, range: 'width', zero: false},
      {name: 'y', type: 'linear', domain: {data: 'p', field: 'y'}, range: 'height', nice: true}],
    axes: [
      {orient: 'bottom', scale: 'x', title: 'x', grid: true, tickCount: 4, labelFontSize: 10},
      {orient: 'left', scale: 'y', title: 'y', titleFontSize: 11}],
    marks: [
      {type: 'symbol', from: {data: 'p'}, encode: {enter: Object.assign({fill: {scale: 'c', field: 'g'},
        tooltip: {signal: "{'x': format(datum.x, '.3g'), 'g': datum.g}"}}, xy)}},
      {type: 'line', from: {data: 'p'}, encode: {enter: Object.assign({stroke: {value: '#444'}}, xy)}},
      {type: 'area', from: {data: 'p'}, encode: {enter: Object.assign({y2: {scale: 'y', value: 0},
        fillOpacity: {value: 0.2}}, xy)}},
      {type: 'rule', encode: {enter: {x: {value: 0}, x2: {value: 60}, y: {value: 20},
        strokeDash: {value: [3, 3]}}}},
      {type: 'text', encode: {enter: {x: {value: 30}, y: {value: 20}, text: {value: 'w'},
        align: {value: 'center'}}}}]};
}
const kWarmUps = [
  {padding: 5, background: 'white', autosize: 'pad',
    title: {text: 'panels', subtitle: ['one', 'two'], anchor: 'start', fontSize: 14},
    layout: {columns: 2, padding: {row: 10, column: 10}, bounds: 'flush', align: 'all'},
    scales: [{name: 'c', type: 'ordinal', domain: ['a', 'b'], range: 'category'}],
    legends: [{fill: 'c', title: 'g', orient: 'top', direction: 'horizontal'}],
    marks: [panel('linear'), panel('log'), panel('sqrt')]},
  {width: 40, height: 30, padding: 5, background: 'white',
    data: [{name: 'cells', values: [{u0: 0, u1: 1, v0: 0, v1: 1, value: 1, inside: true},
      {u0: 1, u1: 2, v0: 0, v1: 1, value: null, inside: false}]},
      {name: 'photo', values: [{url:
        'data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAAAAAA6fptVAAAACklEQVR4nGNoAAAAggCBd81ytgAAAABJRU5ErkJggg=='}]}],
    scales: [
      {name: 'u', type: 'linear', domain: [0, 2], range: [0, 40], zero: false, nice: false},
      {name: 'v', type: 'linear', domain: [0, 1], range: [0, 30], zero: false, nice: false},
      {name: 'k', type: 'point', domain: ['a', 'b'], range: 'width'},
      {name: 'colour', type: 'linear', scheme: 'viridis', domain: {data: 'cells', field: 'value'},
        zero: true, nice: true}],
    axes: [{orient: 'bottom', scale: 'k'}, {orient: 'left', scale: 'v', tickCount: 3}],
    legends: [{fill: 'colour', type: 'gradient', title: 's'}],
    marks: [
      {type: 'image', from: {data: 'photo'}, encode: {enter: {x: {value: 0}, y: {value: 0},
        width: {value: 40}, height: {value: 30}, aspect: {value: false}, url: {field: 'url'}}}},
      {type: 'rect', from: {data: 'cells'}, encode: {enter: {
        x: {scale: 'u', field: 'u0'}, x2: {scale: 'u', field: 'u1'},
        y: {scale: 'v', field: 'v0'}, y2: {scale: 'v', field: 'v1'},
        fill: {signal: "datum.value === null ? '#bbbbbb' : scale('colour', datum.value)"},
        fillOpacity: {signal: 'datum.inside ? 1 : 0.55'}}}}]}];
function warmUp() {
  return kWarmUps.reduce((chain, spec) => chain.then(() => svg(spec)).catch(() => {}),
                         Promise.resolve());
}
async function serve(dir, before) {
  await before;
  let chain = Promise.resolve(), pending = '';
  process.stdout.write('ready\n');
  process.stdin.setEncoding('utf8');
  process.stdin.on('data', d => {
    pending += d;
    for (let at = pending.indexOf('\n'); at >= 0; at = pending.indexOf('\n')) {
      const line = pending.slice(0, at);
      pending = pending.slice(at + 1);
      if (line === 'end') {
        chain = chain.then(() => process.stdout.write('end\n'));
        continue;
      }
      const i = Number(line);
      chain = chain.then(() => draw(dir, i)).then(() => process.stdout.write(i + '\n'));
    }
  });
  process.stdin.on('end', () => chain.then(() => process.exit(0)));
}
)js";

// The runtime read from vega.js of the folder in argv[2] (node's argv: node,
// script, folder).
constexpr const char* kLoadRuntime =
    "const fs = require('fs'), path = require('path');\n"
    "(0, eval)(fs.readFileSync(path.join(process.argv[2], 'vega.js'), 'utf8'));\n";

// Node reading the runtime itself: the server on the folder in argv[2],
// ready once the warm-up is drawn.
std::string PlainScript() {
  return std::string(kLoadRuntime) + kServerScript + "serve(process.argv[2], warmUp());\n";
}

// The script a start-up snapshot is built from (`node --build-snapshot`):
// the runtime loaded and the warm-up drawn, then the heap, compiled
// bytecode included, is written to the snapshot; node started from it
// draws the warm-up again and serves the folder in its argv[1] (node's argv
// from a snapshot: node, folder).
std::string SnapshotScript() {
  return std::string(kLoadRuntime) + kServerScript +
         "warmUp();\n"
         "require('v8').startupSnapshot.setDeserializeMainFunction(\n"
         "    () => serve(process.argv[1], warmUp()));\n";
}

// V8's flags, the same for a snapshot's build and every start from it (V8
// refuses a snapshot built with other flags).
// --no-opt: V8's optimising compiler off. One pass over a few dozen specs
// is too short for its compiled code to pay back: node takes about a third
// less CPU time for the photo session's figures (which share the machine
// with the diagnosis), and writes the same SVG bytes.
// --single-threaded: no helper threads for V8's garbage collector and
// compiler, which on a machine whose cores are busy cost more CPU than they
// save (opencv_bench_side_by_side_benchmark's run includes the figures).
// --min/max-semi-space-size=64: a young generation of 64 MB from the start.
// Drawing a figure makes short-lived objects by the megabyte (scenegraph
// items, SVG strings); in V8's default of 1 MB growing to 16 MB they are
// scavenged dozens of times per figure, and each scavenge copies what is
// still alive. figures_benchmark's BM_BenchFiguresDraw (configs/bench.yaml's
// seven figures, SVG and PNG) is about 4 % faster with it; node's resident
// memory grows from about 100 to 185 MB while it draws.
const std::vector<std::string> kNodeFlags = {"--no-opt", "--single-threaded",
                                             "--min-semi-space-size=64",
                                             "--max-semi-space-size=64"};

// 64-bit FNV-1a: a name for the snapshot's inputs.
uint64_t Fnv1a(const std::string& text, uint64_t h = 14695981039346656037ull) {
  for (const unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

// The user's cache folder for rtscalib ($XDG_CACHE_HOME/rtscalib, else
// ~/.cache/rtscalib), or "" when neither is set.
fs::path CacheDir() {
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  if (xdg && *xdg == '/') return fs::path(xdg) / "rtscalib";
  const char* home = std::getenv("HOME");
  if (home && *home == '/') return fs::path(home) / ".cache" / "rtscalib";
  return {};
}

// The program `name` on PATH, or "".
std::string FindProgram(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::istringstream dirs(path ? path : "/usr/bin:/bin");
  std::string d;
  while (std::getline(dirs, d, ':')) {
    const fs::path p = fs::path(d.empty() ? "." : d) / name;
    if (::access(p.c_str(), X_OK) == 0) return p.string();
  }
  return "";
}

// Starts argv[0] (a path) with `io` as its stdin and stdout (-1: stdin from
// /dev/null, stdout to `log`) and stderr to `log`; its pid, or -1.
// posix_spawn, not fork: glibc spawns with the parent's memory shared until
// the exec (clone with CLONE_VM | CLONE_VFORK), where fork copies the page
// tables of the whole process, its heap of observations and matrices
// included, once per program, and the child frees them again at the exec;
// a run starts node once.
pid_t Start(const std::vector<std::string>& argv, int io, const fs::path& log) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  if (::posix_spawn_file_actions_init(&actions) != 0) return -1;
  if (io >= 0) {
    ::posix_spawn_file_actions_adddup2(&actions, io, 0);
    ::posix_spawn_file_actions_adddup2(&actions, io, 1);
  } else {
    ::posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    ::posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_APPEND,
                                       0644);
  }
  ::posix_spawn_file_actions_addopen(&actions, 2, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  // The child's environment is the parent's (PATH, RTSCALIB_VEGA_DIR, ...)
  // but for what would change how node starts: NODE_OPTIONS (flags and
  // preloaded scripts of the user's own node programs; other flags than the
  // snapshot's would make node refuse it) and NODE_EXTRA_CA_CERTS (node
  // reads and parses the certificates when it starts, which costs CPU time
  // for nothing: it draws figures offline).
  std::vector<char*> env;
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string_view var(*e);
    if (var.rfind("NODE_OPTIONS=", 0) == 0 || var.rfind("NODE_EXTRA_CA_CERTS=", 0) == 0) continue;
    env.push_back(*e);
  }
  env.push_back(nullptr);
  pid_t pid = -1;
  const int err = ::posix_spawn(&pid, args[0], &actions, nullptr, args.data(), env.data());
  ::posix_spawn_file_actions_destroy(&actions);
  return err == 0 ? pid : -1;
}

// The exit status of a started program, or -1 when it did not exit normally.
int Wait(pid_t pid) {
  if (pid < 0) return -1;
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return -1;
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string Tail(const fs::path& log) {
  std::string s = ReadText(log);
  if (s.size() > 600) s = "..." + s.substr(s.size() - 600);
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  return s;
}

// Builds the snapshot `blob` with node (its folder made when missing):
// written beside it under a name of its own, then renamed, so that a run
// reading it never sees half a file and two runs building it at once each
// leave a whole one. `work` is a folder for the scripts and the log.
bool BuildSnapshot(const std::string& node, const std::string& runtime, const fs::path& blob,
                   const fs::path& work) {
  std::error_code ec;
  fs::create_directories(blob.parent_path(), ec);
  if (ec) return false;
  std::string tmp = blob.string() + ".XXXXXX";
  const int fd = ::mkstemp(tmp.data());
  if (fd < 0) return false;
  ::close(fd);
  std::ofstream(work / "vega.js", std::ios::binary) << runtime;
  std::ofstream(work / "snapshot.js", std::ios::binary) << SnapshotScript();
  std::vector<std::string> argv = {node};
  argv.insert(argv.end(), kNodeFlags.begin(), kNodeFlags.end());
  argv.insert(argv.end(), {"--snapshot-blob", tmp, "--build-snapshot",
                           (work / "snapshot.js").string(), work.string()});
  const bool built = Wait(Start(argv, -1, work / "log.txt")) == 0 && fs::file_size(tmp, ec) > 0;
  if (built) fs::rename(tmp, blob, ec);
  if (!built || ec) {
    fs::remove(tmp, ec);
    return false;
  }
  // The snapshots of another node or runtime are replaced by this one.
  for (const fs::directory_entry& e : fs::directory_iterator(blob.parent_path(), ec)) {
    const std::string name = e.path().filename().string();
    if (e.path() != blob && name.rfind("vega-", 0) == 0 && e.path().extension() == ".blob") {
      fs::remove(e.path(), ec);
    }
  }
  return true;
}

// The PNG of each figure handed over by Add, drawn on a thread of its own
// one after the other, then given to `drawn`; a figure librsvg cannot draw
// keeps its error and no SVG. Finish (or the destructor) waits for the
// last; Finish rethrows the first thing `drawn` threw (the figures after it
// are drawn but not handed over).
class PngQueue {
 public:
  PngQueue(const SvgRasterizer& raster, const VegaRenderer::Drawn& drawn)
      : raster_(raster), drawn_(drawn), thread_([this] {
          raster_.WarmUp();  // while node draws the first SVG
          Run();
        }) {}
  ~PngQueue() { Stop(); }
  PngQueue(const PngQueue&) = delete;
  PngQueue& operator=(const PngQueue&) = delete;

  // Figure `i`, its SVG in *fig (which stays where it is until Finish).
  void Add(size_t i, RenderedFigure* fig) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      queue_.emplace_back(i, fig);
    }
    wake_.notify_one();
  }
  // Called once nothing more is added: the calling thread, which would
  // only wait, draws PNGs of the queue beside the queue's own thread. While
  // node drew, the queue's thread kept pace with it on the other core; once
  // node is done its core is free for the PNGs still waiting.
  void Finish() {
    Close();
    Run();
    Stop();
    if (failed_) std::rethrow_exception(failed_);
  }

 private:
  void Close() {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      closed_ = true;
    }
    wake_.notify_all();
  }
  void Stop() {
    if (!thread_.joinable()) return;
    Close();
    thread_.join();
  }
  void Run() {
    for (;;) {
      size_t i = 0;
      RenderedFigure* next = nullptr;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [this] { return !queue_.empty() || closed_; });
        if (queue_.empty()) return;  // closed, and nothing left
        std::tie(i, next) = queue_.front();
        queue_.pop_front();
      }
      RenderedFigure& fig = *next;
      if (!raster_.ToPng(fig.svg, &fig.png, &fig.error)) {
        fig.svg.clear();
        fig.png.clear();
        continue;
      }
      if (!drawn_) continue;
      try {
        if (!Failed()) drawn_(i, fig);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(mutex_);
        if (!failed_) failed_ = std::current_exception();
      }
    }
  }
  bool Failed() {
    const std::lock_guard<std::mutex> lock(mutex_);
    return failed_ != nullptr;
  }

  const SvgRasterizer& raster_;
  const VegaRenderer::Drawn& drawn_;
  std::mutex mutex_;  // guards queue_, closed_ and failed_
  std::condition_variable wake_;
  std::deque<std::pair<size_t, RenderedFigure*>> queue_;
  bool closed_ = false;
  std::exception_ptr failed_;
  std::thread thread_;
};

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

std::string VegaSnapshotPath(const std::string& node) {
  const fs::path cache = CacheDir();
  std::error_code ec;
  const fs::path program = fs::canonical(node, ec);
  struct stat st {};
  if (cache.empty() || ec || ::stat(program.c_str(), &st) != 0) return "";
  const std::string& runtime = VegaRuntime();
  if (runtime.empty()) return "";
  // What V8 needs to be the same to start from the snapshot (node's binary:
  // its path, size and time of change) and what the snapshot holds.
  std::string inputs = program.string() + "\n" + std::to_string(st.st_size) + "\n" +
                       std::to_string(st.st_mtim.tv_sec) + "." +
                       std::to_string(st.st_mtim.tv_nsec) + "\n";
  for (const std::string& f : kNodeFlags) inputs += f + "\n";
  uint64_t h = Fnv1a(inputs);
  h = Fnv1a(SnapshotScript(), h);
  h = Fnv1a(runtime, h);
  char name[64];
  std::snprintf(name, sizeof name, "vega-%016llx.blob", static_cast<unsigned long long>(h));
  return (cache / name).string();
}

struct VegaRenderer::State {
  std::string missing;  // what is not installed, "" when everything is
  std::string failure;  // why node could not be started, "" when it was
  std::string node;     // node's path
  std::string how;      // how node was started (VegaRenderer::how)
  fs::path dir;         // the temporary folder: specs, SVG files, log (vega.js, scripts)
  pid_t pid = -1;
  int socket = -1;      // our end of node's stdin and stdout
  std::string received;  // node's output not yet read as lines
  std::shared_future<void> started;  // node's start (Add and Collect wait for it)
  // The specs handed over (Add) and whether End came: Collect, on another
  // thread, reads them once End has come.
  std::mutex mutex;
  std::condition_variable end_came;
  std::set<size_t> added;
  bool ended = false;

  bool Ready() const { return missing.empty() && failure.empty() && socket >= 0; }

  // Node started with `args` after its path and flags, in `dir`; true once
  // it has answered "ready". A node that ends first (a snapshot it cannot
  // read, a flag it does not know) or says nothing for a minute is stopped.
  bool Spawn(const std::vector<std::string>& args, bool flags) {
    int fds[2];
    if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0) return false;
    std::vector<std::string> argv = {node};
    if (flags) argv.insert(argv.end(), kNodeFlags.begin(), kNodeFlags.end());
    argv.insert(argv.end(), args.begin(), args.end());
    pid = Start(argv, fds[1], dir / "log.txt");
    ::close(fds[1]);
    if (pid < 0) {
      ::close(fds[0]);
      return false;
    }
    socket = fds[0];
    std::string line;
    if (ReadLine(&line, 60000) && line == "ready") return true;
    ::kill(pid, SIGKILL);  // a node that hangs would not end with its input
    Stop();
    return false;
  }
  // Node's input ends: it exits (Stop waits for it).
  void CloseInput() {
    if (socket >= 0) ::close(socket);
    socket = -1;
  }
  void Stop() {
    CloseInput();
    if (pid > 0) Wait(pid);
    pid = -1;
    received.clear();
  }
  // One line from node, or false when its output ended (or, with
  // timeout_ms >= 0, nothing came for that long).
  bool ReadLine(std::string* line, int timeout_ms = -1) {
    for (;;) {
      const size_t at = received.find('\n');
      if (at != std::string::npos) {
        *line = received.substr(0, at);
        received.erase(0, at + 1);
        return true;
      }
      pollfd p{socket, POLLIN, 0};
      const int ready = ::poll(&p, 1, timeout_ms);
      if (ready < 0 && errno == EINTR) continue;
      if (ready <= 0) return false;
      char chunk[256];
      const ssize_t n = ::recv(socket, chunk, sizeof chunk, 0);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return false;
      received.append(chunk, static_cast<size_t>(n));
    }
  }
  bool Send(const std::string& text) {
    for (size_t done = 0; done < text.size();) {
      // MSG_NOSIGNAL: a node that died gives EPIPE here, not a SIGPIPE
      // that would end this process.
      const ssize_t n = ::send(socket, text.data() + done, text.size() - done, MSG_NOSIGNAL);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return false;
      done += static_cast<size_t>(n);
    }
    return true;
  }
  // Node started from the snapshot (built first when missing), else with
  // the runtime read from the folder, else the same without V8's flags (a
  // node that does not know them).
  void StartNode(const std::string& runtime) {
    const fs::path blob = VegaSnapshotPath(node);
    std::error_code ec;
    if (!blob.empty()) {
      const bool built = !fs::exists(blob, ec) && BuildSnapshot(node, runtime, blob, dir);
      if (fs::exists(blob, ec)) {
        if (Spawn({"--snapshot-blob", blob.string(), dir.string()}, true)) {
          how = std::string(built ? "built the snapshot " : "started from the snapshot ") +
                blob.string();
          return;
        }
        // Unreadable (damaged, or made by another node of the same name):
        // the next run builds it again.
        fs::remove(blob, ec);
      }
    }
    std::ofstream(dir / "vega.js", std::ios::binary) << runtime;
    std::ofstream(dir / "render.js", std::ios::binary) << PlainScript();
    const std::vector<std::string> plain = {(dir / "render.js").string(), dir.string()};
    if (Spawn(plain, true) || Spawn(plain, false)) {
      how = "read the runtime (no snapshot" +
            std::string(blob.empty() ? ": no cache folder, $XDG_CACHE_HOME or $HOME" : "") + ")";
      return;
    }
    failure = "cannot start " + node + ": " + Tail(dir / "log.txt");
  }
};

VegaRenderer::VegaRenderer() : state_(std::make_unique<State>()) {
  State* s = state_.get();
  s->started = std::async(std::launch::async, [s] {
    std::string missing;
    const std::string& runtime = VegaRuntime(&missing);
    s->node = !FindProgram("node").empty() ? FindProgram("node") : FindProgram("nodejs");
    const SvgRasterizer& raster = SvgRasterizer::Get();  // opens librsvg meanwhile
    // Fontconfig and the fonts are loaded while node starts.
    std::thread warm_up([&raster] { raster.WarmUp(); });
    struct Join {
      std::thread& t;
      ~Join() { t.join(); }
    } join{warm_up};
    if (runtime.empty() || s->node.empty() || !raster.missing().empty()) {
      s->missing = runtime.empty() ? "the Vega modules are missing: " + missing
                   : s->node.empty()
                       ? std::string("node is not installed (Debian package nodejs)")
                       : raster.missing();
      return;
    }
    std::string tmpl = (fs::temp_directory_path() / "rtscalib-figures-XXXXXX").string();
    if (!::mkdtemp(tmpl.data())) {
      s->failure = "cannot make a temporary folder";
      return;
    }
    s->dir = tmpl;
    s->StartNode(runtime);
  });
}

VegaRenderer::~VegaRenderer() {
  if (state_->started.valid()) state_->started.wait();
  state_->Stop();
  if (!state_->dir.empty()) {
    std::error_code ec;
    fs::remove_all(state_->dir, ec);
  }
}

const std::string& VegaRenderer::how() {
  if (state_->started.valid()) state_->started.get();
  return state_->how;
}

void VegaRenderer::Add(size_t index, const std::string& spec) {
  State& s = *state_;
  if (s.started.valid()) s.started.get();
  {
    const std::lock_guard<std::mutex> lock(s.mutex);
    if (s.ended || !s.added.insert(index).second) {
      throw std::logic_error("VegaRenderer::Add: spec " + std::to_string(index) +
                             (s.ended ? " after End" : " added twice"));
    }
  }
  if (!s.Ready()) return;
  std::ofstream(s.dir / ("spec_" + std::to_string(index) + ".json"), std::ios::binary) << spec;
  // A node that has died fails the send; Collect then says why.
  s.Send(std::to_string(index) + "\n");
}

void VegaRenderer::End() {
  State& s = *state_;
  if (s.started.valid()) s.started.get();
  const std::lock_guard<std::mutex> lock(s.mutex);
  if (s.ended) return;
  // Node answers "end" once it has drawn every spec sent before it. Sent
  // before `ended` is set: Collect closes node's input only after that.
  if (s.Ready()) s.Send("end\n");
  s.ended = true;
  s.end_came.notify_all();
}

std::vector<RenderedFigure> VegaRenderer::Collect(std::string* note, const Drawn& drawn) {
  State& s = *state_;
  if (s.started.valid()) s.started.get();
  note->clear();
  if (!s.missing.empty()) {
    *note = "figures: no PNG files written (report.html and figures/*.vg.json have them): " +
            s.missing + "; scripts/install-deps.sh installs it";
    return {};
  }
  if (!s.failure.empty()) {
    *note = "figures: no PNG files written: " + s.failure;
    return {};
  }
  const SvgRasterizer& raster = SvgRasterizer::Get();
  // Each answer where the PNG thread finds it while later answers come.
  std::map<size_t, RenderedFigure> answered;
  bool node_ended = true;
  {
    // The PNGs are drawn by one thread of this process, in the order node
    // answers, each while node draws the next SVG: one thread, so that on
    // two cores node keeps one of its own (the PNGs take about as long as
    // node's SVGs; a thread per PNG had two or three of them, the
    // diagnosis and the reports' writing share node's core). Once node is
    // done, this thread draws beside it.
    PngQueue pngs(raster, drawn);
    std::string line;
    while (s.ReadLine(&line)) {
      if (line == "end") {
        node_ended = false;
        break;
      }
      const long i = std::strtol(line.c_str(), nullptr, 10);
      if (i < 0 || answered.count(static_cast<size_t>(i)) != 0) continue;
      RenderedFigure& fig = answered[static_cast<size_t>(i)];
      fig.svg = ReadText(s.dir / ("fig_" + std::to_string(i) + ".svg"));
      if (fig.svg.empty()) {
        fig.error = ReadText(s.dir / ("error_" + std::to_string(i) + ".txt"));
        if (fig.error.empty()) fig.error = "no SVG written";
        continue;
      }
      pngs.Add(static_cast<size_t>(i), &fig);
    }
    {
      // Node that ended early: no spec comes after End.
      std::unique_lock<std::mutex> lock(s.mutex);
      s.end_came.wait(lock, [&] { return s.ended; });
    }
    // Node takes a while to exit (its heap of tens of megabytes): the PNGs
    // still waiting are drawn meanwhile.
    s.CloseInput();
    pngs.Finish();  // rethrows what `drawn` threw
    s.Stop();
  }
  std::vector<RenderedFigure> out(s.added.empty() ? 0 : *s.added.rbegin() + 1);
  bool lost = false;
  for (size_t i = 0; i < out.size(); ++i) {
    const auto a = answered.find(i);
    if (a != answered.end()) {
      out[i] = std::move(a->second);
    } else if (s.added.count(i) != 0) {
      out[i].error = "node stopped before drawing it";
      lost = true;
    } else {
      out[i].error = "not handed to the renderer";
    }
  }
  if (lost || node_ended) {
    *note = "figures: node failed rendering the specs: " + Tail(s.dir / "log.txt");
  }
  return out;
}

std::vector<RenderedFigure> VegaRenderer::Draw(const std::vector<nlohmann::json>& specs,
                                               std::string* note, const Drawn& drawn) {
  if (specs.empty()) {
    End();
    return {};
  }
  std::vector<std::string> texts;
  std::vector<size_t> bytes;
  for (const nlohmann::json& spec : specs) {
    texts.push_back(spec.dump());
    bytes.push_back(texts.back().size());
  }
  for (size_t i : LargestFirst(bytes)) Add(i, texts[i]);
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

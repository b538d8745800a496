#include "app/vega.h"

#include "app/svg_raster.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <future>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <mutex>
#include <sstream>

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

// The node side, a server on stdin and stdout: it reads the runtime, then
// for each line "<i>" draws spec_<i>.json of its folder to fig_<i>.svg (or
// error_<i>.txt) and answers "<i>", one spec after the other; it ends when
// its input ends. Before the first spec it draws a small one with the marks,
// axes and legend the figures use, so that V8 has compiled their code when
// the first figure comes.
constexpr const char* kRenderScript = R"js(
const fs = require('fs'), path = require('path');
const dir = process.argv[2];
(0, eval)(fs.readFileSync(path.join(dir, 'vega.js'), 'utf8'));
async function svg(spec) {
  const view = new vega.View(vega.parse(spec), {renderer: 'none'});
  view.logLevel(vega.Error);
  const out = await view.toSVG();
  view.finalize();
  return out;
}
async function draw(i) {
  try {
    const spec = JSON.parse(fs.readFileSync(path.join(dir, 'spec_' + i + '.json'), 'utf8'));
    fs.writeFileSync(path.join(dir, 'fig_' + i + '.svg'), await svg(spec));
  } catch (e) {
    fs.writeFileSync(path.join(dir, 'error_' + i + '.txt'), String(e).slice(0, 400));
  }
}
const warm = {
  width: 60, height: 40, padding: 5,
  data: [{name: 't', values: [{x: 1, y: 2, g: 'a'}, {x: 2, y: 1, g: 'b'}]}],
  scales: [
    {name: 'x', type: 'linear', domain: {data: 't', field: 'x'}, range: 'width', nice: true},
    {name: 'y', type: 'linear', domain: {data: 't', field: 'y'}, range: 'height', zero: true},
    {name: 'c', type: 'ordinal', domain: {data: 't', field: 'g'}, range: 'category'}],
  axes: [{orient: 'bottom', scale: 'x', title: 'x', grid: true}, {orient: 'left', scale: 'y'}],
  legends: [{fill: 'c', title: 'g', orient: 'top'}],
  marks: [
    {type: 'symbol', from: {data: 't'}, encode: {enter: {x: {scale: 'x', field: 'x'},
      y: {scale: 'y', field: 'y'}, fill: {scale: 'c', field: 'g'}, tooltip: {field: 'g'}}}},
    {type: 'line', from: {data: 't'}, encode: {enter: {x: {scale: 'x', field: 'x'},
      y: {scale: 'y', field: 'y'}, stroke: {value: '#444'}}}},
    {type: 'area', from: {data: 't'}, encode: {enter: {x: {scale: 'x', field: 'x'},
      y: {scale: 'y', field: 'y'}, y2: {scale: 'y', value: 0}, fillOpacity: {value: 0.2}}}},
    {type: 'rect', from: {data: 't'}, encode: {enter: {x: {scale: 'x', field: 'x'}, width: {value: 3},
      y: {scale: 'y', field: 'y'}, y2: {scale: 'y', value: 0}}}},
    {type: 'rule', encode: {enter: {x: {value: 0}, x2: {value: 60}, y: {value: 20},
      strokeDash: {value: [3, 3]}}}},
    {type: 'text', encode: {enter: {x: {value: 30}, y: {value: 20}, text: {value: 'w'},
      align: {value: 'center'}}}}]};
let chain = svg(warm).catch(() => {}), pending = '';
process.stdin.setEncoding('utf8');
process.stdin.on('data', d => {
  pending += d;
  for (let at = pending.indexOf('\n'); at >= 0; at = pending.indexOf('\n')) {
    const i = Number(pending.slice(0, at));
    pending = pending.slice(at + 1);
    chain = chain.then(() => draw(i)).then(() => process.stdout.write(i + '\n'));
  }
});
process.stdin.on('end', () => chain.then(() => process.exit(0)));
)js";

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

// Starts argv[0] (a path) with `io` as its stdin and stdout and stderr to
// `log`; its pid, or -1.
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
  ::posix_spawn_file_actions_adddup2(&actions, io, 0);
  ::posix_spawn_file_actions_adddup2(&actions, io, 1);
  ::posix_spawn_file_actions_addopen(&actions, 2, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  pid_t pid = -1;
  // The child's environment is the parent's (PATH, RTSCALIB_VEGA_DIR, ...).
  const int err = ::posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ);
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
  std::string missing;  // what is not installed, "" when everything is
  std::string failure;  // why node could not be started, "" when it was
  std::string node;     // node's path
  fs::path dir;         // the temporary folder: vega.js, render.js, specs, SVG files
  pid_t pid = -1;
  int socket = -1;      // our end of node's stdin and stdout
  bool no_opt = true;   // node started with --no-opt --single-threaded
  std::future<void> started;

  // Node started in `dir` (--no-opt: see Spawn); false when it could not be.
  bool Spawn() {
    int fds[2];
    if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0) return false;
    // --no-opt: V8's optimising compiler off. One pass over a few dozen
    // specs is too short for its compiled code to pay back: node takes about
    // a third less CPU time for the photo session's figures (which share the
    // machine with the diagnosis), and writes the same SVG bytes.
    // --single-threaded: no helper threads for V8's garbage collector and
    // compiler, which on a machine whose cores are busy cost more than they
    // save (the bench's figures: 0.24 instead of 0.27 s of CPU).
    std::vector<std::string> argv = {node};
    if (no_opt) argv.insert(argv.end(), {"--no-opt", "--single-threaded"});
    argv.insert(argv.end(), {(dir / "render.js").string(), dir.string()});
    pid = Start(argv, fds[1], dir / "log.txt");
    ::close(fds[1]);
    if (pid < 0) {
      ::close(fds[0]);
      return false;
    }
    socket = fds[0];
    return true;
  }
  void Stop() {
    if (socket >= 0) ::close(socket);  // node's input ends: it exits
    socket = -1;
    if (pid > 0) Wait(pid);
    pid = -1;
  }
  // One line "<i>" from node, or -1 when its output ended.
  int ReadIndex(std::string* buffer) {
    for (;;) {
      const size_t at = buffer->find('\n');
      if (at != std::string::npos) {
        const std::string line = buffer->substr(0, at);
        buffer->erase(0, at + 1);
        return std::atoi(line.c_str());
      }
      char chunk[256];
      const ssize_t n = ::recv(socket, chunk, sizeof chunk, 0);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return -1;
      buffer->append(chunk, static_cast<size_t>(n));
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
};

VegaRenderer::VegaRenderer() : state_(std::make_unique<State>()) {
  State* s = state_.get();
  s->started = std::async(std::launch::async, [s] {
    std::string missing;
    const std::string& runtime = VegaRuntime(&missing);
    s->node = !FindProgram("node").empty() ? FindProgram("node") : FindProgram("nodejs");
    const SvgRasterizer& raster = SvgRasterizer::Get();  // opens librsvg meanwhile
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
    std::ofstream(s->dir / "vega.js", std::ios::binary) << runtime;
    std::ofstream(s->dir / "render.js", std::ios::binary) << kRenderScript;
    if (!s->Spawn()) s->failure = "cannot start " + s->node;
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

std::vector<RenderedFigure> VegaRenderer::Draw(const std::vector<nlohmann::json>& specs,
                                               std::string* note) {
  State& s = *state_;
  if (s.started.valid()) s.started.get();
  if (specs.empty()) return {};
  if (!s.missing.empty()) {
    *note = "figures: no PNG files written (report.html and figures/*.vg.json have them): " +
            s.missing + "; scripts/install-deps.sh installs it";
    return {};
  }
  if (!s.failure.empty()) {
    *note = "figures: no PNG files written: " + s.failure;
    return {};
  }
  std::vector<std::pair<size_t, size_t>> by_size;  // spec's bytes, index
  for (size_t i = 0; i < specs.size(); ++i) {
    const std::string text = specs[i].dump();
    std::ofstream(s.dir / ("spec_" + std::to_string(i) + ".json"), std::ios::binary) << text;
    by_size.emplace_back(text.size(), i);
  }
  // The largest specs first: their SVG files are the largest too, and the
  // PNG of the last SVG, drawn after node is done, is then a small one.
  std::stable_sort(by_size.begin(), by_size.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  const SvgRasterizer& raster = SvgRasterizer::Get();
  std::vector<RenderedFigure> out(specs.size());
  std::vector<std::future<std::string>> png(specs.size());  // each PNG's error, "" when drawn
  std::string requests;
  for (const auto& [bytes, i] : by_size) requests += std::to_string(i) + "\n";
  size_t answered = 0;
  for (int attempt = 0; attempt < 2 && answered == 0; ++attempt) {
    // A node that does not know the flags ends at once: it is asked again
    // without them.
    if (attempt == 1) {
      s.Stop();
      if (s.no_opt) {
        s.no_opt = false;
        if (!s.Spawn()) break;
      } else {
        break;
      }
    }
    if (!s.Send(requests)) continue;
    std::string buffer;
    for (int i = s.ReadIndex(&buffer); i >= 0; i = s.ReadIndex(&buffer)) {
      if (i >= static_cast<int>(specs.size()) || png[i].valid()) continue;
      ++answered;
      out[i].svg = ReadText(s.dir / ("fig_" + std::to_string(i) + ".svg"));
      if (out[i].svg.empty()) {
        out[i].error = ReadText(s.dir / ("error_" + std::to_string(i) + ".txt"));
        if (out[i].error.empty()) out[i].error = "no SVG written";
      } else {
        png[i] = std::async(std::launch::async, [&raster, &fig = out[i]] {
          std::string error;
          if (!raster.ToPng(fig.svg, &fig.png, &error)) return error;
          return std::string();
        });
      }
      if (answered == specs.size()) break;
    }
  }
  s.Stop();
  std::string png_error;
  for (std::future<std::string>& f : png) {
    if (!f.valid()) continue;
    const std::string error = f.get();
    if (!error.empty() && png_error.empty()) png_error = error;
  }
  if (answered < specs.size()) {
    *note = "figures: no PNG files written: node failed rendering the specs: " +
            Tail(s.dir / "log.txt");
    return {};
  }
  if (!png_error.empty()) {
    *note = "figures: no PNG files written: " + png_error;
    return {};
  }
  return out;
}

std::vector<RenderedFigure> RenderFigures(const std::vector<nlohmann::json>& specs,
                                          std::string* note) {
  VegaRenderer renderer;
  return renderer.Draw(specs, note);
}

}  // namespace rtscalib::app

#include "app/vega.h"

#include "app/svg_raster.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
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

// The node side: every spec_<i>.json of a folder to fig_<i>.svg.
constexpr const char* kRenderScript = R"js(
const fs = require('fs'), path = require('path');
const dir = process.argv[2], n = Number(process.argv[3]);
(0, eval)(fs.readFileSync(path.join(dir, 'vega.js'), 'utf8'));
(async () => {
  for (let i = 0; i < n; ++i) {
    try {
      const spec = JSON.parse(fs.readFileSync(path.join(dir, 'spec_' + i + '.json'), 'utf8'));
      const view = new vega.View(vega.parse(spec), {renderer: 'none'});
      view.logLevel(vega.Error);
      fs.writeFileSync(path.join(dir, 'fig_' + i + '.svg'), await view.toSVG());
      view.finalize();
    } catch (e) {
      fs.writeFileSync(path.join(dir, 'error_' + i + '.txt'), String(e).slice(0, 400));
    }
  }
})().catch(e => { console.error(String((e && e.stack) || e)); process.exit(1); });
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

// Starts argv[0] (a path) with stdout and stderr to `log`; its pid, or -1.
// posix_spawn, not fork: glibc spawns with the parent's memory shared until
// the exec (clone with CLONE_VM | CLONE_VFORK), where fork copies the page
// tables of the whole process, its heap of observations and matrices
// included, once per program, and the child frees them again at the exec;
// a run starts node once.
pid_t Start(const std::vector<std::string>& argv, const fs::path& log) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  if (::posix_spawn_file_actions_init(&actions) != 0) return -1;
  ::posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  ::posix_spawn_file_actions_adddup2(&actions, 1, 2);
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

int Run(const std::vector<std::string>& argv, const fs::path& log) {
  return Wait(Start(argv, log));
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

std::vector<RenderedFigure> RenderFigures(const std::vector<nlohmann::json>& specs,
                                          std::string* note) {
  if (specs.empty()) return {};
  std::string missing;
  const std::string& runtime = VegaRuntime(&missing);
  const std::string node =
      !FindProgram("node").empty() ? FindProgram("node") : FindProgram("nodejs");
  const SvgRasterizer& raster = SvgRasterizer::Get();
  if (runtime.empty() || node.empty() || !raster.missing().empty()) {
    *note = "figures: no PNG files written (report.html and figures/*.vg.json have them): " +
            (runtime.empty() ? "the Vega modules are missing: " + missing
             : node.empty()  ? std::string("node is not installed (Debian package nodejs)")
                             : raster.missing()) +
            "; scripts/install-deps.sh installs it";
    return {};
  }
  std::string tmpl = (fs::temp_directory_path() / "rtscalib-figures-XXXXXX").string();
  if (!::mkdtemp(tmpl.data())) {
    *note = "figures: no PNG files written: cannot make a temporary folder";
    return {};
  }
  const fs::path dir = tmpl;
  struct Cleanup {
    fs::path dir;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(dir, ec);
    }
  } cleanup{dir};
  std::ofstream(dir / "vega.js", std::ios::binary) << runtime;
  std::ofstream(dir / "render.js", std::ios::binary) << kRenderScript;
  for (size_t i = 0; i < specs.size(); ++i) {
    std::ofstream(dir / ("spec_" + std::to_string(i) + ".json"), std::ios::binary)
        << specs[i].dump();
  }
  const fs::path log = dir / "log.txt";
  // --no-opt: V8's optimising compiler off. One pass over a few dozen specs
  // is too short for its compiled code to pay back: node takes about a third
  // less CPU time for the photo session's figures (which share the machine
  // with the diagnosis), and writes the same SVG bytes. A node that does not
  // know the flag is asked again without it.
  const std::vector<std::string> args = {(dir / "render.js").string(), dir.string(),
                                         std::to_string(specs.size())};
  auto run_node = [&](const std::vector<std::string>& flags) {
    std::vector<std::string> argv = {node};
    argv.insert(argv.end(), flags.begin(), flags.end());
    argv.insert(argv.end(), args.begin(), args.end());
    return Run(argv, log);
  };
  if (run_node({"--no-opt"}) != 0 && run_node({}) != 0) {
    *note = "figures: no PNG files written: node failed rendering the specs: " + Tail(log);
    return {};
  }
  std::vector<RenderedFigure> out(specs.size());
  for (size_t i = 0; i < specs.size(); ++i) {
    out[i].svg = ReadText(dir / ("fig_" + std::to_string(i) + ".svg"));
    if (out[i].svg.empty()) {
      out[i].error = ReadText(dir / ("error_" + std::to_string(i) + ".txt"));
      if (out[i].error.empty()) out[i].error = "no SVG written";
      continue;
    }
    std::string error;
    if (!raster.ToPng(out[i].svg, &out[i].png, &error)) {
      *note = "figures: no PNG files written: " + error;
      return {};
    }
  }
  return out;
}

}  // namespace rtscalib::app

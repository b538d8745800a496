#include "render/headless.h"

#include <X11/Xlib.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

namespace rtscalib::render {
namespace {

bool PathExists(const std::string& path) {
  struct stat st;
  return ::lstat(path.c_str(), &st) == 0;
}

bool DisplayLooksFree(int n) {
  return !PathExists("/tmp/.X11-unix/X" + std::to_string(n)) &&
         !PathExists("/tmp/.X" + std::to_string(n) + "-lock");
}

std::string ReadTail(const std::string& path, size_t max_chars) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  std::string s = ss.str();
  if (s.size() > max_chars) s = "..." + s.substr(s.size() - max_chars);
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  return s;
}

// The pid in display n's lock file (Xvfb writes its own), -1 if none.
pid_t LockOwner(int n) {
  std::ifstream in("/tmp/.X" + std::to_string(n) + "-lock");
  long pid = -1;
  if (!(in >> pid)) return -1;
  return static_cast<pid_t>(pid);
}

// Tries to open `display`; the X handshake only completes once the server
// serves clients, so success means "ready".
bool AcceptsConnections(const std::string& display) {
  Display* d = XOpenDisplay(display.c_str());
  if (d == nullptr) return false;
  XCloseDisplay(d);
  return true;
}

void StopServer(pid_t pid) {
  if (pid <= 0) return;
  ::kill(pid, SIGTERM);
  for (int i = 0; i < 200; ++i) {  // up to 2 s, then force
    if (::waitpid(pid, nullptr, WNOHANG) == pid) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ::kill(pid, SIGKILL);
  ::waitpid(pid, nullptr, 0);
}

// Starts Xvfb on display n with stdout/stderr to `log`. The server gets
// SIGTERM when the thread that started it dies, so a crashed run leaves no
// orphaned server behind.
pid_t SpawnXvfb(const std::string& xvfb, int n, const std::string& screen, const std::string& log) {
  const std::string disp = ":" + std::to_string(n);
  // -noreset: by default an X server resets when its last client leaves, and a
  // client connecting during the reset is refused; the readiness probe below
  // would trigger exactly that.
  std::vector<std::string> args = {xvfb,   disp,        "-screen", "0",
                                   screen, "-nolisten", "tcp",     "-noreset"};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    // Only async-signal-safe calls between fork and exec.
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (::getppid() != parent) ::_exit(127);
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    if (fd >= 0) {
      ::dup2(fd, STDOUT_FILENO);
      ::dup2(fd, STDERR_FILENO);
      ::close(fd);
    }
    const int null_fd = ::open("/dev/null", O_RDONLY);
    if (null_fd >= 0) ::dup2(null_fd, STDIN_FILENO);
    ::setpgid(0, 0);  // keep terminal signals (Ctrl-C) for the parent to handle
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  return pid;
}

}  // namespace

std::string HeadlessOptions::Check() const {
  if (xvfb.empty()) return "xvfb: expected a program name, got an empty string";
  if (screen.empty()) return "screen: expected WxHxD (e.g. 1920x1080x24), got an empty string";
  if (first_display < 0)
    return "first_display: expected >= 0, got " + std::to_string(first_display);
  if (max_tries < 1) return "max_tries: expected >= 1, got " + std::to_string(max_tries);
  if (!(start_timeout_s > 0)) return "start_timeout_s: expected > 0";
  return "";
}

std::string FindExecutable(const std::string& program) {
  if (program.find('/') != std::string::npos) {
    return ::access(program.c_str(), X_OK) == 0 ? program : "";
  }
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path != nullptr ? path : "/usr/local/bin:/usr/bin:/bin");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (dir.empty()) dir = ".";
    const std::string full = dir + "/" + program;
    struct stat st;
    if (::stat(full.c_str(), &st) == 0 && S_ISREG(st.st_mode) &&
        ::access(full.c_str(), X_OK) == 0) {
      return full;
    }
  }
  return "";
}

HeadlessDisplay::HeadlessDisplay(const HeadlessOptions& options) {
  if (const std::string msg = options.Check(); !msg.empty()) {
    throw DisplayError("HeadlessOptions: " + msg);
  }
  const char* existing = std::getenv("DISPLAY");
  if (existing != nullptr && existing[0] != '\0') {
    display_ = existing;
    return;
  }
  const std::string xvfb = FindExecutable(options.xvfb);
  if (xvfb.empty()) {
    throw DisplayError(
        "DISPLAY is unset and '" + options.xvfb +
        "' was not found on PATH: VTK renders through GLX and needs an X server. "
        "Install Xvfb (Debian: apt-get install xvfb) or set DISPLAY to a running X server.");
  }

  char log_template[] = "/tmp/rtscalib-xvfb-XXXXXX";
  const int log_fd = ::mkstemp(log_template);
  if (log_fd >= 0) ::close(log_fd);
  const std::string log = log_template;

  std::string last_failure;
  int n = options.first_display;
  for (int tries = 0; tries < options.max_tries; ++n) {
    if (!DisplayLooksFree(n)) continue;
    ++tries;
    const pid_t pid = SpawnXvfb(xvfb, n, options.screen, log);
    if (pid < 0) {
      ::unlink(log.c_str());
      throw DisplayError(std::string("could not fork to start Xvfb: ") + std::strerror(errno));
    }
    const std::string disp = ":" + std::to_string(n);
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(options.start_timeout_s);
    bool exited = false, ready = false;
    while (std::chrono::steady_clock::now() < deadline) {
      int status = 0;
      if (::waitpid(pid, &status, WNOHANG) == pid) {
        exited = true;
        last_failure = "Xvfb " + disp + " exited (status " + std::to_string(status) +
                       "): " + ReadTail(log, 400);
        break;
      }
      // Ready only when the server on :n is ours: another process may have
      // raced us to the same number (our server then exits, next number).
      if (LockOwner(n) == pid && AcceptsConnections(disp)) {
        ready = true;
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    if (ready) {
      ::unlink(log.c_str());
      server_pid_ = pid;
      display_ = disp;
      SetEnv("DISPLAY", display_);
      SetEnv("LIBGL_ALWAYS_SOFTWARE", "1");
      SetEnv("GALLIUM_DRIVER", "llvmpipe");
      return;
    }
    if (!exited) {
      StopServer(pid);
      const std::string tail = ReadTail(log, 400);
      ::unlink(log.c_str());
      throw DisplayError("Xvfb " + disp + " did not accept connections within " +
                         std::to_string(options.start_timeout_s) + " s" +
                         (tail.empty() ? std::string() : ": " + tail));
    }
    // Lost a race for this display number (another server took it): next one.
  }
  ::unlink(log.c_str());
  throw DisplayError("could not start Xvfb on any of " + std::to_string(options.max_tries) +
                     " free display numbers from :" + std::to_string(options.first_display) +
                     "; last failure: " + last_failure);
}

HeadlessDisplay::~HeadlessDisplay() {
  if (server_pid_ > 0) {
    StopServer(server_pid_);
    RestoreEnv();
  }
}

void HeadlessDisplay::SetEnv(const char* name, const std::string& value) {
  SavedVar& s = saved_[num_saved_++];
  s.name = name;
  const char* old = std::getenv(name);
  s.was_set = old != nullptr;
  if (old != nullptr) s.value = old;
  ::setenv(name, value.c_str(), 1);
}

void HeadlessDisplay::RestoreEnv() {
  for (int i = num_saved_ - 1; i >= 0; --i) {
    if (saved_[i].was_set) {
      ::setenv(saved_[i].name.c_str(), saved_[i].value.c_str(), 1);
    } else {
      ::unsetenv(saved_[i].name.c_str());
    }
  }
  num_saved_ = 0;
}

}  // namespace rtscalib::render

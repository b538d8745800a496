// A display for VTK's GLX renderer on machines without one.
//
// Debian's VTK renders through GLX only, so every render needs an X server,
// even for offscreen rendering. HeadlessDisplay is an RAII guard:
//   * DISPLAY set:   it is used as is; nothing is started, nothing changed.
//   * DISPLAY unset: a private
//                    `Xvfb :N -screen 0 1920x1080x24 -nolisten tcp -noreset`
//                    is started on the lowest free display number N >= 99
//                    (free = neither /tmp/.X11-unix/XN nor /tmp/.XN-lock
//                    exists), the constructor waits until the server accepts
//                    connections (and its lock file names our server, so
//                    a concurrent process racing for :N is detected), then
//                    sets DISPLAY=:N,
//                    LIBGL_ALWAYS_SOFTWARE=1 and GALLIUM_DRIVER=llvmpipe
//                    (Mesa's multi-threaded software rasteriser).
//                    The destructor stops the server and restores the three
//                    variables.
// Destroy every SceneRenderer before the HeadlessDisplay it renders on.
// Not thread-safe: it edits the process environment.
#pragma once

#include <sys/types.h>

#include <stdexcept>
#include <string>

namespace rtscalib::render {

// Raised when no display can be provided (Xvfb missing, failed to start, ...).
class DisplayError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct HeadlessOptions {
  std::string xvfb = "Xvfb";            // program, looked up on PATH
  std::string screen = "1920x1080x24";  // Xvfb -screen 0 argument
  int first_display = 99;               // search starts at :first_display
  int max_tries = 64;                   // display numbers tried
  double start_timeout_s = 15.0;        // wait for the server to accept clients

  // Empty when valid, else what is wrong.
  std::string Check() const;
};

class HeadlessDisplay {
 public:
  explicit HeadlessDisplay(const HeadlessOptions& options = HeadlessOptions());
  ~HeadlessDisplay();
  HeadlessDisplay(const HeadlessDisplay&) = delete;
  HeadlessDisplay& operator=(const HeadlessDisplay&) = delete;

  // The display in use, e.g. ":99".
  const std::string& display() const { return display_; }
  // True when this object started (and will stop) an Xvfb.
  bool started_server() const { return server_pid_ > 0; }
  pid_t server_pid() const { return server_pid_; }

 private:
  struct SavedVar {
    std::string name;
    bool was_set = false;
    std::string value;
  };
  void SetEnv(const char* name, const std::string& value);
  void RestoreEnv();

  std::string display_;
  pid_t server_pid_ = -1;
  SavedVar saved_[3];
  int num_saved_ = 0;
};

// Full path of `program` on PATH (or `program` itself when it contains a
// '/'), empty when not found or not executable.
std::string FindExecutable(const std::string& program);

}  // namespace rtscalib::render

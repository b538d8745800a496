// Progress lines for long work, on stderr so that stdout stays the report.
// The calibration library reports through the same interface.
#pragma once

#include <chrono>
#include <cstdio>
#include <string>

#include "libcalib/calibrate/progress.h"

namespace rtscalib::app {

class Progress : public CalibrationProgress {
 public:
  explicit Progress(bool quiet) : quiet_(quiet) {}
  // Starts step `name`; the previous step (if any) is closed with its time.
  void Step(const std::string& name) override {
    Done();
    open_ = true;
    start_ = std::chrono::steady_clock::now();
    if (!quiet_) std::fprintf(stderr, "[rtscalib] %s ...\n", name.c_str());
    name_ = name;
  }
  void Note(const std::string& text) override {
    if (!quiet_) std::fprintf(stderr, "[rtscalib]   %s\n", text.c_str());
  }
  void Done() override {
    if (!open_) return;
    open_ = false;
    const double s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    if (!quiet_) std::fprintf(stderr, "[rtscalib]   done: %s (%.2f s)\n", name_.c_str(), s);
  }
  bool quiet() const { return quiet_; }

 private:
  bool quiet_;
  bool open_ = false;
  std::string name_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace rtscalib::app

// Progress of a long calibration, for whoever runs it: the rtscalib binary
// prints it on stderr (app/progress.h), a user's program may log it or
// ignore it. The library never prints.
#pragma once

#include <string>

namespace rtscalib {

class CalibrationProgress {
 public:
  virtual ~CalibrationProgress() = default;
  // A new step starts; the previous one (if any) is over.
  virtual void Step(const std::string& name) = 0;
  // A line worth showing within the current step.
  virtual void Note(const std::string& text) = 0;
  // The current step is over and no other follows yet.
  virtual void Done() = 0;
};

// Progress that goes nowhere (the default when the caller passes none).
class SilentProgress : public CalibrationProgress {
 public:
  void Step(const std::string&) override {}
  void Note(const std::string&) override {}
  void Done() override {}
};

}  // namespace rtscalib

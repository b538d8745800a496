// stdout to /dev/null for the lifetime of the object: a run in process
// prints its report there, and the benchmark's own table should stay
// readable.
#pragma once

#include <fcntl.h>
#include <unistd.h>

#include <cstdio>

namespace rtscalib::bench {

class QuietStdout {
 public:
  QuietStdout() : saved_(::dup(STDOUT_FILENO)) {
    std::fflush(stdout);
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, STDOUT_FILENO);
    ::close(null);
  }
  ~QuietStdout() {
    std::fflush(stdout);
    ::dup2(saved_, STDOUT_FILENO);
    ::close(saved_);
  }
  QuietStdout(const QuietStdout&) = delete;
  QuietStdout& operator=(const QuietStdout&) = delete;

 private:
  int saved_;
};

}  // namespace rtscalib::bench

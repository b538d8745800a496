#include "fuzz/fuzz_util.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <typeinfo>

#include "libcalib/text/errors.h"

namespace rtscalib::fuzz {
namespace {

namespace fs = std::filesystem;

[[noreturn]] void Bug(const std::string& message) {
  std::fprintf(stderr, "\n*** rtscalib fuzz: %s\n", message.c_str());
  std::fflush(stderr);
  std::abort();
}

// One folder per process so that parallel fuzzers (-jobs/-workers) never
// share a file; removed when the process exits normally.
class ScratchDir {
 public:
  ScratchDir() {
    path_ = fs::temp_directory_path() / ("rtscalib_fuzz_" + std::to_string(::getpid()));
    fs::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// Checks a caught InputError and decides: clean (0) or a bug (abort).
int CheckInputError(const InputError& e, const std::string& file) {
  // A message without the file would leave the user guessing which input is
  // wrong; Combine keeps the first error's fields.
  if (e.file != file)
    Bug("InputError names file '" + e.file + "', not '" + file + "': " + e.what());
  if (std::string(e.what()).empty()) Bug("InputError with an empty message");
  return 0;
}

template <typename Input>
int Run(const Input& input, const std::string& file, const std::function<void(const Input&)>& read,
        const DocumentedException& documented) {
  try {
    read(input);
  } catch (const InputError& e) {
    return CheckInputError(e, file);
  } catch (const std::exception& e) {
    if (documented && documented(e)) return 0;
    Bug(std::string("undocumented exception ") + typeid(e).name() + ": " + e.what());
  } catch (...) {
    Bug("an exception not derived from std::exception");
  }
  return 0;
}

}  // namespace

std::string WriteInputFile(const uint8_t* data, size_t size, const std::string& suffix) {
  static const ScratchDir dir;
  const std::string path = (dir.path() / ("input" + suffix)).string();
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  out.close();
  if (!out) Bug("cannot write the input to " + path);
  return path;
}

int RunFileReader(const uint8_t* data, size_t size, const std::string& suffix,
                  const std::function<void(const std::string& path)>& read,
                  const DocumentedException& documented) {
  const std::string path = WriteInputFile(data, size, suffix);
  return Run<std::string>(path, path, read, documented);
}

int RunTextReader(const uint8_t* data, size_t size, const std::string& name,
                  const std::function<void(const std::string& text)>& read,
                  const DocumentedException& documented) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  return Run<std::string>(text, name, read, documented);
}

void RequireFinite(double value, const std::string& what) {
  if (!std::isfinite(value)) Bug("accepted a non-finite " + what);
}

void Require(bool ok, const std::string& what) {
  if (!ok) Bug("accepted input that breaks: " + what);
}

}  // namespace rtscalib::fuzz

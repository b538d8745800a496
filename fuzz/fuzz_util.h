// Shared plumbing of the reader fuzzers (docs/fuzzing.md).
//
// The contract every reader is fuzzed against: any byte string either reads
// into values that satisfy the reader's documented rules (numbers finite,
// ranges as documented) or throws a clean rtscalib::InputError that names the
// file. Everything else is a bug the fuzzer reports by aborting: a crash, an
// ASan/UBSan report, an exception of another type, a glog CHECK, a value the
// reader should have refused.
//
// A fuzzer for a file reader is therefore a few lines (records_fuzzer.cc):
//   extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
//     return rtscalib::fuzz::RunFileReader(data, size, ".csv", [](const std::string& path) {
//       for (const Record& r : ReadRecords(path).records) RequireFinite(r.d, "d");
//     });
//   }
#pragma once

#include <cstddef>
#include <cstdint>
#include <exception>
#include <functional>
#include <string>

namespace rtscalib::fuzz {

// Writes the input to one temporary file per process (overwritten by every
// input, removed at exit) whose name ends in `suffix`, and returns its path.
std::string WriteInputFile(const uint8_t* data, size_t size, const std::string& suffix);

// Other exceptions a reader documents besides InputError; return true for one
// that is acceptable.
using DocumentedException = std::function<bool(const std::exception&)>;

// Runs `read` on the input written to a temporary file. A clean InputError
// (one that names `path` as its file) counts as success; anything else aborts
// with a message.
int RunFileReader(const uint8_t* data, size_t size, const std::string& suffix,
                  const std::function<void(const std::string& path)>& read,
                  const DocumentedException& documented = nullptr);

// The same for readers that take the text itself; `name` is what messages
// must name as the file.
int RunTextReader(const uint8_t* data, size_t size, const std::string& name,
                  const std::function<void(const std::string& text)>& read,
                  const DocumentedException& documented = nullptr);

// Aborts with `what` unless the accepted value is finite (a reader must never
// pass NaN or Inf on where its documentation promises finite numbers).
void RequireFinite(double value, const std::string& what);
// Aborts with `what` unless `ok` (a documented property of accepted input).
void Require(bool ok, const std::string& what);

}  // namespace rtscalib::fuzz

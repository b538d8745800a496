// records.csv reader (libcalib/io/records.h) against its documented rules.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz/fuzz_util.h"
#include "libcalib/io/records.h"

using rtscalib::fuzz::Require;
using rtscalib::fuzz::RequireFinite;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return rtscalib::fuzz::RunFileReader(data, size, ".csv", [](const std::string& path) {
    const rtscalib::RecordsFile file = rtscalib::ReadRecords(path);
    Require(!file.records.empty(), "at least one row");
    for (const rtscalib::Record& r : file.records) {
      Require(r.line >= 2, "a data row comes after the header");
      Require(r.face == 1 || r.face == 2, "face 1 or 2");
      Require(r.zoom >= 0, "zoom >= 0");
      Require(r.tool == rtscalib::Tool::kEdm || r.tool == rtscalib::Tool::kCam, "tool edm or cam");
      RequireFinite(r.phi, "phi");
      RequireFinite(r.theta, "theta");
      RequireFinite(r.u, "u");
      RequireFinite(r.v, "v");
      RequireFinite(r.d, "d");
      Require(r.d > 0, "d > 0");
      for (int i = 0; i < 3; ++i) RequireFinite(r.x[i], "x, y or z");
    }
  });
}

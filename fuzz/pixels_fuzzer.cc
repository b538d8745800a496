// pixels.csv reader (libcalib/io/records.h) against its documented rules.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz/fuzz_util.h"
#include "libcalib/io/records.h"

using rtscalib::fuzz::Require;
using rtscalib::fuzz::RequireFinite;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return rtscalib::fuzz::RunFileReader(data, size, ".csv", [](const std::string& path) {
    const rtscalib::PixelsFile file = rtscalib::ReadPixels(path);
    Require(!file.pixels.empty(), "at least one row");
    for (const rtscalib::PixelObservation& p : file.pixels) {
      Require(p.line >= 2, "a data row comes after the header");
      Require(p.face == 1 || p.face == 2, "face 1 or 2");
      Require(p.zoom >= 0, "zoom >= 0");
      Require(!p.shot.empty(), "a shot id");
      Require(p.target >= 0, "target >= 0");
      Require(p.corner >= 0 && p.corner <= 3, "corner 0..3");
      RequireFinite(p.phi, "phi");
      RequireFinite(p.theta, "theta");
      for (int i = 0; i < 3; ++i) RequireFinite(p.X[i], "X, Y or Z");
      for (int i = 0; i < 2; ++i) RequireFinite(p.uv[i], "u or v");
    }
  });
}

// shots.csv reader (libcalib/io/shots.h) against its documented rules. The
// reader checks that every image exists, so the fuzzer's temporary folder
// holds a few (empty) image files that inputs can name: shot0.png, a.jpg,
// img/1.tif.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include "fuzz/fuzz_util.h"
#include "libcalib/io/shots.h"

namespace {

using rtscalib::fuzz::Require;
using rtscalib::fuzz::RequireFinite;

void CreateImages(const std::filesystem::path& folder) {
  std::filesystem::create_directories(folder / "img");
  for (const char* name : {"shot0.png", "a.jpg", "img/1.tif"}) {
    const std::filesystem::path file = folder / name;
    if (!std::filesystem::exists(file)) std::ofstream(file) << "";
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return rtscalib::fuzz::RunFileReader(data, size, ".csv", [](const std::string& path) {
    CreateImages(std::filesystem::path(path).parent_path());
    for (rtscalib::AngleUnit unit :
         {rtscalib::AngleUnit::kRad, rtscalib::AngleUnit::kDeg, rtscalib::AngleUnit::kGon}) {
      const rtscalib::ShotsFile file = rtscalib::ReadShots(path, unit);
      Require(!file.shots.empty(), "at least one shot");
      std::set<std::string> ids;
      for (const rtscalib::PhotoShot& s : file.shots) {
        Require(s.line >= 2, "a data row comes after the header");
        Require(s.face == 1 || s.face == 2, "face 1 or 2");
        Require(s.zoom >= 0, "zoom >= 0");
        RequireFinite(s.phi, "phi");
        RequireFinite(s.theta, "theta");
        Require(!s.image.empty(), "an image name");
        Require(std::filesystem::exists(s.image_path), "the image exists: " + s.image_path);
        Require(!s.shot.empty(), "a shot id");
        Require(ids.insert(s.shot).second, "shot ids are unique: " + s.shot);
      }
    }
  });
}

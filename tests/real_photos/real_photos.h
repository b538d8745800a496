// Where the tests find the public photo sets of real cameras
// (../shared/real-photos beside the checkout, or -DRTSCALIB_REAL_PHOTOS=DIR).
// They are read in place, never copied into the repository.
#pragma once

#include <filesystem>
#include <string>

#include <gtest/gtest.h>

namespace rtscalib::testing_real_photos {

// The folder of one set, e.g. RealPhotoSet("yac_d435i_aprilgrid"); empty
// when the sets are not there (the caller skips: RTSCALIB_REQUIRE_REAL_PHOTOS).
inline std::string RealPhotoSet(const std::string& set) {
  const std::filesystem::path dir = std::filesystem::path(RTSCALIB_REAL_PHOTOS_DIR) / set;
  return std::filesystem::is_directory(dir) ? dir.string() : std::string();
}

}  // namespace rtscalib::testing_real_photos

// Declares `std::string var` = the set's folder, or skips the test naming the
// missing folder (a checkout without ../shared/real-photos).
#define RTSCALIB_REQUIRE_REAL_PHOTOS(var, set)                                              \
  const std::string var = ::rtscalib::testing_real_photos::RealPhotoSet(set);               \
  if (var.empty()) {                                                                         \
    GTEST_SKIP() << "real photo set " << (set) << " not found in " RTSCALIB_REAL_PHOTOS_DIR \
                 << " (configure with -DRTSCALIB_REAL_PHOTOS=DIR)";                         \
  }

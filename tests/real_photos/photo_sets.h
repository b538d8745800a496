// A set's photos as rtscalib reads a user's: a shots.csv written into a
// folder of the test's own (the photos are named by absolute path, read in
// place), detected by DetectPhotos with the targets file given, and the
// kept tags by photo.
#pragma once

#include <Eigen/Core>
#include <array>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <unistd.h>

#include "detect/photos.h"
#include "libcalib/io/shots.h"
#include "libcalib/io/targets_io.h"

namespace rtscalib::testing_real_photos {

// A folder for one test's files, removed at its end.
class TestFolder {
 public:
  TestFolder() {
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = std::filesystem::path(::testing::TempDir()) /
            ("rtscalib_real_" + std::string(info->test_suite_name()) + "_" +
             std::to_string(::getpid()));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TestFolder() { std::filesystem::remove_all(path_); }
  TestFolder(const TestFolder&) = delete;
  TestFolder& operator=(const TestFolder&) = delete;
  std::string Path(const std::string& name) const { return (path_ / name).string(); }
  std::string Write(const std::string& name, const std::string& text) const {
    std::ofstream(Path(name)) << text;
    return Path(name);
  }

 private:
  std::filesystem::path path_;
};

struct SetPhoto {
  std::string image;  // absolute path
  std::string shot;   // shot id = placement (one board pose per photo)
  int zoom = 0;       // one per image size
};

// shots.csv of a camera-only session: face 1, empty readings, one placement
// per photo (SPEC 7.1).
inline std::string WriteShots(const TestFolder& folder, const std::vector<SetPhoto>& photos,
                              const std::string& name = "shots.csv") {
  std::string text = "face,zoom,phi,theta,shot,placement,image\n";
  for (const SetPhoto& p : photos) {
    text += "1," + std::to_string(p.zoom) + ",,," + p.shot + "," + p.shot + "," + p.image + "\n";
  }
  return folder.Write(name, text);
}

struct DetectedSet {
  ShotsFile shots;
  TargetScene targets;
  detect::PhotoDetectionResult result;
  // The kept AprilTags and point-board corners by shot, then target id.
  std::map<std::string, std::map<int, std::array<Eigen::Vector2d, 4>>> tags;
  std::map<std::string, int> from_neighbours;  // by shot
};

inline DetectedSet DetectSet(const std::string& shots_path, const std::string& targets_path,
                             const detect::PhotoDetectionOptions& options = {}) {
  DetectedSet out;
  const std::map<std::string, int> codes = detect::DetectableCodeCounts();
  out.shots = ReadShots(shots_path);
  out.targets = ReadTargets(targets_path, &codes);
  detect::PhotoDetectionOptions o = options;
  o.progress = false;
  out.result = detect::DetectPhotos(out.shots, out.targets, o);
  for (size_t i = 0; i < out.shots.shots.size(); ++i) {
    const std::string& shot = out.shots.shots[i].shot;
    out.tags[shot];
    for (const detect::DetectedTag& t : out.result.photos[i].tags) out.tags[shot][t.id] = t.uv;
    out.from_neighbours[shot] = out.result.photos[i].from_neighbours;
  }
  return out;
}

// Kalibr's own target file of an AprilGrid (SPEC 7.2).
inline std::string WriteKalibrAprilGrid(const TestFolder& folder, int cols, int rows,
                                        double tag_size, double spacing_ratio,
                                        const std::string& name = "aprilgrid.yaml") {
  return folder.Write(name, "target_type: 'aprilgrid'\ntagCols: " + std::to_string(cols) +
                                "\ntagRows: " + std::to_string(rows) +
                                "\ntagSize: " + std::to_string(tag_size) +
                                "\ntagSpacing: " + std::to_string(spacing_ratio) + "\n");
}

}  // namespace rtscalib::testing_real_photos

// Single tag36h11 tags (1-bit border) in real photos, no board layout:
//   swat_tags_hallway: 72 iPhone 4S photos (816 x 612 JPEG, indoors, low
//     light) of 20 tags taped around a room, with the ids visible in each
//     photo (groundtruth.txt, 236 sightings);
//   apriltag_swarmathon: libapriltag's own regression photos (799 x 533,
//     outdoors, 12-45 px tags, all id 0) with its own corners.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "detect/detector.h"
#include "detect/photo_image.h"
#include "tests/real_photos/photo_sets.h"
#include "tests/real_photos/real_photos.h"

namespace rtscalib::testing_real_photos {
namespace {

// The photo session's path (DetectPhotos) with the 20 tags as one board of
// ids 0-19 (a layout that means nothing here: the tags are single, and
// only the ids are checked; the growth finds nothing on it). At least 95 %
// of the 236 sightings (measured 227: libapriltag finds 228 with its own
// settings and with ours, and one is dropped unrefined, its bits of 1.3 px
// below the pattern fit's 1.5), and no id that groundtruth.txt does not
// list for the photo.
TEST(SwatTagsHallway, FindsTheListedTagsAndNoOther) {
  RTSCALIB_REQUIRE_REAL_PHOTOS(set, "swat_tags_hallway");
  std::map<std::string, std::set<int>> listed;
  std::ifstream in(set + "/groundtruth.txt");
  std::vector<SetPhoto> photos;
  for (std::string line; std::getline(in, line);) {
    std::istringstream ss(line);
    std::string file;
    if (!(ss >> file)) continue;
    const std::string shot = file.substr(0, file.find('.'));
    for (int id; ss >> id;) listed[shot].insert(id);
    listed[shot];
    photos.push_back({set + "/" + file, shot, 0});
  }
  ASSERT_EQ(photos.size(), 72u);
  const TestFolder folder;
  const std::string targets = folder.Write(
      "targets.yaml",
      "boards:\n  - {family: tag36h11, first_id: 0, rows: 4, cols: 5, tag_size: 0.127, "
      "spacing: 0.1}\n");
  const DetectedSet found = DetectSet(WriteShots(folder, photos), targets);
  int sightings = 0, seen = 0, unlisted = 0;
  for (const auto& [shot, ids] : listed) {
    sightings += static_cast<int>(ids.size());
    for (const auto& [id, uv] : found.tags.at(shot)) {
      if (ids.count(id) > 0) {
        ++seen;
      } else {
        ++unlisted;
        ADD_FAILURE() << shot << ": tag " << id << " is not listed in groundtruth.txt";
      }
    }
  }
  int unrefined = 0;
  for (const detect::PhotoDetection& p : found.result.photos) unrefined += p.unrefined;
  std::printf("swat_tags_hallway: %d of %d sightings (%.1f %%), %d not listed, %d dropped as "
              "unrefined\n",
              seen, sightings, 100.0 * seen / sightings, unlisted, unrefined);
  EXPECT_EQ(sightings, 236);
  EXPECT_GE(seen, 0.95 * sightings);
}

// libapriltag's reference corners (quad_decimate 1, refine_edges off;
// PROVENANCE.md), which are detector output and not complete, against our
// refined corners on the tags both have. Their coordinates are
// libapriltag's, where pixel (x, y) spans [x, x + 1): OpenCV's (ours,
// SPEC 2) + 0.5, measured here as the mean difference of our unrefined
// corners (libapriltag's own, shifted by -0.5) from them, (-0.48, -0.45)
// px before the shift is undone. The corner order is the same
// (apriltag_detection::p, TargetCorner's). Tolerances from what the two
// estimate: libapriltag's unrefined corners are the quad fitted to the
// boundary pixels of the thresholded tag, a few tenths of a pixel off on
// tags of 1.5-5 px bits with blur; our refined corners differ from them by
// 0.59 px rms, (0.00, +0.17) px on average (measured). So: every tag of
// the reference that we refine within 1 px rms and 0.3 px of bias per axis,
// and most of the reference's tags refined: 40 of 47 (measured 42; of the
// other 5, 2 are not found (our segmentation threshold follows the image's
// noise, detector.h) and 3 are found but their refinements do not hold).
TEST(AprilTagSwarmathon, RefinedCornersAgainstLibapriltagsOwn) {
  RTSCALIB_REQUIRE_REAL_PHOTOS(set, "apriltag_swarmathon");
  detect::TagDetector detector;
  int reference = 0, matched = 0, n = 0;
  double sum_sq = 0;
  Eigen::Vector2d bias = Eigen::Vector2d::Zero();
  for (const char* name :
       {"33369213973_9d9bb4cc96_c", "34085369442_304b6bafd9_c", "34139872896_defdb2f8d9_c"}) {
    const detect::Photo photo = detect::LoadPhoto(set + "/" + name + ".jpg");
    const std::vector<detect::TagDetection> found = detector.Detect(photo.gray);
    std::ifstream in(set + "/" + name + ".txt");
    for (std::string line; std::getline(in, line);) {
      if (line.empty()) continue;
      for (char& c : line) {
        if (c == '(' || c == ')' || c == ',') c = ' ';
      }
      std::istringstream ss(line);
      int id = -1;
      std::array<Eigen::Vector2d, 4> ref;
      ss >> id;
      for (Eigen::Vector2d& c : ref) {
        ss >> c.x() >> c.y();
        c -= Eigen::Vector2d(0.5, 0.5);  // libapriltag's pixels -> SPEC 2
      }
      ASSERT_TRUE(ss) << name << ": " << line;
      ++reference;
      const Eigen::Vector2d centre = (ref[0] + ref[1] + ref[2] + ref[3]) / 4;
      for (const detect::TagDetection& d : found) {
        const Eigen::Vector2d c = (d.corners[0] + d.corners[1] + d.corners[2] + d.corners[3]) / 4;
        if (d.id != id || (c - centre).norm() > 3.0 || !d.refined()) continue;
        ++matched;
        for (int k = 0; k < 4; ++k) {
          const Eigen::Vector2d e = d.corners[k] - ref[k];
          sum_sq += e.squaredNorm();
          bias += e;
          ++n;
        }
      }
    }
  }
  bias /= n;
  const double rms = std::sqrt(sum_sq / n);
  std::printf("apriltag_swarmathon: %d of the reference's %d tags refined; corners RMS %.3f px, "
              "bias (%+.3f, %+.3f) px\n",
              matched, reference, rms, bias.x(), bias.y());
  EXPECT_EQ(reference, 47);
  EXPECT_GE(matched, 40);
  EXPECT_LT(rms, 1.0);
  EXPECT_LT(std::abs(bias.x()), 0.3);
  EXPECT_LT(std::abs(bias.y()), 0.3);
}

}  // namespace
}  // namespace rtscalib::testing_real_photos

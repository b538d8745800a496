// yac_d435i_aprilgrid: 30 JPEG photos (640 x 480, an Intel RealSense
// D435i) of Kalibr's 6 x 6 AprilGrid (tag36h11 with a 2-bit border,
// 0.088 m tags, spacing 0.3), with yac's own detections per photo
// (grid0/cam0/data/<ts>.csv: kp = pixel, p = the corner in Kalibr's target
// frame, corner 0 = (x0, y0), 1 = (x0 + s, y0), 2 = (x0 + s, y0 + s),
// 3 = (x0, y0 + s), y up the printed target) and OpenCV's calibration on
// them (ref.json). The board is read from Kalibr's own target file, as a
// Kalibr user has it (SPEC 7.2).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "app/pipeline.h"
#include "tests/real_photos/opencv_calibration.h"
#include "tests/real_photos/photo_sets.h"
#include "tests/real_photos/real_photos.h"

namespace rtscalib::testing_real_photos {
namespace {

namespace fs = std::filesystem;

struct YacCorner {
  Eigen::Vector2d kp;  // pixel
  Eigen::Vector2d p;   // Kalibr's target frame [m]
};
// Per photo (timestamp), per tag id, per corner index.
using YacDetections = std::map<std::string, std::map<int, std::map<int, YacCorner>>>;

YacDetections ReadYacCsvs(const std::string& set) {
  YacDetections out;
  for (const fs::directory_entry& e : fs::directory_iterator(set + "/grid0/cam0/data")) {
    if (e.path().extension() != ".csv") continue;
    std::ifstream in(e.path());
    std::string line;
    auto& photo = out[e.path().stem().string()];
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#') continue;
      std::vector<double> f;
      std::stringstream ss(line);
      for (std::string cell; std::getline(ss, cell, ',');) f.push_back(std::stod(cell));
      // ts, tag_rows, tag_cols, tag_size, tag_spacing, kp_x, kp_y, p_x, p_y, p_z, tag_id, corner_idx
      if (f.size() != 12) throw std::runtime_error("unexpected yac row: " + line);
      photo[static_cast<int>(f[10])][static_cast<int>(f[11])] = {{f[5], f[6]}, {f[7], f[8]}};
    }
  }
  return out;
}

std::vector<SetPhoto> YacPhotos(const std::string& set) {
  std::vector<SetPhoto> photos;
  for (const fs::directory_entry& e : fs::directory_iterator(set + "/cam0/data")) {
    if (e.path().extension() == ".jpg") photos.push_back({e.path().string(), e.path().stem().string(), 0});
  }
  std::sort(photos.begin(), photos.end(),
            [](const SetPhoto& a, const SetPhoto& b) { return a.shot < b.shot; });
  return photos;
}

// yac's tags found with the right id: at least 95 % of them (the issue's
// figure; measured 1,001 of 1,007, those missed being corner tags whose
// outer corner carries a motion-capture marker), every photo used. The
// corners against yac's, whose detector (Kaess's AprilTags, its own edge
// fit) is independent of ours: OpenCV's aruco corners differ from yac's by
// 0.72 px rms (PROVENANCE.md). Both put pixel (0, 0) at the top-left
// pixel's centre: a convention half a pixel apart would show as a 0.5 px
// bias in both axes, a corner order mixed up as tag-sized errors.
TEST(YacAprilGrid, FindsTheTagsOfYacsDetectionsWithTheirIdsAndCorners) {
  RTSCALIB_REQUIRE_REAL_PHOTOS(set, "yac_d435i_aprilgrid");
  const TestFolder folder;
  const std::vector<SetPhoto> photos = YacPhotos(set);
  ASSERT_EQ(photos.size(), 30u);
  const DetectedSet found =
      DetectSet(WriteShots(folder, photos), WriteKalibrAprilGrid(folder, 6, 6, 0.088, 0.3));
  const YacDetections yac = ReadYacCsvs(set);
  ASSERT_EQ(yac.size(), 30u);

  int listed = 0, matched = 0, extra = 0, grown = 0;
  double sum_sq = 0, max_error = 0;
  Eigen::Vector2d bias = Eigen::Vector2d::Zero();
  int corners = 0;
  std::vector<double> size_ratios;
  for (const SetPhoto& photo : photos) {
    const auto& ours = found.tags.at(photo.shot);
    EXPECT_FALSE(ours.empty()) << photo.shot << ": no tag found";
    grown += found.from_neighbours.at(photo.shot);
    const auto& theirs = yac.at(photo.shot);
    for (const auto& [id, uv] : ours) extra += theirs.count(id) == 0;
    for (const auto& [id, yac_corners] : theirs) {
      ++listed;
      const auto it = ours.find(id);
      if (it == ours.end()) continue;
      ++matched;
      for (const auto& [k, c] : yac_corners) {
        const Eigen::Vector2d e = it->second[k] - c.kp;
        sum_sq += e.squaredNorm();
        bias += e;
        max_error = std::max(max_error, e.norm());
        ++corners;
      }
      if (yac_corners.size() == 4) {
        // Edge placement: the mean distance of the corners from the tag's
        // centre, ours over yac's.
        Eigen::Vector2d a = Eigen::Vector2d::Zero(), b = Eigen::Vector2d::Zero();
        for (int k = 0; k < 4; ++k) {
          a += it->second[k] / 4;
          b += yac_corners.at(k).kp / 4;
        }
        double ra = 0, rb = 0;
        for (int k = 0; k < 4; ++k) {
          ra += (it->second[k] - a).norm();
          rb += (yac_corners.at(k).kp - b).norm();
        }
        size_ratios.push_back(ra / rb);
      }
    }
  }
  bias /= corners;
  const double rms = std::sqrt(sum_sq / corners);
  std::sort(size_ratios.begin(), size_ratios.end());
  const double size_ratio = size_ratios[size_ratios.size() / 2];
  std::printf("yac_d435i_aprilgrid: %d of yac's %d tags found (%.1f %%), %d more that yac did not "
              "list, %d grown from their neighbours\n",
              matched, listed, 100.0 * matched / listed, extra, grown);
  std::printf("  corners against yac's: %d, RMS %.3f px, bias (%+.3f, %+.3f) px, max %.2f px; "
              "tag size ours / yac's %.4f (median)\n",
              corners, rms, bias.x(), bias.y(), max_error, size_ratio);
  EXPECT_GE(matched, 0.95 * listed);
  // Measured 0.33 px: 0.5 px leaves room for the JPEG's blur and is below
  // the 0.72 px between OpenCV's corners and yac's.
  EXPECT_LT(rms, 0.5);
  EXPECT_LT(std::abs(bias.x()), 0.1);
  EXPECT_LT(std::abs(bias.y()), 0.1);
  // Measured 0.994: the detectors place the edges 0.6 % (0.15 px on a
  // 25 px tag) apart; OpenCV's quads are 1.5-3.6 % smaller than yac's.
  EXPECT_NEAR(size_ratio, 1.0, 0.02);
}

// The camera-only calibration of the 30 photos through the user's path
// (shots.csv, Kalibr's target file, model.kinematics: none, k1 k2 p1 p2 k3)
// against OpenCV's calibrateCamera, run here on yac's CSV corners (ref.json
// holds OpenCV 5's result on them) and on rtscalib's own corners:
//   - on rtscalib's corners the same least-squares problem: within half
//     of OpenCV's sigma (rtscalib takes out one gross error, a row of 2.7 px
//     at 11 robust sigmas, which OpenCV keeps);
//   - on yac's corners the detectors differ (0.33 px rms, above): within 3
//     of OpenCV's sigmas (measured 0.8-1.2);
//   - OpenCV here on yac's corners reproduces ref.json within a tenth of a
//     sigma (a check that the CSVs are read as ref.json read them).
TEST(YacAprilGridCalibration, CameraOnlyAgreesWithOpenCvOnYacsAndOnItsOwnCorners) {
  RTSCALIB_REQUIRE_REAL_PHOTOS(set, "yac_d435i_aprilgrid");
  const TestFolder folder;
  const std::vector<SetPhoto> photos = YacPhotos(set);
  WriteShots(folder, photos);
  WriteKalibrAprilGrid(folder, 6, 6, 0.088, 0.3);
  folder.Write("run.yaml",
               "data: {shots: shots.csv, targets: aprilgrid.yaml}\n"
               "model:\n"
               "  kinematics: none\n"
               "  effects: [radial_distortion, tangential_distortion]\n"
               "  intrinsics: fit\n"
               "detect: {jobs: 2}\n"
               "diagnose: {enabled: false}\n"
               "output: out\n");
  app::Progress progress(true);
  const app::RunSettings settings = app::LoadRunSettings(folder.Path("run.yaml"));
  const app::PipelineResult r = app::RunPipeline(settings, folder.Path("out"), &progress);
  const InstrumentModel& m = r.calibration.model;
  ASSERT_EQ(m.kinematics, Kinematics::kNone);
  ASSERT_EQ(m.NumZooms(), 1);
  ASSERT_TRUE(m.sigmas.valid);
  EXPECT_EQ(r.photos.photos_without_tags, 0);

  // OpenCV on rtscalib's corners (pixels.csv order, per photo).
  const OpenCvViews views = ViewsOf(r.obs.pixels, r.obs.targets);
  const OpenCvCalibration same =
      CalibrateWithOpenCv(views.object, views.image, cv::Size(640, 480));

  // OpenCV on yac's corners, in Kalibr's target frame (planar, z = 0).
  std::vector<std::vector<cv::Point3f>> object;
  std::vector<std::vector<cv::Point2f>> image;
  for (const auto& [ts, tags] : ReadYacCsvs(set)) {
    object.emplace_back();
    image.emplace_back();
    for (const auto& [id, corners] : tags) {
      for (const auto& [k, c] : corners) {
        object.back().emplace_back(c.p.x(), c.p.y(), 0.0f);
        image.back().emplace_back(c.kp.x(), c.kp.y());
      }
    }
  }
  const OpenCvCalibration yac = CalibrateWithOpenCv(object, image, cv::Size(640, 480));
  // ref.json: OpenCV 5.0.0 on the same corners.
  const double ref[4] = {606.5683553340094, 609.9581791228969, 324.4442418214721,
                         245.65284931044044};

  const char* const names[] = {"fx", "fy", "cx", "cy"};
  std::printf("yac_d435i_aprilgrid camera-only, %zu corners of rtscalib's; OpenCV on yac's %d\n",
              r.obs.pixels.size(), static_cast<int>(object.size()));
  std::printf("  %-3s %10s %8s | %10s %8s %9s | %10s %8s %9s\n", "", "rtscalib", "sigma",
              "OpenCV own", "sigma", "diff/sig", "OpenCV yac", "sigma", "diff/sig");
  for (int i = 0; i < 4; ++i) {
    const double value = m.cams[0].intrinsics[i], sigma = m.sigmas.intrinsics[0][i];
    const double d_same = (value - same.k[i]) / same.sigma[i];
    const double d_yac = (value - yac.k[i]) / yac.sigma[i];
    std::printf("  %-3s %10.3f %8.3f | %10.3f %8.3f %+9.2f | %10.3f %8.3f %+9.2f\n", names[i],
                value, sigma, same.k[i], same.sigma[i], d_same, yac.k[i], yac.sigma[i], d_yac);
    EXPECT_LT(std::abs(d_same), 0.5) << names[i];
    EXPECT_LT(std::abs(d_yac), 3.0) << names[i];
    EXPECT_LT(std::abs(yac.k[i] - ref[i]), 0.1 * yac.sigma[i]) << names[i] << " vs ref.json";
  }
  std::printf("  RMS: rtscalib %.3f px, OpenCV on rtscalib's corners %.3f px, on yac's %.3f px\n",
              r.calibration.final_errors.pixels.rms_px, same.rms, yac.rms);
}

}  // namespace
}  // namespace rtscalib::testing_real_photos

// Photos of a real camera that no part of this project made: OpenCV's own
// samples left01.jpg ... left14.jpg (no left10; Debian's opencv-doc,
// installed by scripts/install-deps.sh): 640 x 480, a 9 x 6 inner-corner
// chessboard of 25 mm squares held by hand, strong barrel distortion, JPEG.
//
// The user's path end to end: configs/bench.yaml (shots.csv with one
// placement per photo and empty readings, targets.yaml, model.kinematics:
// none) through LoadRunSettings and RunPipeline, as `rtscalib --config`
// runs it. The result is compared in the same test with
// cv::calibrateCameraExtended (C++: calibrateCamera with standard deviations), same model (k1, k2, p1, p2, k3):
//   - on rtscalib's own detected corners: the same least-squares problem,
//     so the intrinsics must agree within half of OpenCV's sigma, the
//     sigmas (both from J^T J and the residuals) within a factor 2, and the
//     reprojection RMS within 10 %;
//   - on OpenCV's own detection (findChessboardCorners + cornerSubPix, as
//     OpenCV's calibration tutorial does): the detectors differ (their
//     corners differ by tenths of a pixel on such photos), so only within
//     1 % of the focal length.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <unistd.h>

#include "app/pipeline.h"
#include "tests/real_photos/opencv_calibration.h"

namespace rtscalib::app {
namespace {

namespace fs = std::filesystem;

const char* const kSamples = "/usr/share/doc/opencv-doc/examples/data";
const char* const kPhotos[] = {"left01", "left02", "left03", "left04", "left05", "left06", "left07",
                               "left08", "left09", "left11", "left12", "left13", "left14"};

using testing_real_photos::CalibrateWithOpenCv;
using testing_real_photos::OpenCvCalibration;

TEST(OpenCvSamplePhotos, CameraOnlyCalibrationAgreesWithCalibrateCamera) {
  for (const char* name : kPhotos) {
    ASSERT_TRUE(fs::exists(std::string(kSamples) + "/" + name + ".jpg"))
        << kSamples << "/" << name << ".jpg is missing: install Debian's opencv-doc "
        << "(bash scripts/install-deps.sh)";
  }
  const fs::path work =
      fs::temp_directory_path() / ("rtscalib_opencv_samples_" + std::to_string(::getpid()));
  fs::remove_all(work);
  Progress progress(true);
  const RunSettings settings =
      LoadRunSettings(std::string(RTSCALIB_SOURCE_DIR) + "/configs/bench.yaml");
  const PipelineResult r = RunPipeline(settings, work.string(), &progress);
  fs::remove_all(work);

  // Every photo used, whole: 54 inner corners each.
  ASSERT_EQ(r.photos.photos.size(), 13u);
  for (const PhotoSessionSummary::Photo& p : r.photos.photos) {
    EXPECT_EQ(p.tags, 54) << p.shot << ": chessboard not found whole";
  }
  EXPECT_TRUE(r.photos.warnings.empty());
  const InstrumentModel& m = r.calibration.model;
  ASSERT_EQ(m.kinematics, Kinematics::kNone);
  ASSERT_EQ(m.NumZooms(), 1);
  ASSERT_TRUE(m.sigmas.valid);
  EXPECT_EQ(m.boards.size(), 13u);  // one pose per placement (photo)

  // OpenCV on rtscalib's corners: per photo, the board-frame corners
  // (TagBoard::CornersInBoard) and the detected pixels, in pixels.csv order.
  const testing_real_photos::OpenCvViews views =
      testing_real_photos::ViewsOf(r.obs.pixels, r.obs.targets);
  const OpenCvCalibration same =
      CalibrateWithOpenCv(views.object, views.image, cv::Size(640, 480));

  // OpenCV's own detection, as its calibration tutorial does it.
  std::vector<std::vector<cv::Point3f>> own_object;
  std::vector<std::vector<cv::Point2f>> own_image;
  std::vector<cv::Point3f> grid;
  for (int row = 0; row < 6; ++row) {
    for (int col = 0; col < 9; ++col) grid.emplace_back(0.025f * col, 0.025f * row, 0.0f);
  }
  for (const char* name : kPhotos) {
    const cv::Mat gray =
        cv::imread(std::string(kSamples) + "/" + name + ".jpg", cv::IMREAD_GRAYSCALE);
    std::vector<cv::Point2f> corners;
    ASSERT_TRUE(cv::findChessboardCorners(gray, cv::Size(9, 6), corners)) << name;
    cv::cornerSubPix(gray, corners, cv::Size(11, 11), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::MAX_ITER, 30, 1e-3));
    own_object.push_back(grid);
    own_image.push_back(corners);
  }
  const OpenCvCalibration own = CalibrateWithOpenCv(own_object, own_image, cv::Size(640, 480));

  const char* const names[] = {"fx", "fy", "cx", "cy"};
  const double rms = r.calibration.final_errors.pixels.rms_px;
  std::printf("OpenCV sample photos, 13 photos, %zu corners (rtscalib's detection)\n",
              r.obs.pixels.size());
  std::printf("  %-4s %12s %12s %12s %10s %12s %12s\n", "", "rtscalib", "+- sigma", "OpenCV same",
              "+- sigma", "diff/sigma", "OpenCV own");
  for (int i = 0; i < 4; ++i) {
    const double value = m.cams[0].intrinsics[i], sigma = m.sigmas.intrinsics[0][i];
    std::printf("  %-4s %12.3f %12.3f %12.3f %10.3f %12.3f %12.3f\n", names[i], value, sigma,
                same.k[i], same.sigma[i], (value - same.k[i]) / same.sigma[i], own.k[i]);
    // The same problem solved twice: half of OpenCV's sigma (the issue's
    // bound); OpenCV's float image points alone limit it to ~1e-5 px.
    EXPECT_LT(std::abs(value - same.k[i]), 0.5 * same.sigma[i]) << names[i];
    // Both sigmas are (J^T J)^-1 scaled by the residuals' variance, but
    // OpenCV 4.6 (Debian's; calibration.cpp) divides the sum of squared
    // residual norms by (points - parameters) where there are 2 x points
    // coordinates: its variance is ~2x too large, its sigmas ~1.4x
    // (measured 1.47x here; fixed in OpenCV 4.7 by pull request 22992).
    EXPECT_GT(sigma, 0.5 * same.sigma[i]) << names[i];
    EXPECT_LT(sigma, 2.0 * same.sigma[i]) << names[i];
  }
  std::printf("  reprojection RMS: rtscalib %.4f px, OpenCV on the same corners %.4f px, OpenCV's "
              "own detection %.4f px\n",
              rms, same.rms, own.rms);
  EXPECT_LT(rms, 1.1 * same.rms);
  // Different detectors: the focal length within 1 % (the bound;
  // findChessboardCornersSB and findChessboardCorners + cornerSubPix alone
  // move fx by ~3 px, 0.6 %, on these photos).
  EXPECT_LT(std::abs(m.cams[0].intrinsics[0] - own.k[0]), 0.01 * own.k[0]);
  EXPECT_LT(std::abs(m.cams[0].intrinsics[1] - own.k[1]), 0.01 * own.k[1]);
}

}  // namespace
}  // namespace rtscalib::app

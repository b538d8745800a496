#include "libcalib/export/opencv_export.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "libcalib/model/kinematics.h"
#include "tests/export/export_fixture.h"

namespace rtscalib {
namespace {

std::string TempPath(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "rtscalib_export_test";
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

struct ReadBack {
  cv::Mat camera_matrix, dist;
  int width = 0, height = 0, zoom = -1;
};

ReadBack Read(const std::string& path) {
  cv::FileStorage fs(path, cv::FileStorage::READ);
  EXPECT_TRUE(fs.isOpened()) << path;
  ReadBack r;
  fs["camera_matrix"] >> r.camera_matrix;
  fs["distortion_coefficients"] >> r.dist;
  fs["image_width"] >> r.width;
  fs["image_height"] >> r.height;
  fs["zoom"] >> r.zoom;
  return r;
}

// The file holds the model's numbers exactly (OpenCV writes doubles with 17
// significant digits), and cv::projectPoints with them reproduces rtscalib's
// projection of reference-frame points seen at random pointings. Tolerance
// 1e-9 px: both evaluate the same formula in double precision (~1e-12 px).
TEST(OpenCvExport, ReadBackProjectsLikeRtscalib) {
  std::mt19937 rng(11);
  for (Kinematics k : {Kinematics::kDh, Kinematics::kSpherical}) {
    const InstrumentModel m =
        RandomModel(k, rng, {Effect::kRadialDistortion, Effect::kSensorTilt, Effect::kThinPrism});
    for (int z = 0; z < m.NumZooms(); ++z) {
      const std::string path = TempPath("camera_zoom" + std::to_string(z) + ".yaml");
      WriteOpenCvCamera(path, m, z);
      const ReadBack r = Read(path);
      const CameraTool& cam = m.cams[z];
      EXPECT_EQ(r.zoom, z);
      EXPECT_EQ(r.width, cam.width);
      EXPECT_EQ(r.height, cam.height);
      ASSERT_EQ(r.camera_matrix.rows, 3);
      ASSERT_EQ(r.camera_matrix.cols, 3);
      EXPECT_EQ(r.camera_matrix.at<double>(0, 0), cam.intrinsics[0]);
      EXPECT_EQ(r.camera_matrix.at<double>(1, 1), cam.intrinsics[1]);
      EXPECT_EQ(r.camera_matrix.at<double>(0, 2), cam.intrinsics[2]);
      EXPECT_EQ(r.camera_matrix.at<double>(1, 2), cam.intrinsics[3]);
      EXPECT_EQ(r.camera_matrix.at<double>(0, 1), 0.0);
      ASSERT_EQ(static_cast<int>(r.dist.total()), kNumDistortion);
      for (int i = 0; i < kNumDistortion; ++i) {
        EXPECT_EQ(r.dist.at<double>(i), cam.distortion[i]) << i;
      }

      std::uniform_real_distribution<double> angle(0.3, 2.5), lateral(-0.3, 0.3), depth(2, 20);
      for (int shot = 0; shot < 10; ++shot) {
        const double phi = angle(rng) * 2, theta = angle(rng);
        const Rigid3 cam_from_ref = RefFromCam(m, z, phi, theta).Inverse();
        std::vector<cv::Point3d> points;
        for (int i = 0; i < 20; ++i) {
          const double d = depth(rng);
          const Eigen::Vector3d x_ref =
              RefFromCam(m, z, phi, theta) * Eigen::Vector3d(lateral(rng) * d, lateral(rng) * d, d);
          points.emplace_back(x_ref.x(), x_ref.y(), x_ref.z());
        }
        cv::Mat rotation(3, 3, CV_64F), rvec;
        for (int i = 0; i < 3; ++i) {
          for (int j = 0; j < 3; ++j) rotation.at<double>(i, j) = cam_from_ref.rotation(i, j);
        }
        cv::Rodrigues(rotation, rvec);
        const cv::Mat tvec = (cv::Mat_<double>(3, 1) << cam_from_ref.translation.x(),
                              cam_from_ref.translation.y(), cam_from_ref.translation.z());
        std::vector<cv::Point2d> projected;
        cv::projectPoints(points, rvec, tvec, r.camera_matrix, r.dist, projected);
        for (size_t i = 0; i < points.size(); ++i) {
          Eigen::Vector2d uv;
          ASSERT_TRUE(PredictPixel(m, z, phi, theta,
                                   Eigen::Vector3d(points[i].x, points[i].y, points[i].z), &uv));
          EXPECT_NEAR(projected[i].x, uv.x(), 1e-9);
          EXPECT_NEAR(projected[i].y, uv.y(), 1e-9);
        }
      }
    }
  }
}

// cv::initUndistortRectifyMap accepts the file: with R = I and the same
// camera matrix, the map sends each pixel to where rtscalib's camera images
// its ray. Tolerance 1e-3 px: the map is stored as float (~1e-4 px at 1300 px).
TEST(OpenCvExport, InitUndistortRectifyMapAgreesWithTheModel) {
  std::mt19937 rng(12);
  const InstrumentModel m =
      RandomModel(Kinematics::kSpherical, rng,
                  {Effect::kRadialDistortion, Effect::kTangentialDistortion,
                   Effect::kRationalDistortion, Effect::kThinPrism, Effect::kSensorTilt});
  const std::string path = TempPath("map_zoom1.yaml");
  WriteOpenCvCamera(path, m, 1);
  const ReadBack r = Read(path);
  cv::Mat map_u, map_v;
  cv::initUndistortRectifyMap(r.camera_matrix, r.dist, cv::Mat(), r.camera_matrix,
                              cv::Size(r.width, r.height), CV_32FC1, map_u, map_v);
  ASSERT_EQ(map_u.cols, m.cams[1].width);
  ASSERT_EQ(map_u.rows, m.cams[1].height);
  const CameraTool& cam = m.cams[1];
  for (int v = 0; v < cam.height; v += 97) {
    for (int u = 0; u < cam.width; u += 131) {
      const double ray[3] = {(u - cam.intrinsics[2]) / cam.intrinsics[0],
                             (v - cam.intrinsics[3]) / cam.intrinsics[1], 1.0};
      double pixel[2];
      ASSERT_TRUE(ProjectToPixel(cam.intrinsics.data(), cam.distortion.data(), ray, pixel));
      EXPECT_NEAR(map_u.at<float>(v, u), pixel[0], 1e-3) << u << "," << v;
      EXPECT_NEAR(map_v.at<float>(v, u), pixel[1], 1e-3) << u << "," << v;
    }
  }
}

// The shortest length OpenCV accepts that holds every coefficient in use.
TEST(OpenCvExport, DistortionCountIsTheShortestOpenCvLengthInUse) {
  InstrumentModel m = IdealModel(Kinematics::kSpherical, 1, CameraTool{});
  EXPECT_EQ(OpenCvDistortionCount(m, 0), 4);
  m.effects.Add(Effect::kTangentialDistortion);
  EXPECT_EQ(OpenCvDistortionCount(m, 0), 4);
  m.effects.Add(Effect::kRadialDistortion);
  EXPECT_EQ(OpenCvDistortionCount(m, 0), 5);
  m.effects.Add(Effect::kRationalDistortion);
  EXPECT_EQ(OpenCvDistortionCount(m, 0), 8);
  m.effects.Add(Effect::kThinPrism);
  EXPECT_EQ(OpenCvDistortionCount(m, 0), 12);
  m.effects.Add(Effect::kSensorTilt);
  EXPECT_EQ(OpenCvDistortionCount(m, 0), 14);
  // A non-zero coefficient counts even without its group (a given camera).
  InstrumentModel g = IdealModel(Kinematics::kSpherical, 1, CameraTool{});
  g.cams[0].distortion[kK5] = 1e-3;
  EXPECT_EQ(OpenCvDistortionCount(g, 0), 8);
  EXPECT_THROW(OpenCvDistortionCount(g, 1), std::out_of_range);

  const std::string path = TempPath("count.yaml");
  WriteOpenCvCamera(path, g, 0);
  EXPECT_EQ(static_cast<int>(Read(path).dist.total()), 8);
}

}  // namespace
}  // namespace rtscalib

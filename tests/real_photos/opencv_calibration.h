// OpenCV's own calibration of a camera from planar views, the reference the
// tests on real photos compare rtscalib's camera-only calibrations with.
#pragma once

#include <vector>

#include <opencv2/calib3d.hpp>

namespace rtscalib::testing_real_photos {

struct OpenCvCalibration {
  double rms = 0;
  double k[4] = {0, 0, 0, 0};      // fx, fy, cx, cy
  double sigma[4] = {0, 0, 0, 0};  // stdDeviationsIntrinsics
};

// calibrateCameraExtended (its C++ name is this overload of calibrateCamera)
// with flags 0: OpenCV's default model, k1 k2 p1 p2 k3.
inline OpenCvCalibration CalibrateWithOpenCv(const std::vector<std::vector<cv::Point3f>>& object,
                                             const std::vector<std::vector<cv::Point2f>>& image,
                                             const cv::Size& size) {
  cv::Mat k, d, sd_intrinsics, sd_extrinsics, per_view;
  std::vector<cv::Mat> rvecs, tvecs;
  OpenCvCalibration out;
  out.rms = cv::calibrateCamera(object, image, size, k, d, rvecs, tvecs, sd_intrinsics,
                                sd_extrinsics, per_view, 0);
  out.k[0] = k.at<double>(0, 0);
  out.k[1] = k.at<double>(1, 1);
  out.k[2] = k.at<double>(0, 2);
  out.k[3] = k.at<double>(1, 2);
  for (int i = 0; i < 4; ++i) out.sigma[i] = sd_intrinsics.at<double>(i);
  return out;
}

}  // namespace rtscalib::testing_real_photos

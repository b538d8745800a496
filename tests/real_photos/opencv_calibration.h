// OpenCV's own calibration of a camera from planar views, the reference the
// tests on real photos compare rtscalib's camera-only calibrations with.
#pragma once

#include <map>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>

#include "libcalib/model/observations.h"
#include "libcalib/model/targets.h"

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

// Pixel observations of boards of unknown pose as OpenCV's views: per
// shot (in shot order), each corner in its board's frame
// (TagBoard::CornersInBoard; one board per view, as calibrateCamera wants)
// and its pixel, in the observations' order.
struct OpenCvViews {
  std::vector<std::vector<cv::Point3f>> object;
  std::vector<std::vector<cv::Point2f>> image;
};
inline OpenCvViews ViewsOf(const std::vector<PixelObservation>& pixels, const TargetScene& targets) {
  std::map<std::string, std::pair<std::vector<cv::Point3f>, std::vector<cv::Point2f>>> views;
  for (const PixelObservation& p : pixels) {
    for (const TagBoard& b : targets.boards) {
      if (!b.HasId(p.target)) continue;
      const Eigen::Vector3d x = b.CornersInBoard(p.target - b.first_id)[p.corner];
      views[p.shot].first.emplace_back(x.x(), x.y(), x.z());
      views[p.shot].second.emplace_back(p.uv.x(), p.uv.y());
    }
  }
  OpenCvViews out;
  for (const auto& [shot, v] : views) {
    out.object.push_back(v.first);
    out.image.push_back(v.second);
  }
  return out;
}

}  // namespace rtscalib::testing_real_photos

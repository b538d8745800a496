#include "libcalib/export/opencv_export.h"

#include <opencv2/core.hpp>
#include <array>
#include <stdexcept>

#include "libcalib/model/focus.h"

namespace rtscalib {

int OpenCvDistortionCount(const InstrumentModel& model, int zoom) {
  if (zoom < 0 || zoom >= model.NumZooms()) {
    throw std::out_of_range("zoom level " + std::to_string(zoom) + " is not in the model (it has " +
                            std::to_string(model.NumZooms()) + " zoom levels)");
  }
  int needed = 0;
  for (Effect e : model.effects.List()) {
    if (!IsDistortion(e)) continue;
    for (int i : Info(e).distortion_indices) needed = std::max(needed, i + 1);
  }
  const auto& d = model.cams[zoom].distortion;
  for (int i = 0; i < kNumDistortion; ++i) {
    if (d[i] != 0.0) needed = std::max(needed, i + 1);
  }
  // The lengths cv::projectPoints and friends accept.
  for (int n : {4, 5, 8, 12}) {
    if (needed <= n) return n;
  }
  return kNumDistortion;
}

std::string OpenCvCameraFileName(int zoom) {
  return "camera_zoom" + std::to_string(zoom) + ".yaml";
}

void WriteOpenCvCamera(const std::string& path, const InstrumentModel& model, int zoom,
                       double focus_distance) {
  const int n = OpenCvDistortionCount(model, zoom);
  const CameraTool& cam = model.cams[zoom];
  const bool focus = model.effects.Has(Effect::kFocus);
  std::array<double, kNumIntrinsics> k = cam.intrinsics;
  if (focus && focus_distance > 0) {
    FocusedIntrinsics(cam.intrinsics.data(), cam.focus.data(), focus_distance, k.data());
  }
  const cv::Mat camera_matrix = (cv::Mat_<double>(3, 3) << k[0], 0, k[2], 0, k[1], k[3], 0, 0, 1);
  cv::Mat dist(1, n, CV_64F);
  for (int i = 0; i < n; ++i) dist.at<double>(0, i) = cam.distortion[i];

  cv::FileStorage fs;
  if (!fs.open(path, cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML)) {
    throw std::runtime_error("cannot write " + path);
  }
  fs.writeComment("rtscalib camera, zoom level " + std::to_string(zoom) +
                  ": OpenCV pinhole model (cv::projectPoints conventions); pixels");
  fs << "zoom" << zoom;
  fs << "image_width" << cam.width;
  fs << "image_height" << cam.height;
  fs << "camera_matrix" << camera_matrix;
  fs << "distortion_coefficients" << dist;
  if (focus) {
    fs.writeComment(
        "SPEC 4.1 focus: camera_matrix is focused at focus_distance [m] (0: at infinity); at "
        "focus distance D use fx (1 + focus_kf/D), fy (1 + focus_kf/D), cx + focus_au/D, "
        "cy + focus_av/D with fx, fy, cx, cy focused at infinity");
    fs << "focus_distance" << (focus_distance > 0 ? focus_distance : 0.0);
    fs << "focus_kf" << cam.focus[kFocusKf];
    fs << "focus_au" << cam.focus[kFocusAu];
    fs << "focus_av" << cam.focus[kFocusAv];
    fs << "infinity_camera_matrix"
       << (cv::Mat_<double>(3, 3) << cam.intrinsics[0], 0, cam.intrinsics[2], 0,
           cam.intrinsics[1], cam.intrinsics[3], 0, 0, 1);
  }
  fs.release();
}

}  // namespace rtscalib

// A zoom level's camera as an OpenCV calibration file (cv::FileStorage YAML).
//
// Keys (what cv::calibrateCamera users read back):
//   camera_matrix            3x3 double, [fx 0 cx; 0 fy cy; 0 0 1]        (pixels)
//   distortion_coefficients  1xN double, k1 k2 p1 p2 [k3 [k4 k5 k6 [s1 s2 s3 s4 [taux tauy]]]]
//   image_width, image_height   int (pixels), the model's image size
//   zoom                     int, the rtscalib zoom level (extra key; OpenCV readers ignore it)
// N is the shortest length OpenCV accepts (4, 5, 8, 12 or 14) that holds every
// coefficient the model uses: those of the enabled distortion groups and any
// non-zero one. The model's camera is OpenCV's pinhole model exactly (SPEC 2,
// libcalib/camera/opencv_model.h), so cv::projectPoints with these values
// reproduces rtscalib's projection of a camera-frame point.
#pragma once

#include <string>

#include "libcalib/model/instrument.h"

namespace rtscalib {

// The distortion vector length written for `zoom`: 4, 5, 8, 12 or 14.
int OpenCvDistortionCount(const InstrumentModel& model, int zoom);

// Writes `zoom`'s intrinsics with cv::FileStorage (YAML). Throws
// std::out_of_range for a zoom the model lacks, std::runtime_error when the
// file cannot be written.
void WriteOpenCvCamera(const std::string& path, const InstrumentModel& model, int zoom);

// The file name used for a zoom level: camera_zoom<z>.yaml.
std::string OpenCvCameraFileName(int zoom);

}  // namespace rtscalib

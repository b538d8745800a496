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
// With the `focus` effect (SPEC 4.1) the intrinsics depend on the focus
// distance D: the file states the D its camera_matrix holds (key
// `focus_distance` [m], 0 = focused at infinity) and the focus terms (keys
// `focus_kf` [m], `focus_au`, `focus_av` [px m]) with which a reader forms
// fx (1 + kf/D), fy (1 + kf/D), cx + au/D, cy + av/D for another D.
#pragma once

#include <string>

#include "libcalib/model/instrument.h"

namespace rtscalib {

// The distortion vector length written for `zoom`: 4, 5, 8, 12 or 14.
int OpenCvDistortionCount(const InstrumentModel& model, int zoom);

// Writes `zoom`'s intrinsics with cv::FileStorage (YAML), with the focus
// effect those focused at `focus_distance` [m] (<= 0: at infinity). Throws
// std::out_of_range for a zoom the model lacks, std::runtime_error when the
// file cannot be written.
void WriteOpenCvCamera(const std::string& path, const InstrumentModel& model, int zoom,
                       double focus_distance = 0);

// The file name used for a zoom level: camera_zoom<z>.yaml.
std::string OpenCvCameraFileName(int zoom);

}  // namespace rtscalib

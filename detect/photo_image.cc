#include "detect/photo_image.h"

#include <cmath>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace rtscalib::detect {
namespace {

int BitDepth(int depth) {
  switch (depth) {
    case CV_8U:
    case CV_8S:
      return 8;
    case CV_16U:
    case CV_16S:
      return 16;
    default:
      return 32;
  }
}

}  // namespace

cv::Mat ToGray8(const cv::Mat& image) {
  if (image.empty()) throw std::invalid_argument("ToGray8: empty image");
  const int depth = image.depth();
  if (depth != CV_8U && depth != CV_16U && depth != CV_32F) {
    throw std::invalid_argument(
        "ToGray8: expected an 8 or 16 bit unsigned or 32-bit float image, got OpenCV depth " +
        std::to_string(depth));
  }
  cv::Mat gray;
  switch (image.channels()) {
    case 1:
      gray = image;
      break;
    case 3:
      cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
      break;
    case 4:
      cv::cvtColor(image, gray, cv::COLOR_BGRA2GRAY);
      break;
    default:
      throw std::invalid_argument("ToGray8: expected 1, 3 or 4 channels, got " +
                                  std::to_string(image.channels()));
  }
  if (depth == CV_8U) return gray.isContinuous() ? gray : gray.clone();
  double lo = 0, hi = 0;
  cv::minMaxLoc(gray, &lo, &hi);
  if (!std::isfinite(lo) || !std::isfinite(hi)) {
    throw std::invalid_argument("ToGray8: image has non-finite values");
  }
  cv::Mat out;
  // A flat image stays flat (no tag can be in it; avoid dividing by zero).
  const double scale = hi > lo ? 255.0 / (hi - lo) : 0.0;
  gray.convertTo(out, CV_8U, scale, -lo * scale);  // rounds to nearest, saturates
  return out;
}

Photo LoadPhoto(const std::string& path) {
  // IMREAD_UNCHANGED keeps depth, channels and alpha, and ignores EXIF
  // orientation: pixels stay on the sensor's grid, which the camera model
  // describes.
  const cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (image.empty()) {
    throw std::runtime_error("cannot read image " + path +
                             " (expected a PNG, JPEG or TIFF file OpenCV can decode)");
  }
  Photo photo;
  photo.width = image.cols;
  photo.height = image.rows;
  photo.channels = image.channels();
  photo.bit_depth = BitDepth(image.depth());
  try {
    photo.gray = ToGray8(image);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error("image " + path + ": " + e.what());
  }
  return photo;
}

}  // namespace rtscalib::detect

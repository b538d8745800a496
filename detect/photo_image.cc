#include "detect/photo_image.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <vector>

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

// What the file's own structure says before it is decoded: whether it is
// whole, and the size its header claims (0 when not read).
struct FileCheck {
  bool complete = true;
  std::string problem;
  int width = 0, height = 0;
};

int Be16(const std::vector<uint8_t>& b, size_t i) { return (b[i] << 8) | b[i + 1]; }
uint32_t Be32(const std::vector<uint8_t>& b, size_t i) {
  return (uint32_t{b[i]} << 24) | (uint32_t{b[i + 1]} << 16) | (uint32_t{b[i + 2]} << 8) | b[i + 3];
}

// A JPEG's segments from SOI to EOI (ITU T.81 B.1). Each marker segment
// carries its length and is skipped whole (an EXIF thumbnail, with its own
// EOI, lies inside APP1); the entropy-coded data after SOS hold no marker
// but RSTn (0xFF is followed by a stuffed 0x00). libjpeg decodes a file cut
// short with the missing rows grey and only a warning on stderr ("Premature
// end of JPEG file"), which no caller sees: so the end is checked here.
FileCheck CheckJpeg(const std::vector<uint8_t>& b) {
  FileCheck out;
  const size_t n = b.size();
  size_t i = 2;  // after SOI
  while (true) {
    while (i + 1 < n && b[i] == 0xFF && b[i + 1] == 0xFF) ++i;  // fill bytes
    if (i + 1 >= n) break;
    if (b[i] != 0xFF) {
      out.complete = false;
      out.problem = "its JPEG markers break off at byte " + std::to_string(i);
      return out;
    }
    const int marker = b[i + 1];
    if (marker == 0xD9) return out;  // EOI
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) {
      i += 2;
      continue;
    }
    if (i + 3 >= n) break;
    const size_t length = Be16(b, i + 2);
    const bool sof = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 &&
                     marker != 0xCC;
    if (sof && i + 8 < n && out.width == 0) {
      out.height = Be16(b, i + 5);
      out.width = Be16(b, i + 7);
    }
    i += 2 + length;
    if (marker == 0xDA) {  // SOS: entropy-coded data up to the next marker
      while (i + 1 < n && !(b[i] == 0xFF && b[i + 1] != 0x00 && b[i + 1] != 0xFF &&
                            !(b[i + 1] >= 0xD0 && b[i + 1] <= 0xD7))) {
        ++i;
      }
    }
  }
  out.complete = false;
  out.problem = "the JPEG data end after " + std::to_string(n) + " bytes without its end marker";
  return out;
}

// A PNG's chunks from the signature to IEND (PNG spec 5.3); IHDR first
// gives the size.
FileCheck CheckPng(const std::vector<uint8_t>& b) {
  FileCheck out;
  const size_t n = b.size();
  size_t i = 8;  // after the signature
  while (i + 8 <= n) {
    const uint64_t length = Be32(b, i);
    const std::string type(b.begin() + static_cast<long>(i) + 4, b.begin() + static_cast<long>(i) + 8);
    if (type == "IHDR" && i + 16 <= n) {
      out.width = static_cast<int>(std::min<uint32_t>(Be32(b, i + 8), 0x7FFFFFFF));
      out.height = static_cast<int>(std::min<uint32_t>(Be32(b, i + 12), 0x7FFFFFFF));
    }
    if (type == "IEND") return out;
    i += 12 + length;  // length, type, data, CRC
  }
  out.complete = false;
  out.problem = "the PNG data end after " + std::to_string(n) + " bytes, before its IEND chunk";
  return out;
}

FileCheck CheckImageFile(const std::vector<uint8_t>& b) {
  static const uint8_t kPng[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  if (b.size() >= 8 && std::equal(kPng, kPng + 8, b.begin())) return CheckPng(b);
  if (b.size() >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF) return CheckJpeg(b);
  return {};  // another format: OpenCV's decoder judges it
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
  // The range of the median-filtered image (photo_image.h): isolated hot or
  // dead pixels do not set it. medianBlur takes 16-bit and float images at
  // a 3 x 3 aperture.
  cv::Mat median;
  cv::medianBlur(gray, median, 3);
  cv::minMaxLoc(median, &lo, &hi);
  cv::Mat out;
  // A flat image stays flat (no tag can be in it; avoid dividing by zero).
  const double scale = hi > lo ? 255.0 / (hi - lo) : 0.0;
  gray.convertTo(out, CV_8U, scale, -lo * scale);  // rounds to nearest, saturates
  return out;
}

Photo LoadPhoto(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw PhotoError("cannot open image " + path + ": " + std::strerror(errno));
  const std::streamoff size = in.tellg();
  std::vector<uint8_t> bytes(size > 0 ? static_cast<size_t>(size) : 0);
  in.seekg(0);
  if (!in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()))) {
    throw PhotoError("cannot read image " + path + ": " + std::strerror(errno));
  }
  const FileCheck check = CheckImageFile(bytes);
  if (!check.complete) {
    throw PhotoError("image " + path + " is damaged: " + check.problem +
                     " (a file cut short by a copy or a download?)");
  }
  // IMREAD_UNCHANGED keeps depth, channels and alpha, and ignores EXIF
  // orientation: pixels stay on the sensor's grid, which the camera model
  // describes.
  cv::Mat image;
  try {
    image = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    // OpenCV refuses what it cannot hold, e.g. a header claiming more pixels
    // than CV_IO_MAX_IMAGE_PIXELS.
    const std::string claims =
        check.width > 0 ? "its header claims " + std::to_string(check.width) + " x " +
                              std::to_string(check.height) + " pixels, and "
                        : "";
    throw PhotoError("image " + path + ": " + claims + "OpenCV refuses to decode it (" + e.err +
                     ")");
  }
  if (image.empty()) {
    throw PhotoError("cannot decode image " + path +
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
    throw PhotoError("image " + path + ": " + e.what());
  }
  return photo;
}

}  // namespace rtscalib::detect

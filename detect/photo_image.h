// Photos as the detector wants them: 8-bit grey, whatever the file holds.
//
// Files are read with cv::imread(IMREAD_UNCHANGED): PNG, JPEG, TIFF (whatever
// OpenCV's imgcodecs reads), grey or colour (BGR, BGRA), 8 or 16 bit unsigned,
// or 32-bit float. EXIF orientation is not applied: pixels stay on the
// sensor's grid.
//
// Conversion to 8-bit grey:
//   * colour -> grey with OpenCV's luma weights (0.299 R + 0.587 G + 0.114 B),
//     a linear map, so an edge's sub-pixel position is unchanged;
//   * 8-bit images are used as they are;
//   * other depths (16-bit, float) are stretched linearly from the image's own
//     [min, max] to [0, 255] and rounded. Nothing is clipped, whatever range
//     the camera used (a 12-bit sensor in a 16-bit file, a dark exposure), and
//     the corner refinement, which only needs the ink and paper levels on
//     either side of an edge, is invariant to a linear map of intensity; the
//     rounding adds at most half a grey level of noise. A fixed >> 8 would turn
//     a 12-bit image into 16 grey levels.
#pragma once

#include <string>

#include <opencv2/core.hpp>

namespace rtscalib::detect {

struct Photo {
  cv::Mat gray;   // CV_8UC1, what the detector sees
  int width = 0;  // the file's image size [px]
  int height = 0;
  int channels = 0;   // of the file: 1 grey, 3 BGR, 4 BGRA
  int bit_depth = 0;  // of the file: 8, 16 or 32 (float)
};

// `image` of any depth and 1, 3 or 4 channels as 8-bit grey (see above).
// Throws std::invalid_argument for other channel counts or depths.
cv::Mat ToGray8(const cv::Mat& image);

// Reads `path`; throws std::runtime_error naming it when OpenCV cannot read it
// or its format is not one ToGray8 takes.
Photo LoadPhoto(const std::string& path);

}  // namespace rtscalib::detect

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
//     range [lo, hi] to [0, 255] and rounded (SPEC 7.2: detected on their
//     full range). lo and hi are the least and greatest values of the image
//     after a 3 x 3 median filter: a region of 2 x 2 pixels or more (any tag,
//     any paper) keeps its values through the median and sets the range,
//     while a single hot or dead pixel (or a pair) does not: one hot pixel at
//     65535 in a 12-bit image would otherwise squeeze the whole picture into
//     16 grey levels. Only such isolated pixels fall outside [lo, hi] and
//     are clipped. Whatever range the camera used (a 12-bit sensor in a
//     16-bit file, a dark exposure), the corner refinement, which only needs
//     the ink and paper levels on either side of an edge, is invariant to a
//     linear map of intensity; the rounding adds at most half a grey level of
//     noise. A fixed >> 8 would turn a 12-bit image into 16 grey levels.
#pragma once

#include <stdexcept>
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

// Reads `path`. Throws PhotoError (a std::runtime_error naming the file and
// what is wrong with it) when the file is missing or unreadable, is not an
// image OpenCV decodes, claims more pixels than OpenCV reads
// (CV_IO_MAX_IMAGE_PIXELS, 2^30 by default: a header claiming 100000 x 100000
// is refused before any memory is taken), is damaged (a JPEG or PNG cut
// short: OpenCV's decoders fill the missing rows with grey and say so only
// on stderr, so the file's own end marker is checked), or has a format
// ToGray8 does not take.
struct PhotoError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
Photo LoadPhoto(const std::string& path);

}  // namespace rtscalib::detect

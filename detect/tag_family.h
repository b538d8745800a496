// AprilTag families by name, owned RAII, and their printed bit patterns.
//
// Geometry of a family's code image (libapriltag's apriltag_to_image): a
// square of `total_width` x `total_width` bits. The detection quad (the four
// corners libapriltag reports, our TagBoard::tag_size square) is the centred
// square of `width_at_border` bits, starting `border_offset()` bits in from the
// image edge. For the classic families (tag36h11, tag25h9, tag16h5) the quad
// is the outer edge of the black border and the outermost bit ring is the white
// quiet zone; for the `reversed_border` families (tagStandard41h12, ...) the
// quad is the edge between an outer black ring and an inner white ring, and
// data bits lie outside the quad.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

struct apriltag_family;  // libapriltag's apriltag_family_t

namespace rtscalib::detect {

struct TagFamilyDeleter {
  void operator()(apriltag_family* family) const;
};
using TagFamilyPtr = std::unique_ptr<apriltag_family, TagFamilyDeleter>;

// The names accepted by CreateTagFamily, e.g. "tag36h11".
const std::vector<std::string>& KnownTagFamilies();
// Every known family's number of codes (ids 0 .. n-1), e.g. for ReadTargets.
std::map<std::string, int> FamilyCodeCounts();

// Creates a family by name. Throws std::invalid_argument naming the known
// families when `name` is not one of them.
TagFamilyPtr CreateTagFamily(const std::string& name);

struct TagFamilyInfo {
  std::string name;
  int num_codes = 0;
  int width_at_border = 0;  // bits across the detection quad
  int total_width = 0;      // bits across the whole code image
  bool reversed_border = false;

  int border_offset() const { return (total_width - width_at_border) / 2; }
};
TagFamilyInfo GetTagFamilyInfo(const std::string& name);

// The code image of tag `id`: total_width x total_width, CV_8UC1, one pixel
// per bit, 0 = black, 255 = white, row 0 = top of the upright tag. Throws
// std::out_of_range for an id the family does not have.
cv::Mat TagCodeImage(const std::string& family, int id);
cv::Mat TagCodeImage(apriltag_family* family, int id);

}  // namespace rtscalib::detect

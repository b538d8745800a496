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
//
// A classic family may be printed with a wider black border (`border_bits`
// > 1, SPEC 7.2: Kalibr's AprilGrid has 2): the same codes, each bit moved
// border_bits - 1 bits further in, the quad (still the outer edge of the
// black border) 2 (border_bits - 1) bits wider, and so the whole code image:
// a tag36h11 code image of a 2-bit border is 12 bits, its quad 10 bits wide.
// libapriltag decodes such a family copy as it does the original (its
// decoder samples the border and the data bits through width_at_border and
// bit_x, bit_y).
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

// A tag family as printed: its name and the width of its black border.
struct PrintedFamily {
  std::string name = "tag36h11";
  int border_bits = 1;

  bool operator<(const PrintedFamily& o) const {
    return name != o.name ? name < o.name : border_bits < o.border_bits;
  }
  bool operator==(const PrintedFamily& o) const {
    return name == o.name && border_bits == o.border_bits;
  }
};

// Whether family `name` may be printed with border_bits > 1 (the classic
// families: their quad is the outer edge of the black border).
bool TakesWideBorder(const std::string& name);

// Creates a family by name, its bits moved in for a border of `border_bits`
// (above). Throws std::invalid_argument naming the known families when
// `name` is not one of them, or when border_bits is not 1 and the family
// does not take a wider border (or border_bits < 1).
TagFamilyPtr CreateTagFamily(const std::string& name, int border_bits = 1);
TagFamilyPtr CreateTagFamily(const PrintedFamily& family);

struct TagFamilyInfo {
  std::string name;
  int border_bits = 1;
  int num_codes = 0;
  int width_at_border = 0;  // bits across the detection quad
  int total_width = 0;      // bits across the whole code image
  bool reversed_border = false;

  int border_offset() const { return (total_width - width_at_border) / 2; }
};
TagFamilyInfo GetTagFamilyInfo(const std::string& name, int border_bits = 1);

// The code image of tag `id`: total_width x total_width, CV_8UC1, one pixel
// per bit, 0 = black, 255 = white, row 0 = top of the upright tag. Throws
// std::out_of_range for an id the family does not have.
cv::Mat TagCodeImage(const std::string& family, int id, int border_bits = 1);
cv::Mat TagCodeImage(apriltag_family* family, int id);

}  // namespace rtscalib::detect

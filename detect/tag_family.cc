#include "detect/tag_family.h"

#include <apriltag.h>
#include <tag16h5.h>
#include <tag25h9.h>
#include <tag36h10.h>
#include <tag36h11.h>
#include <tagCircle21h7.h>
#include <tagCircle49h12.h>
#include <tagCustom48h12.h>
#include <tagStandard41h12.h>
#include <tagStandard52h13.h>

#include <stdexcept>

namespace rtscalib::detect {
namespace {

struct FamilyEntry {
  const char* name;
  apriltag_family_t* (*create)();
  void (*destroy)(apriltag_family_t*);
};

const FamilyEntry kFamilies[] = {
    {"tag36h11", tag36h11_create, tag36h11_destroy},
    {"tag36h10", tag36h10_create, tag36h10_destroy},
    {"tag25h9", tag25h9_create, tag25h9_destroy},
    {"tag16h5", tag16h5_create, tag16h5_destroy},
    {"tagStandard41h12", tagStandard41h12_create, tagStandard41h12_destroy},
    {"tagStandard52h13", tagStandard52h13_create, tagStandard52h13_destroy},
    {"tagCircle21h7", tagCircle21h7_create, tagCircle21h7_destroy},
    {"tagCircle49h12", tagCircle49h12_create, tagCircle49h12_destroy},
    {"tagCustom48h12", tagCustom48h12_create, tagCustom48h12_destroy},
};

const FamilyEntry* FindFamily(const std::string& name) {
  for (const FamilyEntry& e : kFamilies) {
    if (name == e.name) return &e;
  }
  return nullptr;
}

const FamilyEntry& FamilyOrThrow(const std::string& name) {
  const FamilyEntry* e = FindFamily(name);
  if (e == nullptr) {
    std::string known;
    for (const std::string& k : KnownTagFamilies()) known += (known.empty() ? "" : ", ") + k;
    throw std::invalid_argument("unknown AprilTag family '" + name +
                                "'; expected one of: " + known);
  }
  return *e;
}

}  // namespace

void TagFamilyDeleter::operator()(apriltag_family* family) const {
  if (family == nullptr) return;
  FamilyOrThrow(family->name).destroy(family);
}

const std::vector<std::string>& KnownTagFamilies() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    for (const FamilyEntry& e : kFamilies) out.push_back(e.name);
    return out;
  }();
  return names;
}

std::map<std::string, int> FamilyCodeCounts() {
  std::map<std::string, int> out;
  for (const FamilyEntry& e : kFamilies) {
    apriltag_family_t* f = e.create();
    out[e.name] = static_cast<int>(f->ncodes);
    e.destroy(f);
  }
  return out;
}

bool TakesWideBorder(const std::string& name) {
  const FamilyEntry& e = FamilyOrThrow(name);
  apriltag_family_t* f = e.create();
  const bool classic = !f->reversed_border;
  e.destroy(f);
  return classic;
}

TagFamilyPtr CreateTagFamily(const std::string& name, int border_bits) {
  TagFamilyPtr f(FamilyOrThrow(name).create());
  if (border_bits == 1) return f;
  if (border_bits < 1 || f->reversed_border) {
    throw std::invalid_argument("tag family " + name + " cannot be printed with a black border of " +
                                std::to_string(border_bits) + " bits" +
                                (f->reversed_border ? " (its quad is not a black border's edge)"
                                                    : ""));
  }
  // The same arrays, edited in place: the family's destroy frees them alike.
  const int extra = border_bits - 1;
  f->width_at_border += 2 * extra;
  f->total_width += 2 * extra;
  for (uint32_t i = 0; i < f->nbits; ++i) {
    f->bit_x[i] += extra;
    f->bit_y[i] += extra;
  }
  return f;
}

TagFamilyPtr CreateTagFamily(const PrintedFamily& family) {
  return CreateTagFamily(family.name, family.border_bits);
}

TagFamilyInfo GetTagFamilyInfo(const std::string& name, int border_bits) {
  const TagFamilyPtr f = CreateTagFamily(name, border_bits);
  TagFamilyInfo info;
  info.name = name;
  info.border_bits = border_bits;
  info.num_codes = static_cast<int>(f->ncodes);
  info.width_at_border = f->width_at_border;
  info.total_width = f->total_width;
  info.reversed_border = f->reversed_border;
  return info;
}

cv::Mat TagCodeImage(const std::string& family, int id, int border_bits) {
  return TagCodeImage(CreateTagFamily(family, border_bits).get(), id);
}

cv::Mat TagCodeImage(apriltag_family* f, int id) {
  if (id < 0 || id >= static_cast<int>(f->ncodes)) {
    throw std::out_of_range("tag id " + std::to_string(id) + " is outside family " + f->name +
                            " (ids 0.." + std::to_string(f->ncodes - 1) + ")");
  }
  image_u8_t* im = apriltag_to_image(f, id);
  cv::Mat out(im->height, im->width, CV_8UC1);
  for (int y = 0; y < im->height; ++y) {
    for (int x = 0; x < im->width; ++x) out.at<uint8_t>(y, x) = im->buf[y * im->stride + x];
  }
  image_u8_destroy(im);
  return out;
}

}  // namespace rtscalib::detect

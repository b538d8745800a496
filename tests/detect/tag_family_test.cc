#include "detect/tag_family.h"

#include <apriltag/apriltag.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>
#include <vector>

namespace rtscalib::detect {
namespace {

TEST(TagFamily, KnownFamiliesCanBeCreated) {
  const std::vector<std::string>& known = KnownTagFamilies();
  // The families SPEC 7 and the docs name must be there.
  for (const char* name : {"tag36h11", "tag25h9", "tag16h5", "tagStandard41h12"}) {
    EXPECT_NE(std::find(known.begin(), known.end(), name), known.end()) << name;
  }
  for (const std::string& name : known) {
    const TagFamilyPtr f = CreateTagFamily(name);
    ASSERT_NE(f, nullptr) << name;
    EXPECT_EQ(std::string(f->name), name);
  }
}

TEST(TagFamily, UnknownFamilyNamesTheKnownOnes) {
  try {
    CreateTagFamily("tag36h12");
    FAIL() << "an unknown family must throw";
  } catch (const std::invalid_argument& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("tag36h12"), std::string::npos) << msg;
    EXPECT_NE(msg.find("tag36h11"), std::string::npos) << msg;
  }
  EXPECT_THROW(GetTagFamilyInfo(""), std::invalid_argument);
  EXPECT_THROW(TagCodeImage("nope", 0), std::invalid_argument);
}

TEST(TagFamily, InfoMatchesLibapriltagsPublishedFamilies) {
  // libapriltag's family definitions: codes, bits across the detection quad
  // and across the whole code image, and which ones have a reversed border.
  struct Expected {
    const char* name;
    int codes, width_at_border, total_width;
    bool reversed;
  };
  for (const Expected& e :
       {Expected{"tag36h11", 587, 8, 10, false}, Expected{"tag25h9", 35, 7, 9, false},
        Expected{"tag16h5", 30, 6, 8, false}, Expected{"tagStandard41h12", 2115, 5, 9, true}}) {
    const TagFamilyInfo info = GetTagFamilyInfo(e.name);
    EXPECT_EQ(info.name, e.name);
    EXPECT_EQ(info.num_codes, e.codes) << e.name;
    EXPECT_EQ(info.width_at_border, e.width_at_border) << e.name;
    EXPECT_EQ(info.total_width, e.total_width) << e.name;
    EXPECT_EQ(info.reversed_border, e.reversed) << e.name;
    EXPECT_EQ(info.border_offset(), (e.total_width - e.width_at_border) / 2) << e.name;
  }
}

// Value of ring k (0 = outermost) if it is uniform, else -1.
int RingValue(const cv::Mat& im, int k) {
  const int n = im.rows;
  int value = -2;
  for (int i = k; i < n - k; ++i) {
    for (const cv::Point p :
         {cv::Point(i, k), cv::Point(i, n - 1 - k), cv::Point(k, i), cv::Point(n - 1 - k, i)}) {
      const int v = im.at<uint8_t>(p);
      if (value == -2) value = v;
      if (v != value) return -1;
    }
  }
  return value;
}

TEST(TagFamily, CodeImageBordersFollowTheHeaderGeometry) {
  // Classic families: the quad is the outer edge of the black border, so ring
  // border_offset - 1 (the quiet zone) is white and ring border_offset black.
  // Reversed-border families: the quad is the edge between an outer black
  // ring and an inner white ring.
  for (const char* name : {"tag36h11", "tag25h9", "tag16h5", "tagStandard41h12"}) {
    const TagFamilyInfo info = GetTagFamilyInfo(name);
    for (int id : {0, 1, info.num_codes - 1}) {
      const cv::Mat im = TagCodeImage(name, id);
      ASSERT_EQ(im.type(), CV_8UC1);
      ASSERT_EQ(im.rows, info.total_width);
      ASSERT_EQ(im.cols, info.total_width);
      for (int y = 0; y < im.rows; ++y) {
        for (int x = 0; x < im.cols; ++x) {
          const int v = im.at<uint8_t>(y, x);
          ASSERT_TRUE(v == 0 || v == 255) << name << " " << id;
        }
      }
      const int b = info.border_offset();
      if (!info.reversed_border) {
        EXPECT_EQ(RingValue(im, b - 1), 255) << name << " " << id;
        EXPECT_EQ(RingValue(im, b), 0) << name << " " << id;
      } else {
        EXPECT_EQ(RingValue(im, b - 1), 0) << name << " " << id;
        EXPECT_EQ(RingValue(im, b), 255) << name << " " << id;
      }
    }
  }
  // Different ids have different patterns.
  EXPECT_GT(cv::norm(TagCodeImage("tag36h11", 0), TagCodeImage("tag36h11", 1), cv::NORM_L1), 0);
}

// SPEC 7.2: a 2-bit border (Kalibr's AprilGrid). The code image is two bits
// wider: a white quiet ring, two black rings, and the same data bits as the
// 1-bit image's, one bit further in. Families whose quad is not a black
// border's edge take no wider border.
TEST(TagFamily, TwoBitBorderMovesTheCodeOneBitIn) {
  const TagFamilyInfo one = GetTagFamilyInfo("tag36h11");
  const TagFamilyInfo two = GetTagFamilyInfo("tag36h11", 2);
  EXPECT_EQ(two.width_at_border, one.width_at_border + 2);
  EXPECT_EQ(two.total_width, one.total_width + 2);
  EXPECT_EQ(two.border_offset(), 1);
  EXPECT_EQ(two.num_codes, one.num_codes);
  for (const int id : {0, 17, 586}) {
    const cv::Mat a = TagCodeImage("tag36h11", id);
    const cv::Mat b = TagCodeImage("tag36h11", id, 2);
    ASSERT_EQ(b.rows, 12);
    EXPECT_EQ(RingValue(b, 0), 255);
    EXPECT_EQ(RingValue(b, 1), 0);
    EXPECT_EQ(RingValue(b, 2), 0);
    EXPECT_EQ(cv::norm(a(cv::Rect(2, 2, 6, 6)), b(cv::Rect(3, 3, 6, 6)), cv::NORM_L1), 0) << id;
  }
  EXPECT_TRUE(TakesWideBorder("tag36h11"));
  EXPECT_FALSE(TakesWideBorder("tagStandard41h12"));
  EXPECT_THROW(CreateTagFamily("tagStandard41h12", 2), std::invalid_argument);
  EXPECT_THROW(CreateTagFamily("tag36h11", 0), std::invalid_argument);
}

TEST(TagFamily, IdsOutsideTheFamilyThrow) {
  EXPECT_THROW(TagCodeImage("tag16h5", 30), std::out_of_range);
  EXPECT_THROW(TagCodeImage("tag16h5", -1), std::out_of_range);
  const TagFamilyPtr f = CreateTagFamily("tag25h9");
  EXPECT_NO_THROW(TagCodeImage(f.get(), 34));
  EXPECT_THROW(TagCodeImage(f.get(), 35), std::out_of_range);
  // Both overloads give the same image.
  EXPECT_EQ(cv::norm(TagCodeImage(f.get(), 7), TagCodeImage("tag25h9", 7), cv::NORM_L1), 0);
}

// The upscaled code image detected by libapriltag itself: the id comes back
// with no bit errors and the corners lie on the quad in libapriltag's order
// (corner 0 bottom-left, 1 bottom-right, 2 top-right, 3 top-left: SPEC 7),
// which shows that row 0 is the top of the upright tag.
TEST(TagFamily, LibapriltagDetectsTheCodeImageUprightWithSpecCornerOrder) {
  constexpr int kScale = 16, kMargin = 40;
  struct Case {
    std::string name;
    int id, border_bits;
  };
  for (const auto& [name, id, border] : std::vector<Case>{{"tag36h11", 0, 1},
                                                          {"tag36h11", 123, 1},
                                                          {"tag25h9", 20, 1},
                                                          {"tagStandard41h12", 77, 1},
                                                          {"tag36h11", 123, 2}}) {
    const TagFamilyInfo info = GetTagFamilyInfo(name, border);
    cv::Mat big;
    cv::resize(TagCodeImage(name, id, border), big, cv::Size(), kScale, kScale, cv::INTER_NEAREST);
    cv::Mat padded;
    cv::copyMakeBorder(big, padded, kMargin, kMargin, kMargin, kMargin, cv::BORDER_CONSTANT,
                       cv::Scalar(255));
    const TagFamilyPtr family = CreateTagFamily(name, border);
    apriltag_detector_t* td = apriltag_detector_create();
    td->quad_decimate = 1.0;
    td->nthreads = 1;
    apriltag_detector_add_family(td, family.get());
    image_u8_t im{padded.cols, padded.rows, static_cast<int32_t>(padded.step), padded.data};
    zarray_t* detections = apriltag_detector_detect(td, &im);
    ASSERT_EQ(zarray_size(detections), 1) << name << " " << id;
    apriltag_detection_t* det = nullptr;
    zarray_get(detections, 0, &det);
    EXPECT_EQ(det->id, id) << name;
    EXPECT_EQ(det->hamming, 0) << name;
    // Quad edges in pixel-centre coordinates: the border_offset-th bit edge.
    const double lo = kMargin + kScale * info.border_offset() - 0.5;
    const double hi = lo + kScale * info.width_at_border;
    const double expected[4][2] = {{lo, hi}, {hi, hi}, {hi, lo}, {lo, lo}};
    for (int k = 0; k < 4; ++k) {
      // libapriltag's quad fit on a sharp, axis-aligned edge: within a pixel
      // (the half-pixel convention of its coordinates included).
      EXPECT_NEAR(det->p[k][0], expected[k][0], 1.0) << name << " corner " << k;
      EXPECT_NEAR(det->p[k][1], expected[k][1], 1.0) << name << " corner " << k;
    }
    apriltag_detections_destroy(detections);
    apriltag_detector_destroy(td);
  }
}

}  // namespace
}  // namespace rtscalib::detect

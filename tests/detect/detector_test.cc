// The detector on photos synthesized without the renderer (synthetic_photo.h):
// the SPEC 2 pixel convention and the SPEC 7 corner order, checked against
// corners known exactly from the homography that made the photo. Rendered-
// and-detected tests live in tests/render/detector_test.cc.
#include "detect/detector.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <opencv2/imgproc.hpp>

#include "detect/photo_image.h"
#include "tests/detect/synthetic_photo.h"

namespace rtscalib::detect {
namespace {

using testing::MakeHomography;
using testing::PrintedTag;
using testing::PrintTag;
using testing::Project;
using testing::QuadCorners;
using testing::RenderCoverage;
using testing::ToPixels;

// The required accuracy of a refined corner on a clean, sharp synthetic
// photo: the refinement measures edges by pixel areas, which the synthesizer
// reproduces to < 0.008 px of edge position; 0.05 px leaves room for the 8-bit
// rounding of the grey levels and is 10x below a half-pixel convention error
// (a swapped corner would be a whole tag edge off).
constexpr double kCornerTolPx = 0.05;

struct View {
  double scale;  // pixels per code bit
  double angle;  // image rotation [rad]
  double px_per, py_per;
};

// Largest corner error seen by ExpectExactCorners in this process [px].
double g_max_error_px = 0;

// Detects the one tag of `photo` (converted by ToGray8) and checks its id,
// refinement and corners against the exact ones.
void ExpectExactCorners(const cv::Mat& photo, const std::string& family, int id,
                        const std::array<Eigen::Vector2d, 4>& exact, const std::string& what) {
  DetectorOptions options;
  options.families = {PrintedFamily{family}};
  TagDetector detector(options);
  const std::vector<TagDetection> found = detector.Detect(ToGray8(photo));
  ASSERT_EQ(found.size(), 1u) << what;
  const TagDetection& d = found[0];
  EXPECT_EQ(d.id, id) << what;
  EXPECT_EQ(d.family, family) << what;
  EXPECT_EQ(d.refinement, CornerRefinement::kEdges) << what;
  for (int k = 0; k < 4; ++k) {
    g_max_error_px = std::max(g_max_error_px, (d.corners[k] - exact[k]).norm());
    EXPECT_LT((d.corners[k] - exact[k]).norm(), kCornerTolPx)
        << what << " corner " << k << ": detected " << d.corners[k].transpose() << ", exact "
        << exact[k].transpose();
    // libapriltag's corners, shifted to SPEC pixels, are within ~0.3 px; a
    // half-pixel convention error would show here too.
    EXPECT_LT((d.apriltag_corners[k] - exact[k]).norm(), 0.35) << what << " corner " << k;
  }
}

TEST(DetectorConventionTest, CornersAndOrderOnSynthesizedPhotos) {
  g_max_error_px = 0;
  const int id = 7;
  // The tag's quad is the plane square [0, 8]^2 (one plane unit = one bit of
  // tag36h11); sizes from 4.5 to 11 px per bit, quarter turns (the order
  // must follow the printed tag, not the image), odd angles and perspective.
  const std::vector<View> views = {
      {6.0, 0.0, 0, 0},         {6.0, M_PI / 2, 0, 0},   {6.0, M_PI, 0, 0},
      {6.0, -M_PI / 2, 0, 0},   {4.5, 0.3, 0.01, -0.02}, {11.0, 2.0, -0.015, 0.01},
      {7.3, -2.7, 0.02, 0.015}, {5.2, 1.1, 0, 0.025},
  };
  for (size_t v = 0; v < views.size(); ++v) {
    const View& view = views[v];
    const PrintedTag tag = PrintTag("tag36h11", id, 0, 0, 8);
    // An off-centre position (not symmetric about a pixel centre or edge).
    const Eigen::Matrix3d h = MakeHomography(8, Eigen::Vector2d(101.3 + 3 * v, 97.8 - 2 * v),
                                             view.scale, view.angle, view.px_per, view.py_per);
    const cv::Mat coverage = RenderCoverage({tag}, h, 200, 200);
    std::array<Eigen::Vector2d, 4> exact;
    const std::array<Eigen::Vector2d, 4> quad = QuadCorners(tag);
    for (int k = 0; k < 4; ++k) exact[k] = Project(h, quad[k]);
    const std::string what = "view " + std::to_string(v);
    ExpectExactCorners(ToPixels(coverage, CV_8UC1, cv::Scalar(25), cv::Scalar(230)), "tag36h11", id,
                       exact, what + " 8-bit grey");
    // 16 bit, 12 bits used (a >> 8 would leave 16 grey levels).
    ExpectExactCorners(ToPixels(coverage, CV_16UC1, cv::Scalar(300), cv::Scalar(3900)), "tag36h11",
                       id, exact, what + " 16-bit grey");
    // Colour with unequal channels (yellowish paper, bluish ink), BGR.
    ExpectExactCorners(
        ToPixels(coverage, CV_8UC3, cv::Scalar(60, 20, 10), cv::Scalar(150, 235, 245)), "tag36h11",
        id, exact, what + " 8-bit colour");
    ExpectExactCorners(
        ToPixels(coverage, CV_16UC3, cv::Scalar(9000, 3000, 2000), cv::Scalar(40000, 60000, 61000)),
        "tag36h11", id, exact, what + " 16-bit colour");
  }
  std::printf("tag36h11, 8 views x 4 formats: max corner error %.4f px\n", g_max_error_px);
}

TEST(DetectorConventionTest, OtherFamilies) {
  g_max_error_px = 0;
  for (const std::string family : {"tag25h9", "tag16h5", "tagStandard41h12"}) {
    const TagFamilyInfo info = GetTagFamilyInfo(family);
    const double w = info.width_at_border;
    const PrintedTag tag = PrintTag(family, 3, 0, 0, w);
    const Eigen::Matrix3d h =
        MakeHomography(w, Eigen::Vector2d(99.6, 100.2), 60.0 / w, 2.4, 0.01, 0.005);
    const cv::Mat coverage = RenderCoverage({tag}, h, 200, 200);
    std::array<Eigen::Vector2d, 4> exact;
    const std::array<Eigen::Vector2d, 4> quad = QuadCorners(tag);
    for (int k = 0; k < 4; ++k) exact[k] = Project(h, quad[k]);
    ExpectExactCorners(ToPixels(coverage, CV_8UC1, cv::Scalar(20), cv::Scalar(235)), family, 3,
                       exact, family);
  }
  std::printf("other families: max corner error %.4f px\n", g_max_error_px);
}

// Below the edge refinement's 2.5 px per bit, the detector refines a tag by
// fitting its whole pattern (tag_pattern_fit.h); from 2.5 px per bit on, by
// its edges.
TEST(DetectorTest, SmallTagsGetThePatternFit) {
  const int id = 12;
  for (const double bit : {1.8, 2.2, 3.0}) {
    const PrintedTag tag = PrintTag("tag36h11", id, 0, 0, 8);
    const Eigen::Matrix3d h = MakeHomography(8, Eigen::Vector2d(50.4, 49.7), bit, 0.7, 0.004, 0);
    cv::Mat coverage = RenderCoverage({tag}, h, 100, 100);
    cv::GaussianBlur(coverage, coverage, cv::Size(0, 0), 0.5);
    std::array<Eigen::Vector2d, 4> exact;
    const std::array<Eigen::Vector2d, 4> quad = QuadCorners(tag);
    for (int k = 0; k < 4; ++k) exact[k] = Project(h, quad[k]);
    TagDetector detector;
    const std::vector<TagDetection> found =
        detector.Detect(ToPixels(coverage, CV_8UC1, cv::Scalar(25), cv::Scalar(230)));
    ASSERT_EQ(found.size(), 1u) << bit;
    EXPECT_EQ(found[0].id, id);
    EXPECT_EQ(found[0].refinement,
              bit < DetectorOptions().min_bit_pixels ? CornerRefinement::kPattern
                                                     : CornerRefinement::kEdges)
        << bit << " px per bit";
    for (int k = 0; k < 4; ++k) {
      // tag_pattern_fit_test.cc: 0.01-0.02 px on such photos; libapriltag's
      // own corners are 0.1-0.2 px off here.
      EXPECT_LT((found[0].corners[k] - exact[k]).norm(), 0.05) << bit << " corner " << k;
    }
  }
  // Refinement off: libapriltag's corners, marked as such.
  DetectorOptions off;
  off.refine_corners = false;
  TagDetector detector(off);
  const PrintedTag tag = PrintTag("tag36h11", id, 0, 0, 8);
  const cv::Mat coverage =
      RenderCoverage({tag}, MakeHomography(8, Eigen::Vector2d(50, 50), 2.0, 0.3), 100, 100);
  const std::vector<TagDetection> found =
      detector.Detect(ToPixels(coverage, CV_8UC1, cv::Scalar(25), cv::Scalar(230)));
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].refinement, CornerRefinement::kNone);
  EXPECT_EQ(found[0].corners, found[0].apriltag_corners);
}

TEST(DetectorTest, NoiseSigmaIsEstimatedDespiteEdges) {
  cv::setRNGSeed(3);
  // Flat grey with Gaussian noise of 2 grey levels.
  cv::Mat flat(480, 640, CV_64FC1, cv::Scalar(120));
  cv::Mat noise(flat.size(), CV_64FC1);
  cv::randn(noise, 0, 2.0);
  cv::Mat img;
  cv::Mat(flat + noise).convertTo(img, CV_8UC1);
  // The rounding to integers adds 1/12 grey level^2 of variance.
  const double expected = std::sqrt(4.0 + 1.0 / 12);
  EXPECT_NEAR(EstimateNoiseSigma(img), expected, 0.1 * expected);
  // A photo of tags (edges everywhere, a quarter of the pixels near one)
  // with 1 grey level of noise: the edges do not move the median.
  std::vector<PrintedTag> tags;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 5; ++c) {
      tags.push_back(PrintTag("tag36h11", 5 * r + c, 10.0 * c, 10.0 * r, 8));
    }
  }
  const Eigen::Matrix3d h = MakeHomography(48, Eigen::Vector2d(320.3, 240.6), 9.0, 0.2);
  const cv::Mat coverage = RenderCoverage(tags, h, 640, 480);
  cv::randn(noise, 0, 1.0);
  cv::Mat(coverage * 200 + 30 + noise).convertTo(img, CV_8UC1);
  const double one = std::sqrt(1.0 + 1.0 / 12);
  EXPECT_NEAR(EstimateNoiseSigma(img), one, 0.15 * one);
  // Without noise: only the rounding of the edge pixels.
  cv::Mat(coverage * 200 + 30).convertTo(img, CV_8UC1);
  EXPECT_LT(EstimateNoiseSigma(img), 0.2);
}

TEST(DetectorTest, TinyTagsAreNotRefined) {
  // A synthetic 20 px tag36h11 (2.5 px bits) is below min_bit_pixels = 3.
  cv::Mat img(100, 100, CV_8UC1, cv::Scalar(200));
  std::array<Eigen::Vector2d, 4> corners = {Eigen::Vector2d(40, 60), Eigen::Vector2d(60, 60),
                                            Eigen::Vector2d(60, 40), Eigen::Vector2d(40, 40)};
  const auto before = corners;
  DetectorOptions options;
  options.min_bit_pixels = 3.0;
  EXPECT_FALSE(RefineTagCorners(img, 8, options, &corners));
  EXPECT_EQ(corners, before);
}

TEST(DetectorTest, OptionsAreChecked) {
  DetectorOptions o;
  EXPECT_EQ(o.Check(), "");
  o.families = {PrintedFamily{"tag42h42"}};
  EXPECT_NE(o.Check(), "");
  EXPECT_THROW(TagDetector{o}, std::invalid_argument);
  o = DetectorOptions();
  o.threads = 0;
  EXPECT_NE(o.Check(), "");
  TagDetector detector;
  EXPECT_THROW(detector.Detect(cv::Mat(10, 10, CV_8UC3)), std::invalid_argument);
}

}  // namespace
}  // namespace rtscalib::detect

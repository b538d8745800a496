// The figures' PNG files: an SVG drawn by librsvg in process (app/plot/svg_raster.h).
#include "app/plot/svg_raster.h"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

namespace rtscalib::app {
namespace {

// A 40 x 30 pixel SVG: a red 10 x 10 square at (5, 5) on a transparent page.
constexpr const char* kSquare =
    "<svg xmlns='http://www.w3.org/2000/svg' width='40' height='30'>"
    "<rect x='5' y='5' width='10' height='10' fill='#ff0000'/></svg>";

TEST(SvgRasterizer, DrawsTheSvgOnWhiteAtItsOwnSize) {
  const SvgRasterizer& raster = SvgRasterizer::Get();
  if (!raster.missing().empty()) GTEST_SKIP() << raster.missing();
  std::vector<unsigned char> png;
  std::string error;
  ASSERT_TRUE(raster.ToPng(kSquare, &png, &error)) << error;
  const cv::Mat im = cv::imdecode(png, cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(im.empty());
  EXPECT_EQ(im.cols, 40);
  EXPECT_EQ(im.rows, 30);
  ASSERT_EQ(im.channels(), 3);  // opaque: the page is painted white first
  // Pixel centres well inside and well outside the square (antialiasing
  // touches only its edge pixels).
  EXPECT_EQ(im.at<cv::Vec3b>(10, 10), cv::Vec3b(0, 0, 255));      // BGR red
  EXPECT_EQ(im.at<cv::Vec3b>(25, 30), cv::Vec3b(255, 255, 255));  // the white page
  EXPECT_EQ(im.at<cv::Vec3b>(2, 2), cv::Vec3b(255, 255, 255));
}

TEST(SvgRasterizer, SaysWhatIsWrongWithABrokenSvg) {
  const SvgRasterizer& raster = SvgRasterizer::Get();
  if (!raster.missing().empty()) GTEST_SKIP() << raster.missing();
  std::vector<unsigned char> png;
  std::string error;
  EXPECT_FALSE(raster.ToPng("<svg xmlns='http://www.w3.org/2000/svg' width='40'", &png, &error));
  EXPECT_NE(error.find("librsvg"), std::string::npos) << error;
  EXPECT_TRUE(png.empty());
}

}  // namespace
}  // namespace rtscalib::app

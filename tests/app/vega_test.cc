// The figures' renderer (app/vega.h): node started ahead of the specs, one
// SVG after the other, each PNG drawn in this process; a spec that Vega
// cannot draw is named by its own error, the others are drawn; a renderer
// that never draws ends its node and leaves no temporary folder.
#include "app/vega.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <string>

#include "app/svg_raster.h"

namespace rtscalib::app {
namespace {

namespace fs = std::filesystem;

// A 100 x 60 px chart: one red bar on a white page.
nlohmann::json Bar() {
  return nlohmann::json::parse(R"({
    "width": 100, "height": 60, "padding": 0, "background": "white",
    "marks": [{"type": "rect", "encode": {"enter": {
      "x": {"value": 10}, "width": {"value": 30}, "y": {"value": 10}, "height": {"value": 40},
      "fill": {"value": "#ff0000"}}}}]})");
}

bool Drawable(std::string* why) {
  std::string missing;
  if (VegaRuntime(&missing).empty()) {
    *why = missing;
    return false;
  }
  if (!SvgRasterizer::Get().missing().empty()) {
    *why = SvgRasterizer::Get().missing();
    return false;
  }
  return true;
}

std::set<std::string> FigureFolders() {
  std::set<std::string> out;
  for (const fs::directory_entry& e : fs::directory_iterator(fs::temp_directory_path())) {
    if (e.path().filename().string().rfind("rtscalib-figures-", 0) == 0) {
      out.insert(e.path().string());
    }
  }
  return out;
}

TEST(VegaRenderer, DrawsEachSpecAndNamesTheOneVegaCannotDraw) {
  std::string why;
  if (!Drawable(&why)) GTEST_SKIP() << why;
  VegaRenderer renderer;
  nlohmann::json broken = Bar();
  broken["marks"][0]["from"] = {{"data", "no_such_data"}};
  std::string note;
  const std::vector<RenderedFigure> out = renderer.Draw({Bar(), broken, Bar()}, &note);
  if (note.find("node is not installed") != std::string::npos) GTEST_SKIP() << note;
  ASSERT_EQ(out.size(), 3u) << note;
  EXPECT_TRUE(note.empty()) << note;
  for (size_t i : {size_t{0}, size_t{2}}) {
    EXPECT_NE(out[i].svg.find("<svg"), std::string::npos);
    EXPECT_TRUE(out[i].error.empty()) << out[i].error;
    const cv::Mat png = cv::imdecode(out[i].png, cv::IMREAD_COLOR);
    ASSERT_FALSE(png.empty());
    EXPECT_EQ(png.cols, 100);
    EXPECT_EQ(png.rows, 60);
    EXPECT_EQ(png.at<cv::Vec3b>(30, 25), cv::Vec3b(0, 0, 255));     // inside the bar (BGR)
    EXPECT_EQ(png.at<cv::Vec3b>(30, 70), cv::Vec3b(255, 255, 255));  // the page
  }
  EXPECT_TRUE(out[1].svg.empty());
  EXPECT_NE(out[1].error.find("no_such_data"), std::string::npos) << out[1].error;
}

TEST(VegaRenderer, EndsItsNodeAndRemovesItsFolderWhenItNeverDraws) {
  std::string why;
  if (!Drawable(&why)) GTEST_SKIP() << why;
  const std::set<std::string> before = FigureFolders();
  {
    VegaRenderer renderer;  // started; destroyed before node has read the runtime
  }
  {
    VegaRenderer renderer;
    std::string note;
    EXPECT_TRUE(renderer.Draw({}, &note).empty());  // nothing to draw
  }
  EXPECT_EQ(FigureFolders(), before);
}

}  // namespace
}  // namespace rtscalib::app

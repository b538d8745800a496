// The figures' renderer (app/plot/vega.h): each spec drawn as SVG and PNG on
// the renderer's threads (all at once, or handed over one at a time while
// the next are made), each handed to the caller as soon as it is drawn; a
// spec outside the drawn part of Vega is named by its own error, the
// others are drawn; a renderer that never draws ends its threads.
#include "app/plot/vega.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "app/plot/svg_raster.h"

namespace rtscalib::app {
namespace {

// A 100 x 60 px chart: one red bar on a white page.
nlohmann::json Bar() {
  return nlohmann::json::parse(R"({
    "width": 100, "height": 60, "padding": 0, "background": "white",
    "marks": [{"type": "rect", "encode": {"enter": {
      "x": {"value": 10}, "width": {"value": 30}, "y": {"value": 10}, "height": {"value": 40},
      "fill": {"value": "#ff0000"}}}}]})");
}

bool Drawable(std::string* why) {
  if (!SvgRasterizer::Get().missing().empty()) {
    *why = SvgRasterizer::Get().missing();
    return false;
  }
  return true;
}

TEST(VegaRenderer, DrawsEachSpecAndNamesTheOneItCannotDraw) {
  std::string why;
  if (!Drawable(&why)) GTEST_SKIP() << why;
  VegaRenderer renderer;
  nlohmann::json broken = Bar();
  broken["marks"][0]["from"] = {{"data", "no_such_data"}};
  nlohmann::json malformed = Bar();
  malformed["width"] = "wide";  // a spec Vega would refuse too
  std::string note;
  std::mutex mutex;
  std::multiset<size_t> handed;  // figures handed over as soon as drawn
  const std::vector<RenderedFigure> out = renderer.Draw(
      {Bar(), broken, Bar(), malformed}, &note, [&](size_t i, const RenderedFigure& fig) {
        EXPECT_FALSE(fig.png.empty());
        const std::lock_guard<std::mutex> lock(mutex);
        handed.insert(i);
      });
  ASSERT_EQ(out.size(), 4u) << note;
  EXPECT_TRUE(note.empty()) << note;
  EXPECT_EQ(handed, (std::multiset<size_t>{0, 2}));
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
  EXPECT_TRUE(out[1].png.empty());
  EXPECT_NE(out[1].error.find("no_such_data"), std::string::npos) << out[1].error;
  EXPECT_TRUE(out[3].svg.empty());
  EXPECT_NE(out[3].error.find("must be number"), std::string::npos) << out[3].error;
}

// Specs handed over one at a time while the earlier ones are drawn: the
// drawings are collected on another thread as they are drawn, one per
// index (an index never handed over says so); nothing comes after End.
TEST(VegaRenderer, DrawsSpecsHandedOverWhileItDrawsAndCollectsThemByIndex) {
  std::string why;
  if (!Drawable(&why)) GTEST_SKIP() << why;
  VegaRenderer renderer;
  std::string note;
  std::mutex mutex;
  std::vector<size_t> handed;  // in the order the PNGs were drawn
  std::thread collector;
  std::vector<RenderedFigure> out;
  collector = std::thread([&] {
    out = renderer.Collect(&note, [&](size_t i, const RenderedFigure&) {
      const std::lock_guard<std::mutex> lock(mutex);
      handed.push_back(i);
    });
  });
  nlohmann::json wide = Bar();
  wide["width"] = 150;
  const nlohmann::json bar = Bar();
  renderer.Add(3, bar);
  renderer.Add(0, wide);
  renderer.End();
  EXPECT_THROW(renderer.Add(1, bar), std::logic_error);
  collector.join();
  EXPECT_TRUE(note.empty()) << note;
  ASSERT_EQ(out.size(), 4u);
  for (size_t i : {size_t{0}, size_t{3}}) {
    EXPECT_TRUE(out[i].error.empty()) << out[i].error;
    const cv::Mat png = cv::imdecode(out[i].png, cv::IMREAD_COLOR);
    ASSERT_FALSE(png.empty());
    EXPECT_EQ(png.cols, i == 0 ? 150 : 100);
  }
  for (size_t i : {size_t{1}, size_t{2}}) {
    EXPECT_TRUE(out[i].png.empty());
    EXPECT_EQ(out[i].error, "not handed to the renderer");
  }
  std::sort(handed.begin(), handed.end());
  EXPECT_EQ(handed, (std::vector<size_t>{0, 3}));
}

TEST(VegaRenderer, EndsItsThreadsWhenItNeverDraws) {
  {
    VegaRenderer renderer;  // destroyed while its threads load librsvg
  }
  {
    const nlohmann::json bar = Bar();  // outlives the renderer, as Add asks
    VegaRenderer renderer;
    renderer.Add(0, bar);  // drawn, never collected
  }
  VegaRenderer renderer;
  std::string note;
  EXPECT_TRUE(renderer.Draw({}, &note).empty());  // nothing to draw
}

}  // namespace
}  // namespace rtscalib::app

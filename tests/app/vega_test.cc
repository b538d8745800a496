// The figures' renderer (app/vega.h): node started ahead of the specs, one
// SVG after the other (all at once, or handed over one at a time while node
// draws), each PNG drawn in this process and handed to the caller as soon
// as it is drawn; a spec that Vega cannot draw is named by
// its own error, the others are drawn; a renderer that never draws ends its
// node and leaves no temporary folder. Node's start-up snapshot is built
// once into the cache folder and started from after that, with the same
// SVG bytes; a damaged one is removed and the figures are drawn without it,
// as they are without a cache folder.
#include "app/vega.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

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
  std::mutex mutex;
  std::multiset<size_t> handed;  // figures handed over as soon as drawn
  const std::vector<RenderedFigure> out =
      renderer.Draw({Bar(), broken, Bar()}, &note, [&](size_t i, const RenderedFigure& fig) {
        EXPECT_FALSE(fig.png.empty());
        const std::lock_guard<std::mutex> lock(mutex);
        handed.insert(i);
      });
  if (note.find("node is not installed") != std::string::npos) GTEST_SKIP() << note;
  ASSERT_EQ(out.size(), 3u) << note;
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
}

// Specs handed over one at a time while node draws the earlier ones: the
// drawings are collected on another thread, in the order node answers,
// one per index (an index never handed over says so); nothing comes after
// End.
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
  renderer.Add(3, Bar().dump());
  renderer.Add(0, wide.dump());
  renderer.End();
  EXPECT_THROW(renderer.Add(1, Bar().dump()), std::logic_error);
  collector.join();
  if (note.find("node is not installed") != std::string::npos) GTEST_SKIP() << note;
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

// An environment variable set for one test, the old value back after it.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::optional<std::string>& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    if (value) {
      ::setenv(name, value->c_str(), 1);
    } else {
      ::unsetenv(name);
    }
  }
  ~ScopedEnv() {
    if (old_) {
      ::setenv(name_, old_->c_str(), 1);
    } else {
      ::unsetenv(name_);
    }
  }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  const char* name_;
  std::optional<std::string> old_;
};

// A cache folder of its own, removed afterwards.
class SnapshotCache : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!Drawable(&why)) GTEST_SKIP() << why;
    node_ = Node();
    if (node_.empty()) GTEST_SKIP() << "node is not installed";
    cache_ = fs::temp_directory_path() / ("rtscalib_vega_cache_" + std::to_string(::getpid()));
    fs::remove_all(cache_);
    env_.emplace("XDG_CACHE_HOME", cache_.string());
  }
  void TearDown() override {
    env_.reset();
    std::error_code ec;
    if (!cache_.empty()) fs::remove_all(cache_, ec);
  }
  // node on PATH, as the renderer finds it.
  static std::string Node() {
    std::istringstream dirs(std::getenv("PATH") ? std::getenv("PATH") : "");
    std::string d;
    while (std::getline(dirs, d, ':')) {
      if (::access((fs::path(d) / "node").c_str(), X_OK) == 0) return (fs::path(d) / "node").string();
    }
    return "";
  }
  std::string node_;
  fs::path cache_;
  std::optional<ScopedEnv> env_;
};

TEST_F(SnapshotCache, IsBuiltOnceReplacingOthersAndStartedFromWithTheSameSvg) {
  const std::string blob = VegaSnapshotPath(node_);
  ASSERT_FALSE(blob.empty());
  EXPECT_EQ(fs::path(blob).parent_path(), cache_ / "rtscalib");
  EXPECT_FALSE(fs::exists(blob));
  // Another node's snapshot, replaced by this one.
  const fs::path stale = fs::path(blob).parent_path() / "vega-0123456789abcdef.blob";
  fs::create_directories(stale.parent_path());
  std::ofstream(stale) << "another node's";
  std::string note;
  VegaRenderer first;
  EXPECT_EQ(first.how(), "built the snapshot " + blob);
  const std::vector<RenderedFigure> built = first.Draw({Bar()}, &note);
  ASSERT_EQ(built.size(), 1u) << note;
  EXPECT_TRUE(fs::exists(blob));
  // Only the snapshot is left in the cache folder (no file of the build, no
  // other snapshot).
  EXPECT_EQ(std::distance(fs::directory_iterator(cache_ / "rtscalib"), fs::directory_iterator()), 1);
  VegaRenderer second;
  EXPECT_EQ(second.how(), "started from the snapshot " + blob);
  const std::vector<RenderedFigure> started = second.Draw({Bar()}, &note);
  ASSERT_EQ(started.size(), 1u) << note;
  EXPECT_FALSE(started[0].svg.empty());
  EXPECT_EQ(started[0].svg, built[0].svg);
}

TEST_F(SnapshotCache, ADamagedSnapshotIsRemovedAndTheFiguresAreDrawnWithoutIt) {
  const std::string blob = VegaSnapshotPath(node_);
  ASSERT_FALSE(blob.empty());
  fs::create_directories(fs::path(blob).parent_path());
  std::ofstream(blob) << "not a snapshot";
  VegaRenderer renderer;
  EXPECT_EQ(renderer.how().rfind("read the runtime", 0), 0u) << renderer.how();
  EXPECT_FALSE(fs::exists(blob));  // the next renderer builds it again
  std::string note;
  const std::vector<RenderedFigure> out = renderer.Draw({Bar()}, &note);
  ASSERT_EQ(out.size(), 1u) << note;
  EXPECT_FALSE(out[0].png.empty()) << out[0].error;
}

TEST_F(SnapshotCache, WithoutACacheFolderTheFiguresAreDrawnWithoutASnapshot) {
  const ScopedEnv xdg("XDG_CACHE_HOME", std::nullopt), home("HOME", std::nullopt);
  EXPECT_EQ(VegaSnapshotPath(node_), "");
  VegaRenderer renderer;
  EXPECT_NE(renderer.how().find("no cache folder"), std::string::npos) << renderer.how();
  std::string note;
  const std::vector<RenderedFigure> out = renderer.Draw({Bar()}, &note);
  ASSERT_EQ(out.size(), 1u) << note;
  EXPECT_FALSE(out[0].png.empty()) << out[0].error;
}

TEST(VegaRenderer, EndsItsNodeAndRemovesItsFolderWhenItNeverDraws) {
  std::string why;
  if (!Drawable(&why)) GTEST_SKIP() << why;
  // A temporary folder of this test's own: other tests' renderers, running
  // in parallel, make and remove their folders in the system's.
  const fs::path tmp = fs::temp_directory_path() /
                       ("rtscalib-vega-test-" + std::to_string(::getpid()));
  fs::create_directories(tmp);
  const ScopedEnv tmpdir("TMPDIR", tmp.string());
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
  std::error_code ec;
  fs::remove_all(tmp, ec);
}

}  // namespace
}  // namespace rtscalib::app

// Headless display handling: Xvfb started when DISPLAY is unset.
#include "render/headless.h"

#include <gtest/gtest.h>
#include <signal.h>

#include <cstdlib>
#include <optional>
#include <string>

#include "render/scene_renderer.h"
#include "tests/render/render_fixture.h"

namespace rtscalib::render {
namespace {

// Unsets DISPLAY for the test's scope and restores it afterwards.
class NoDisplay {
 public:
  NoDisplay() {
    if (const char* d = std::getenv("DISPLAY")) saved_ = d;
    ::unsetenv("DISPLAY");
  }
  ~NoDisplay() {
    if (saved_) ::setenv("DISPLAY", saved_->c_str(), 1);
  }

 private:
  std::optional<std::string> saved_;
};

TEST(HeadlessDisplayTest, RendersWithDisplayUnset) {
  NoDisplay no_display;
  pid_t server = -1;
  {
    HeadlessDisplay display;
    ASSERT_TRUE(display.started_server());
    server = display.server_pid();
    ASSERT_NE(std::getenv("DISPLAY"), nullptr);
    EXPECT_EQ(std::string(std::getenv("DISPLAY")), display.display());
    EXPECT_EQ(display.display().front(), ':');
    EXPECT_STREQ(std::getenv("GALLIUM_DRIVER"), "llvmpipe");
    EXPECT_STREQ(std::getenv("LIBGL_ALWAYS_SOFTWARE"), "1");

    const TagBoard board = testing::FrontBoard();
    SceneRenderer renderer(testing::SceneOf(board));
    const CameraTool cam = testing::TestCamera(false);
    const cv::Mat img = renderer.Render(Rigid3(), cam);
    ASSERT_EQ(img.rows, cam.height);
    ASSERT_EQ(img.cols, cam.width);
    // The board is in the middle: paper and ink there, background at the rim.
    double lo, hi;
    cv::minMaxLoc(img(cv::Rect(540, 400, 200, 160)), &lo, &hi);
    EXPECT_LT(lo, 40);
    EXPECT_GT(hi, 220);
    EXPECT_NEAR(img.at<uint8_t>(10, 10), renderer.options().background, 1.0);
  }
  // The server is gone and the environment restored.
  EXPECT_EQ(std::getenv("DISPLAY"), nullptr);
  EXPECT_NE(::kill(server, 0), 0);
}

TEST(HeadlessDisplayTest, UsesAnExistingDisplay) {
  testing::EnsureDisplay();
  const std::string before = std::getenv("DISPLAY");
  HeadlessDisplay display;
  EXPECT_FALSE(display.started_server());
  EXPECT_EQ(display.display(), before);
}

TEST(HeadlessDisplayTest, MissingXvfbIsAClearError) {
  NoDisplay no_display;
  HeadlessOptions options;
  options.xvfb = "Xvfb-does-not-exist";
  try {
    HeadlessDisplay display(options);
    FAIL() << "expected a DisplayError";
  } catch (const DisplayError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("Xvfb-does-not-exist"), std::string::npos) << msg;
    EXPECT_NE(msg.find("DISPLAY"), std::string::npos) << msg;
  }
}

TEST(HeadlessDisplayTest, FindExecutable) {
  EXPECT_FALSE(FindExecutable("sh").empty());
  EXPECT_TRUE(FindExecutable("no-such-program-anywhere").empty());
  EXPECT_EQ(FindExecutable("/bin/sh"), "/bin/sh");
}

}  // namespace
}  // namespace rtscalib::render

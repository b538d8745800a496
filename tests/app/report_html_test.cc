// report.json's diagnosis (SPEC 6) and report.html, end to end on a small
// simulated run with one hidden effect; the page is loaded in headless
// Chromium when it is installed.
#include "app/report_html.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "app/commands.h"
#include "tests/app/read_file.h"

namespace rtscalib::app {
namespace {

namespace fs = std::filesystem;

// A run whose instrument hides a horizontal circle eccentricity, through the
// command itself (`rtscalib diagnose --config run.yaml --output out`).
class ReportRun : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(fs::temp_directory_path() /
                        ("rtscalib_report_test_" + std::to_string(::getpid())));
    fs::remove_all(*dir_);
    fs::create_directories(*dir_);
    std::ofstream(*dir_ / "run.yaml") << R"(
model:
  kinematics: dh
  effects: []
  cameras:
    - {width: 1280, height: 960, fx: 1500, fy: 1500, cx: 640, cy: 480}
simulate:
  seed: 3
  truth:
    effects: {hz_eccentricity: [5.0, 30.0]}
  noise: {angle_arcsec: 1.0, distance_m: 1.0e-5, point_m: 1.0e-5}
  plan:
    edm_distances: [1, 2, 7]
    grid: {phi_steps: 8, theta_steps: 5, edm_distances: [1, 2.3, 12], pixels_per_axis: 3}
    faces: [1, 2]
output: out
)";
    RunArgs args;
    args.config = (*dir_ / "run.yaml").string();
    args.output = (*dir_ / "out").string();
    args.quiet = true;
    ::testing::internal::CaptureStdout();
    rc_ = RunDiagnose(args);
    ::testing::internal::GetCapturedStdout();
    std::ifstream in(*dir_ / "out" / "report.json");
    report_ = new nlohmann::json(nlohmann::json::parse(in));
  }
  static void TearDownTestSuite() { fs::remove_all(*dir_); }
  static fs::path Out(const std::string& name) { return *dir_ / "out" / name; }
  static std::string Html() { return testing_files::ReadFile(Out("report.html")); }

  static fs::path* dir_;
  static int rc_;
  static nlohmann::json* report_;
};
fs::path* ReportRun::dir_ = nullptr;
int ReportRun::rc_ = -1;
nlohmann::json* ReportRun::report_ = nullptr;

TEST_F(ReportRun, ReportJsonHasTheSpecDiagnosis) {
  ASSERT_EQ(rc_, 0);
  const nlohmann::json& d = (*report_)["diagnosis"];
  ASSERT_TRUE(d["ranking"].is_array());
  // Every catalogue effect not in the model is listed (SPEC 6).
  EXPECT_EQ(d["ranking"].size(), EffectCatalogue().size());
  const nlohmann::json& top = d["ranking"][0];
  for (const char* key : {"effect", "rms_before", "rms_after", "delta_bic", "significant",
                          "identifiable", "config_line"}) {
    EXPECT_TRUE(top.contains(key)) << key;
  }
  EXPECT_EQ(top["effect"], "hz_eccentricity");
  EXPECT_TRUE(top["significant"].get<bool>());
  EXPECT_EQ(top["config_line"], "model.effects: [hz_eccentricity]");
  EXPECT_LT(top["rms_after"].get<double>(), top["rms_before"].get<double>());
  ASSERT_TRUE(d["unexplained"].is_array());
  EXPECT_TRUE(d["unexplained"].empty()) << d["unexplained"].dump();
}

TEST_F(ReportRun, HtmlIsSelfContainedAndReadsTopDown) {
  const std::string html = Html();
  ASSERT_FALSE(html.empty());
  // Only embedded pictures: no reference to another file (every src= or
  // href= value is a data: URI or an anchor in the page).
  for (const std::string attr : {"src=\"", "href=\""}) {
    for (size_t at = html.find(attr); at != std::string::npos; at = html.find(attr, at + 1)) {
      const size_t value = at + attr.size();
      ASSERT_LT(value, html.size());
      EXPECT_TRUE(html[value] == 'd' || html[value] == '#')
          << attr << html.substr(value, 60) << " at " << at;
    }
  }
  const size_t verdict = html.find("Verdict"), maps = html.find("Where the model fails"),
               ranking = html.find("Which effect is missing");
  ASSERT_NE(verdict, std::string::npos);
  ASSERT_NE(maps, std::string::npos);
  ASSERT_NE(ranking, std::string::npos);
  EXPECT_LT(verdict, maps);
  EXPECT_LT(maps, ranking);
  EXPECT_NE(html.find("model.effects: [hz_eccentricity]"), std::string::npos);
  // The image coverage with report.json's warnings, before the maps of
  // projection uncertainty.
  const size_t coverage = html.find("id=\"coverage\"");
  ASSERT_NE(coverage, std::string::npos);
  EXPECT_LT(coverage, html.find("id=\"uncertainty\""));
  for (const nlohmann::json& w : (*report_)["coverage"]["warnings"]) {
    const std::string text = w.get<std::string>();
    const std::string plain = text.substr(0, std::min<size_t>(text.find_first_of("<>&\"'"), 40));
    EXPECT_NE(html.find(plain, coverage), std::string::npos) << text;
  }
  // The figures: Vega specs drawn by the runtime inlined in the page.
  EXPECT_NE(html.find("new vega.View"), std::string::npos);
  const nlohmann::json& figures = (*report_)["figures"]["list"];
  std::set<std::string> names;
  for (const nlohmann::json& f : figures) {
    names.insert(f["name"].get<std::string>());
    EXPECT_NE(html.find("data-figure=\"" + f["name"].get<std::string>() + "\""), std::string::npos)
        << f["name"];
    // Each file report.json names is there: the spec, and the SVG and PNG
    // when the renderer is installed (else report.json says why not).
    for (const nlohmann::json& file : f["files"]) {
      EXPECT_TRUE(fs::exists(Out(file.get<std::string>()))) << file;
    }
    EXPECT_EQ(f["files"].size() == 3, !(*report_)["figures"].contains("note"));
  }
  for (const char* f : {"error_map_edm", "error_map_cam_zoom0", "image_residuals_zoom0",
                        "residuals_vs_variables", "residual_histograms"}) {
    EXPECT_TRUE(names.count(f)) << f;
  }
  // The residual table beside report.json: one row per record, every row fitted
  // or excluded with a reason.
  const nlohmann::json& res = (*report_)["residuals"];
  EXPECT_EQ(res["file"], "residuals.csv");
  EXPECT_EQ(res["rows"].get<size_t>(), (*report_)["data"]["records"].get<size_t>() +
                                           (*report_)["data"]["pixels"].get<size_t>());
  EXPECT_TRUE(fs::exists(Out("residuals.csv")));
  EXPECT_GT(res["status"]["fitted"].get<int>(), 0);
}

bool HaveChromium() {
  return std::system(
             "command -v chromium > /dev/null 2>&1 || command -v chromium-browser > /dev/null "
             "2>&1") == 0;
}

TEST_F(ReportRun, LoadsInHeadlessChromiumWithoutErrors) {
  if (!HaveChromium()) {
    GTEST_SKIP()
        << "chromium is not installed (scripts/install-deps.sh installs it): report.html was not "
           "checked in a browser";
  }
  const fs::path png = *dir_ / "report.png";
  const std::string cmd = std::string(RTSCALIB_SOURCE_DIR) + "/scripts/render-report.sh '" +
                          Out("report.html").string() + "' '" + png.string() + "' > /dev/null 2>&1";
  const int rc = std::system(cmd.c_str());
  // render-report.sh also fails when a figure of the page is missing, failed
  // to draw or drew no data marks (its DOM check).
  ASSERT_EQ(rc, 0) << "render-report.sh failed; see " << png.string() << ".log";
  ASSERT_TRUE(fs::exists(png));
  EXPECT_GT(fs::file_size(png), 20000u);  // a rendered page, not a blank one
}

}  // namespace
}  // namespace rtscalib::app

// The earlier runs of an output folder as report.json lists them
// (app/reports.h HistoryJson): the complete runs' numbers, whether they come
// from the latest complete run's own list or from each run's report.json,
// and the other runs by their state.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "app/output_folder.h"
#include "app/reports.h"

namespace rtscalib::app {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

class HistoryJsonTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::path(::testing::TempDir()) / ("rtscalib_history_json_" + std::to_string(::getpid()));
    fs::remove_all(root_);
  }
  void TearDown() override { fs::remove_all(root_); }

  // history/<name> with a status and, unless `report` is null, a report.json.
  void Entry(const std::string& name, const std::string& status, const json& report) {
    const fs::path dir = root_ / "history" / name;
    fs::create_directories(dir);
    std::ofstream(dir / "status") << status << "\n";
    if (!report.is_null()) std::ofstream(dir / "report.json") << report.dump(2) << "\n";
  }

  static json Report(const std::string& effect, double rms, const json& history) {
    return {{"model", {{"kinematics", "none"}, {"effects", {effect}}, {"cameras", json::array()}}},
            {"final", {{"pixels_rms_px", rms}}},
            {"fit", {{"iterations", 3}}},
            {"history", history}};
  }

  fs::path root_;
};

TEST_F(HistoryJsonTest, CompleteRunsCarryTheirNumbersWhereverTheyAreReadFrom) {
  // 001 complete; 002 failed; 003 complete, listing 001 (as a run before it
  // did); 004 complete, listing 001 to 003; 005 complete but listed by no
  // later run; 006 killed (running, its process gone).
  const json r1 = Report("radial_distortion", 0.5, json::array());
  const json e1 = {{"run", "001-20260101-000001"},
                   {"status", "complete"},
                   {"kinematics", "none"},
                   {"effects", {"radial_distortion"}},
                   {"final", {{"pixels_rms_px", 0.5}}}};
  const json e2 = {{"run", "002-20260101-000002"}, {"status", "failed"}, {"reason", "boom"}};
  const json e3 = {{"run", "003-20260101-000003"},
                   {"status", "complete"},
                   {"kinematics", "none"},
                   {"effects", {"thin_prism"}},
                   {"final", {{"pixels_rms_px", 0.3}}}};
  Entry("001-20260101-000001", "complete", r1);
  Entry("002-20260101-000002", "failed: boom", nullptr);
  Entry("003-20260101-000003", "complete", Report("thin_prism", 0.3, {e1, e2}));
  Entry("004-20260101-000004", "complete", Report("sensor_tilt", 0.2, {e1, e2, e3}));
  Entry("005-20260101-000005", "complete", Report("focus", 0.1, json::array()));
  Entry("006-20260101-000006", "running\npid: 999999999\nhost: nowhere", nullptr);
  const OutputFolder out(root_.string());
  const json h = HistoryJson(out);
  ASSERT_EQ(h.size(), 6u) << h.dump(1);
  EXPECT_EQ(h[0], e1);
  EXPECT_EQ(h[1]["status"], "failed");
  EXPECT_EQ(h[1]["reason"], "boom");
  EXPECT_FALSE(h[1].contains("final"));
  EXPECT_EQ(h[2], e3);
  for (const auto& [i, effect, rms] : {std::tuple{3, "sensor_tilt", 0.2}, {4, "focus", 0.1}}) {
    EXPECT_EQ(h[i]["status"], "complete");
    EXPECT_EQ(h[i]["effects"], json::array({effect}));
    EXPECT_EQ(h[i]["final"]["pixels_rms_px"], rms);
  }
  EXPECT_NE(h[5]["status"], "complete");
  EXPECT_FALSE(h[5].contains("final"));
}

// A run whose report.json is gone is not complete, whatever a later run's
// list says; an unreadable one neither.
TEST_F(HistoryJsonTest, ARunWithoutAReadableReportIsIncomplete) {
  const json e1 = {{"run", "001-20260101-000001"},
                   {"status", "complete"},
                   {"kinematics", "none"},
                   {"effects", {"radial_distortion"}},
                   {"final", {{"pixels_rms_px", 0.5}}}};
  Entry("001-20260101-000001", "complete", nullptr);
  Entry("002-20260101-000002", "complete", Report("thin_prism", 0.3, {e1}));
  Entry("003-20260101-000003", "complete", nullptr);
  std::ofstream(root_ / "history" / "003-20260101-000003" / "report.json") << "{\"model\": ";
  const OutputFolder out(root_.string());
  const json h = HistoryJson(out);
  ASSERT_EQ(h.size(), 3u) << h.dump(1);
  for (int i : {0, 2}) {
    EXPECT_EQ(h[i]["status"], "incomplete") << h[i].dump();
    EXPECT_EQ(h[i]["reason"], "report.json missing or unreadable");
  }
  EXPECT_EQ(h[1]["effects"], json::array({"thin_prism"}));
}

}  // namespace
}  // namespace rtscalib::app

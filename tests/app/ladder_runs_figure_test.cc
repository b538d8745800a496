// The ladder across runs (RunsLadderFigure): every complete run of the output
// folder's history and this run, drawn from report.json's own `final`
// numbers, capped to the latest kLadderRunsShown rungs so that a folder of
// many runs still gives a figure a screen shows.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "app/ladder_figures.h"

namespace rtscalib::app {
namespace {

// report.json's "history" entry of run `index` (1-based): complete, with
// an EDM and a pixel rms that fall with the run number.
nlohmann::json HistoryRun(int index, const std::vector<std::string>& effects) {
  char run[32];
  std::snprintf(run, sizeof(run), "%03d-20261127-0400%02d", index, index % 60);
  return {{"run", run},
          {"status", "complete"},
          {"kinematics", "dh"},
          {"effects", effects},
          {"final",
           {{"records", {{"edm", {{"rms_m", 1e-3 / index}, {"n", 100}}}}},
            {"pixels", {{"rms_px", 1.0 / index}, {"n", 400}}}}}};
}

const nlohmann::json& SeriesOf(const Figure& f, const std::string& unit) {
  for (const nlohmann::json& s : f.summary["series"]) {
    if (s["unit"] == unit) return s["points"];
  }
  static const nlohmann::json none = nlohmann::json::array();
  ADD_FAILURE() << "no " << unit << " series";
  return none;
}

TEST(RunsLadderFigure, ManyRunsShowTheLatestWithWhatChangedAgainstTheRunBefore) {
  nlohmann::json history = nlohmann::json::array();
  std::vector<std::string> effects = {"radial_distortion"};
  for (int i = 1; i <= 30; ++i) {
    // Run 20 adds hz_eccentricity: the first run shown (31 rungs, the
    // latest 12: runs 20-30 and this run) names it.
    if (i == 20) effects.push_back("hz_eccentricity");
    history.push_back(HistoryRun(i, effects));
  }
  // A run that did not complete has no `final`: listed by the table, not drawn.
  history.push_back({{"run", "031-20261127-050000"}, {"status", "running"}});
  const nlohmann::json final = {{"records", {{"edm", {{"rms_m", 2e-5}, {"n", 100}}}}},
                                {"pixels", {{"rms_px", 0.02}, {"n", 400}}}};
  const Figure f = RunsLadderFigure(history, effects, final);

  EXPECT_EQ(f.name, "ladder_runs");
  EXPECT_EQ(f.summary["runs"].get<int>(), 31);
  const nlohmann::json& rungs = f.summary["rungs"];
  ASSERT_EQ(rungs.size(), kLadderRunsShown);
  EXPECT_EQ(rungs.front().get<std::string>(), "run 020: +hz_eccentricity");
  EXPECT_EQ(rungs[1].get<std::string>(), "run 021");
  EXPECT_EQ(rungs.back().get<std::string>(), "this run");
  EXPECT_NE(f.title.find("latest 12 of 31"), std::string::npos) << f.title;

  // The drawn values are report.json's, unit for unit: mm for the EDM.
  const nlohmann::json& mm = SeriesOf(f, "mm");
  const nlohmann::json& px = SeriesOf(f, "px");
  ASSERT_EQ(mm.size(), kLadderRunsShown);
  ASSERT_EQ(px.size(), kLadderRunsShown);
  EXPECT_DOUBLE_EQ(mm.front()["value"].get<double>(), 1e-3 / 20 * 1e3);
  EXPECT_DOUBLE_EQ(px.front()["value"].get<double>(), 1.0 / 20);
  EXPECT_DOUBLE_EQ(mm.back()["value"].get<double>(), 2e-5 * 1e3);
  EXPECT_DOUBLE_EQ(px.back()["value"].get<double>(), 0.02);

  // One panel per unit, each as wide as its rungs need, never wider than
  // the cap's rungs at 110 px.
  for (const nlohmann::json& panel : f.spec["marks"]) {
    EXPECT_LE(panel["encode"]["enter"]["width"]["value"].get<int>(),
              110 * static_cast<int>(kLadderRunsShown));
  }
}

TEST(RunsLadderFigure, FewRunsAreAllShown) {
  nlohmann::json history = nlohmann::json::array();
  history.push_back(HistoryRun(1, {}));
  history.push_back(HistoryRun(2, {"radial_distortion"}));
  const nlohmann::json final = {{"records", {{"edm", {{"rms_m", 1e-4}, {"n", 100}}}}},
                                {"pixels", {{"rms_px", 0.1}, {"n", 0}}}};
  const Figure f = RunsLadderFigure(history, {}, final);
  EXPECT_EQ(f.summary["runs"].get<int>(), 3);
  const nlohmann::json& rungs = f.summary["rungs"];
  ASSERT_EQ(rungs.size(), 3u);
  EXPECT_EQ(rungs[0].get<std::string>(), "run 001");
  EXPECT_EQ(rungs[1].get<std::string>(), "run 002: +radial_distortion");
  EXPECT_EQ(rungs[2].get<std::string>(), "this run: -radial_distortion");
  EXPECT_EQ(f.title, "The ladder across runs (this output folder's history)");
  // No image points in this run (n 0): its pixel rung is not drawn.
  EXPECT_EQ(SeriesOf(f, "px").size(), 2u);
}

}  // namespace
}  // namespace rtscalib::app

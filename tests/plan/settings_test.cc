// The `plan` config section (libcalib/plan/settings.h): values read, bad
// values and unknown keys named with their key path, relative paths
// resolved against the config's folder.
#include "libcalib/plan/settings.h"

#include <gtest/gtest.h>

#include <string>

#include "libcalib/text/errors.h"

namespace rtscalib::testing_plan {
namespace {

PlanSettings Read(const std::string& text) {
  const YamlDocument doc = YamlDocument::Parse(text, "plan.yaml");
  PlanSettings s = ReadPlanSettings(doc.Root().Require("plan"), "/cfg");
  doc.CheckAllKeysUsed();
  return s;
}

std::string Error(const std::string& text) {
  try {
    Read(text);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(PlanSettings, ReadsEveryKey) {
  const PlanSettings s = Read(
      "plan:\n"
      "  goal:\n"
      "    sigmas: {hz_eccentricity.e: 0.5, 'cam[0].fx': 0.2}\n"
      "    projection_px: 0.05\n"
      "  faces: [2]\n"
      "  zooms: [0, 2]\n"
      "  max_shots: 50\n"
      "  candidates_per_board: 9\n"
      "  fill: 0.5\n"
      "  exchange: false\n"
      "  board_poses: unknown\n"
      "  prior_model: earlier/model.yaml\n"
      "  board: boards/targets.yaml\n");
  ASSERT_EQ(s.options.goal.sigmas.size(), 2u);
  EXPECT_EQ(s.options.goal.sigmas[0].first, "hz_eccentricity.e");
  EXPECT_EQ(s.options.goal.sigmas[1].second, 0.2);
  EXPECT_EQ(s.options.goal.projection_px, 0.05);
  EXPECT_EQ(s.options.faces, std::vector<int>{2});
  EXPECT_EQ(s.options.zooms, (std::vector<int>{0, 2}));
  EXPECT_EQ(s.options.max_shots, 50);
  EXPECT_EQ(s.options.candidates_per_board, 9);
  EXPECT_EQ(s.options.fill, 0.5);
  EXPECT_FALSE(s.options.exchange);
  ASSERT_TRUE(s.board_poses_known.has_value());
  EXPECT_FALSE(*s.board_poses_known);
  EXPECT_EQ(s.prior_model, "/cfg/earlier/model.yaml");
  EXPECT_EQ(s.board, "/cfg/boards/targets.yaml");
  EXPECT_TRUE(s.present);
}

TEST(PlanSettings, BadValuesAndUnknownKeysNameTheirKey) {
  EXPECT_NE(Error("plan: {max_shots: 0}\n").find("plan.max_shots"), std::string::npos);
  EXPECT_NE(Error("plan: {faces: [3]}\n").find("plan.faces"), std::string::npos);
  EXPECT_NE(Error("plan: {goal: {sigmas: {collimation.c: -1}}}\n").find("collimation.c"),
            std::string::npos);
  EXPECT_NE(Error("plan: {board_poses: surveyed}\n").find("plan.board_poses"), std::string::npos);
  EXPECT_NE(Error("plan: {max_shot: 10}\n").find("plan.max_shot"), std::string::npos);
  EXPECT_NE(Error("plan: {goal: {projection: 0.1}}\n").find("plan.goal.projection"),
            std::string::npos);
}

}  // namespace
}  // namespace rtscalib::testing_plan

// report.txt's list of strongly correlated parameters
// (StrongCorrelationsText): the 16 strongest pairs, the strongest first, so
// that a pair whose |rho| sits at the 0.95 threshold (listed in one run,
// not in the next, as the fit's threads sum in varying order) changes
// only the count of the pairs not shown.
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "app/reports.h"

namespace rtscalib::app {
namespace {

// The listed lines ("  a ~ b  rho = ..."), in order.
std::vector<std::string> ListedPairs(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("  ", 0) == 0 && line.find(" rho = ") != std::string::npos)
      lines.push_back(line);
  }
  return lines;
}

TEST(StrongCorrelationsText, ListsTheStrongestFirstSoAPairAtTheThresholdMovesNoOther) {
  FitSummary fit;
  // In parameter order: four pairs just over the threshold, then 16
  // stronger ones, two of them tied at |rho| = 1.000.
  for (int i = 0; i < 4; ++i)
    fit.strong_correlations.push_back({"weak" + std::to_string(i), 0.951});
  for (int i = 0; i < 14; ++i) {
    fit.strong_correlations.push_back({"strong" + std::to_string(i), -(0.96 + 0.002 * i)});
  }
  fit.strong_correlations.push_back({"tied_a", -0.99996});
  fit.strong_correlations.push_back({"tied_b", 1.0});
  const std::string text = StrongCorrelationsText(fit);
  const std::vector<std::string> listed = ListedPairs(text);
  ASSERT_EQ(listed.size(), 16u) << text;
  EXPECT_EQ(listed[0], "  tied_a  rho = -1.000");  // ties keep parameter order
  EXPECT_EQ(listed[1], "  tied_b  rho = +1.000");
  EXPECT_EQ(listed[2], "  strong13  rho = -0.986");
  EXPECT_EQ(listed[15], "  strong0  rho = -0.960");
  EXPECT_EQ(text.find("weak"), std::string::npos) << text;
  EXPECT_NE(text.find("... and 4 more pairs"), std::string::npos) << text;

  // Another run of the same data where one more pair crossed the threshold,
  // first in parameter order: the same 16 lines.
  FitSummary again = fit;
  again.strong_correlations.insert(again.strong_correlations.begin(), {"crossed", -0.9501});
  const std::string text_again = StrongCorrelationsText(again);
  EXPECT_EQ(ListedPairs(text_again), listed);
  EXPECT_NE(text_again.find("... and 5 more pairs"), std::string::npos) << text_again;

  EXPECT_EQ(StrongCorrelationsText(FitSummary()), "");
}

// A camera calibrated from boards of unknown pose: each placement's pose
// correlates with the principal point. Those pairs are counted on one line,
// and the pairs among the camera's own parameters are all listed, weaker
// as they are.
TEST(StrongCorrelationsText, CountsThePairsWithBoardPosesOnOneLine) {
  FitSummary fit;
  for (int i = 0; i < 40; ++i) {
    fit.strong_correlations.push_back(
        {"cam[0].intrinsics[2] ~ board[0@p" + std::to_string(i) + "/z0].t[0]", -0.9995});
  }
  fit.strong_correlations.push_back({"cam[0].intrinsics[0] ~ cam[0].intrinsics[1]", 0.982});
  fit.strong_correlations.push_back({"cam[0].distortion[1] ~ cam[0].distortion[4]", -0.961});
  const std::string text = StrongCorrelationsText(fit);
  const std::vector<std::string> listed = ListedPairs(text);
  ASSERT_EQ(listed.size(), 2u) << text;
  EXPECT_EQ(listed[0], "  cam[0].intrinsics[0] ~ cam[0].intrinsics[1]  rho = +0.982");
  EXPECT_EQ(listed[1], "  cam[0].distortion[1] ~ cam[0].distortion[4]  rho = -0.961");
  EXPECT_NE(text.find("40 pair(s) with an estimated board pose, |rho| up to 1.000"),
            std::string::npos)
      << text;
  EXPECT_EQ(text.find("board[0@p"), std::string::npos) << text;
}

}  // namespace
}  // namespace rtscalib::app

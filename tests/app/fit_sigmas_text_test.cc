// report.txt's line of a-posteriori sigmas (FitSigmasText): it says when the
// variance-component estimate ran out of rounds with the sigmas still moving
// (FitSummary::sigma_rounds, sigmas_converged; docs/refinement.md), and
// says nothing of it when they settled or were held.
#include <gtest/gtest.h>

#include <string>

#include "app/reports.h"

namespace rtscalib::app {
namespace {

TEST(FitSigmasText, SaysWhenTheVarianceComponentsWereStillMoving) {
  FitSummary f;
  f.sigma_pixel_px = 0.05;
  f.sigma_pixel_px_zoom = {0.05};
  f.sigma_rounds = 4;
  f.sigmas_converged = false;
  EXPECT_NE(FitSigmasText(f, false).find("still moving by more than 5 % after 4 rounds"),
            std::string::npos)
      << FitSigmasText(f, false);
  f.sigmas_converged = true;  // settled
  EXPECT_EQ(FitSigmasText(f, false).find("still moving"), std::string::npos);
  f.sigma_rounds = 0;  // held: nothing estimated
  f.sigmas_converged = false;
  EXPECT_EQ(FitSigmasText(f, false).find("still moving"), std::string::npos);
}

}  // namespace
}  // namespace rtscalib::app

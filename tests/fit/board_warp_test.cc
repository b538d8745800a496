// board_warp (TagBoard::warp, mrcal's calobject_warp) hidden in simulated
// photos of one board at six tilted placements (tests/fit/warped_boards.h)
// and fitted with the boards' poses: in an instrument session (dh, the
// board's pose per placement) and in a camera-only one (SPEC 7.1, a pose
// per photo). The warp is one pair per board, whatever the number of its
// poses; it is recovered within 3 of its own sigmas, and with it the fit
// reaches the noise, which a flat board's model does not.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "libcalib/fit/refine.h"
#include "tests/fit/warped_boards.h"

namespace rtscalib {
namespace {

using namespace testing_scene;

// The model to fit: the truth's effects, the given start, intrinsics a few
// pixels off; with or without board_warp.
FitSummary FitWarpScene(const Observations& obs, InstrumentModel* model, bool warp) {
  for (CameraTool& c : model->cams) {
    c.intrinsics[0] *= 1.01;
    c.intrinsics[1] *= 0.99;
    c.intrinsics[2] += 3;
    c.intrinsics[3] -= 2;
  }
  if (warp) model->effects.Add(Effect::kBoardWarp);
  FitOptions fo;
  fo.fit_intrinsics = true;
  return Refine(obs, fo, model);
}

void ExpectWarpRecovered(const InstrumentModel& m, const char* what) {
  ASSERT_EQ(m.board_warps.size(), 1u) << what << ": one warp for the board, not per pose";
  const BoardWarp& w = m.board_warps[0];
  for (int i = 0; i < 2; ++i) {
    const double sigma = std::sqrt(w.cov[3 * i]);
    std::cout << what << ": w" << "xy"[i] << " = " << w.w[i] * 1e3 << " +- " << sigma * 1e3
              << " mm (truth " << kHiddenWarp[i] * 1e3 << ")\n";
    ASSERT_GT(sigma, 0.0) << what;
    // 3 sigma: a 0.3 % chance per component for a right sigma.
    EXPECT_LT(std::abs(w.w[i] - kHiddenWarp[i]), 3 * sigma) << what << " component " << i;
    // Tilted placements determine it well: a fifth of the warp at most.
    EXPECT_LT(sigma, 0.2 * std::abs(kHiddenWarp[i])) << what << " component " << i;
  }
  // Every pose of the board carries the fitted warp (WithEstimates, model.yaml, predict).
  for (const EstimatedBoard& b : m.boards) {
    EXPECT_EQ(b.board.warp, w.w) << b.Name();
  }
}

TEST(BoardWarp, RecoveredWithTheBoardPosesOfAnInstrumentSession) {
  const WarpedSession s = SimulateWarpedSession(11, kWarpSessionNoisePx, true, kHiddenWarp);
  InstrumentModel flat = PerturbedStart(s.truth, 11, 1e-3);
  InstrumentModel warped = flat;
  const FitSummary without = FitWarpScene(s.obs, &flat, false);
  const FitSummary with = FitWarpScene(s.obs, &warped, true);
  ASSERT_TRUE(with.converged) << with.message;
  ASSERT_TRUE(warped.sigmas.valid) << with.message;
  EXPECT_EQ(warped.boards.size(), 6u);  // one pose per placement
  ExpectWarpRecovered(warped, "instrument");
  std::cout << "pixel sigma: flat board " << without.sigma_pixel_px << " px, with board_warp "
            << with.sigma_pixel_px << " px (noise " << kWarpSessionNoisePx << ")\n";
  // ~5,000 residuals: the estimated sigma is the noise within ~2 %; 10 % is
  // wide of chance. The flat board's model leaves the warp's 0.1-0.3 px.
  EXPECT_NEAR(with.sigma_pixel_px, kWarpSessionNoisePx, 0.1 * kWarpSessionNoisePx);
  EXPECT_GT(without.sigma_pixel_px, 1.5 * kWarpSessionNoisePx);
}

TEST(BoardWarp, RecoveredInACameraOnlySession) {
  const WarpedSession s = SimulateWarpedSession(12, kWarpSessionNoisePx, true, kHiddenWarp);
  const Observations obs = CameraOnly(s.obs);
  CameraTool cam = s.truth.cams[0];
  InstrumentModel model = IdealModel(Kinematics::kNone, 1, cam);
  model.effects = s.truth.effects;
  const FitSummary with = FitWarpScene(obs, &model, true);
  ASSERT_TRUE(with.converged) << with.message;
  ASSERT_TRUE(model.sigmas.valid) << with.message;
  // One pose per photo, one warp for them all.
  EXPECT_GT(model.boards.size(), 20u);
  ExpectWarpRecovered(model, "camera-only");
  EXPECT_NEAR(with.sigma_pixel_px, kWarpSessionNoisePx, 0.1 * kWarpSessionNoisePx);
}

}  // namespace
}  // namespace rtscalib

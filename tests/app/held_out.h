// Corners the calibration never saw, for the rendered sessions of one board
// moved between placements (OneBoardSession, RenderedFocus): every pointing
// of the photos turned by (0.01, 0.005) rad, and there every corner of the
// placement's true board that the truth's camera sees in its image. The
// truth predicts it at the board's true pose, the fitted model at its own
// estimate of that placement's board; with the focus effect both focus at
// the board centre's distance from the camera (ignored without it).
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "libcalib/model/instrument.h"
#include "libcalib/model/kinematics.h"
#include "libcalib/model/observations.h"
#include "libcalib/model/targets.h"

namespace rtscalib::app::testing_held_out {

struct HeldOut {
  double sum_sq = 0;  // sum of |uv_model - uv_true|^2 [px^2]
  int n = 0;          // corners
  double RmsPerCoordinate() const { return n ? std::sqrt(sum_sq / (2.0 * n)) : 0.0; }
};

// Adds the held-out corners of `pixels`' pointings to `out`. `placements`:
// the simulated scenes by placement name (SimulationOptions::placements).
inline void AddHeldOutPlacements(const InstrumentModel& model, const InstrumentModel& truth,
                                 const PlacedScenes& placements,
                                 const std::vector<PixelObservation>& pixels, HeldOut* out) {
  std::set<std::tuple<std::string, int, double, double>> pointings;
  for (const PixelObservation& p : pixels) pointings.insert({p.placement, p.zoom, p.phi, p.theta});
  for (const auto& [placement, zoom, phi0, theta0] : pointings) {
    const double phi = phi0 + 0.01, theta = theta0 + 0.005;
    const TagBoard& tb = placements.at(placement).boards.at(0);
    const EstimatedBoard* eb = model.BoardOf(tb.first_id, placement, zoom);
    ASSERT_NE(eb, nullptr) << "placement " << placement << " not estimated";
    const CameraTool& cam = truth.cams[zoom];
    const double d = (tb.CentreInRef() - RefFromCam(truth, zoom, phi, theta).translation).norm();
    for (int i = 0; i < tb.NumTags(); ++i) {
      for (const Eigen::Vector3d& corner : tb.CornersInBoard(i)) {
        Eigen::Vector2d uv_true, uv_model;
        if (!PredictPixel(truth, zoom, phi, theta, tb.ref_from_board * corner, &uv_true, d) ||
            uv_true.x() < 0 || uv_true.y() < 0 || uv_true.x() > cam.width - 1 ||
            uv_true.y() > cam.height - 1) {
          continue;
        }
        ASSERT_TRUE(PredictPixel(model, zoom, phi, theta, eb->pose.ToRigid() * corner, &uv_model, d));
        out->sum_sq += (uv_model - uv_true).squaredNorm();
        ++out->n;
      }
    }
  }
}

}  // namespace rtscalib::app::testing_held_out

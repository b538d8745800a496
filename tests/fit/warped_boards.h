// A simulated session whose board is not flat (the effect board_warp,
// TagBoard::warp): one AprilTag board of 6 x 8 tags (about 1.2 x 0.9 m) put
// at several placements 3 m from the instrument, the same warp at every one
// (a board bends alike wherever it is put), photographed by libcalib/sim's
// shot plan in both faces. The observations do not say the board is bent:
// its poses are unknown (X_known false), as in a real session.
//
// Tilted: the placements turn the board up to +-35 degrees about both its
// axes (what makes a warp tell from a pose and the lens); head-on: every
// placement faces the instrument, which cannot tell it.
#pragma once

#include <array>
#include <string>

#include "libcalib/model/kinematics.h"
#include "libcalib/sim/simulator.h"
#include "tests/fit/joint_scene.h"

namespace rtscalib::testing_scene {

// The warp the tests hide: 2 mm across, -1 mm along the board, a bow of
// about a board's thickness (mrcal's tour board: -1.04 and +0.52 mm over
// 0.69 m); and the pixel noise, well below the 0.1-0.3 px it moves corners.
constexpr std::array<double, 2> kHiddenWarp = {0.002, -0.001};
constexpr double kWarpSessionNoisePx = 0.05;

struct WarpedSession {
  InstrumentModel truth;
  Observations obs;  // pixels of the board at its placements, poses unknown
  std::array<double, 2> warp{};
};

// A dh truth (one 640 x 480 zoom, f = 800 px, radial distortion) whose base
// frame is the instrument's ideal one (SPEC 7: with nothing known the
// reference frame is the instrument's), so that the boards' poses compare
// with the truth's.
inline InstrumentModel WarpedSessionTruth() {
  InstrumentModel t = DhTruth(1);
  EffectSet radial;
  radial.Add(Effect::kRadialDistortion);
  AddDistortion(radial, &t);
  const InstrumentModel ideal = IdealModel(Kinematics::kDh, 0, CameraTool());
  t.base = ideal.base;
  t.links[0].p[kDhD] = ideal.links[0].p[kDhD];
  t.links[0].p[kDhGamma] = ideal.links[0].p[kDhGamma];
  for (Effect e : t.effects.List()) {
    if (IsKinematic(e)) {
      t.effects.Remove(e);
      t.EffectValue(e) = {0, 0};
    }
  }
  return t;
}

inline WarpedSession SimulateWarpedSession(std::uint64_t seed, double noise_px, bool tilted,
                                           std::array<double, 2> warp) {
  WarpedSession s;
  s.truth = WarpedSessionTruth();
  s.warp = warp;
  SimulationOptions o;
  o.seed = seed;
  o.truth = s.truth;
  o.plan.faces = {1, 2};
  o.plan.zooms = {0};
  o.noise.pixel_px = noise_px;
  o.shots.shots_per_board = 3;
  const Eigen::Vector3d station = RefFromFlange(s.truth, 0.0, M_PI / 2).translation;
  // Placement k: the board in direction phi_k, tilted by (a_k, b_k) about
  // its x and y axes through its centre.
  const double tilt = tilted ? 0.6 : 0.0;
  const double a[6] = {tilt, -tilt, 0.5 * tilt, -0.5 * tilt, tilt, -tilt};
  const double b[6] = {0.5 * tilt, -0.5 * tilt, -tilt, tilt, -tilt, tilt};
  for (int k = 0; k < 6; ++k) {
    TagBoard board = FacingBoard(station, 0, 6, 8, 0.12, 3.0, 0.4 + 0.9 * k, 0.1 * (k % 3) - 0.1,
                                 b[k]);
    const Eigen::Vector3d centre = board.CentreInRef();
    const Eigen::Matrix3d r = board.ref_from_board.rotation * Rx(a[k]);
    board.ref_from_board =
        Rigid3{r, centre - r * Eigen::Vector3d(board.Width() / 2, board.Height() / 2, 0)};
    board.warp = warp;
    o.placements["p" + std::to_string(k)].boards.push_back(board);
  }
  SimulatedData data = Simulate(o);
  s.obs = data.obs;
  s.obs.records.clear();
  // What a user's targets.yaml says: the board, flat, pose unknown.
  TagBoard flat = o.placements.begin()->second.boards[0];
  flat.pose_known = false;
  flat.warp = {0, 0};
  flat.ref_from_board = Rigid3();
  s.obs.targets.boards = {flat};
  for (PixelObservation& p : s.obs.pixels) {
    p.X_known = false;
    p.X.setZero();
  }
  return s;
}

// The same photos as a camera-only session (SPEC 7.1): no readings, and
// each photo its own placement (the board moved between photos as the
// camera saw it).
inline Observations CameraOnly(Observations obs) {
  for (PixelObservation& p : obs.pixels) {
    p.has_reading = false;
    p.phi = 0;
    p.theta = M_PI / 2;
    p.placement = p.shot;
  }
  return obs;
}

}  // namespace rtscalib::testing_scene

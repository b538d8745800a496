// Small simulated scenes for the joint (records + pixels) refinement tests:
// a truth instrument with a few zoom levels and AprilTag boards around the
// station that suit every zoom. Shared by tests/fit/joint_*_test.cc; the
// fits in those tests start from InitFromPixels or the extraction, never from
// this truth.
#pragma once

#include <random>

#include "libcalib/model/kinematics.h"
#include "libcalib/model/targets.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib::testing_scene {

// A board of rows x cols tags whose printed side faces the station: centre
// `distance` metres away in direction `phi` (SPEC 1: clockwise from +y) at
// height `z`, turned by `tilt` about its own vertical axis.
inline TagBoard FacingBoard(int first_id, int rows, int cols, double tag, double distance,
                            double phi, double z, double tilt) {
  TagBoard b;
  b.first_id = first_id;
  b.rows = rows;
  b.cols = cols;
  b.tag_size = tag;
  b.spacing = 0.25 * tag;
  // Board frame: x right, y down, z away from the viewer (targets.h).
  const Eigen::Matrix3d r = Rz(-phi) * Rx(-M_PI / 2) * Ry(tilt);
  const Eigen::Vector3d centre(distance * std::sin(phi), distance * std::cos(phi), z);
  const double w = cols * tag + (cols - 1) * b.spacing, h = rows * tag + (rows - 1) * b.spacing;
  b.ref_from_board = Rigid3{r, centre - r * Eigen::Vector3d(w / 2, h / 2, 0)};
  return b;
}

// Boards for zooms with focal lengths `f0` .. `f0 * 2^(n-1)` px on a
// 640 x 480 image: per zoom one board that fills about half the view with
// 6 x 8 tags, at two directions and tilts, so that OpenCV's per-zoom
// calibration sees non-parallel planes.
inline TargetScene SceneFor(int num_zooms, double f0) {
  TargetScene scene;
  for (int z = 0; z < num_zooms; ++z) {
    const double f = f0 * std::pow(2.0, z);
    const double distance = 3.0;
    const double half_view = distance * 320.0 / f;  // metres at the board
    // 8 columns of tags with spacing 0.25 tag span ~ the view's half width.
    const double tag = half_view / (8 * 1.25);
    scene.boards.push_back(FacingBoard(100 * z, 6, 8, tag, distance, 0.3 + 0.8 * z, -0.2, 0.5));
    scene.boards.push_back(
        FacingBoard(100 * z + 50, 6, 8, tag, distance * 1.3, -0.5 + 0.8 * z, 0.3, -0.6));
  }
  return scene;
}

// A dh truth near Klug's PLT 300 (PaperTruth) with `num_zooms` 640 x 480
// cameras, f = f0 * 2^z, principal points off centre by a few pixels.
inline InstrumentModel DhTruth(int num_zooms, double f0 = 800.0) {
  InstrumentModel m = PaperTruth(num_zooms);
  for (int z = 0; z < num_zooms; ++z) {
    CameraTool& c = m.cams[z];
    c.width = 640;
    c.height = 480;
    const double f = f0 * std::pow(2.0, z);
    c.intrinsics = {f, f * (1 + 3e-4), 320.0 + 4.0 - 1.5 * z, 240.0 - 3.0 + z};
  }
  return m;
}

// Distortion of zoom z for the enabled groups (moderate, well inside the
// trusted region over a 640 x 480 image at f >= 800 px).
inline void AddDistortion(const EffectSet& groups, InstrumentModel* m) {
  for (int z = 0; z < m->NumZooms(); ++z) {
    auto& d = m->cams[z].distortion;
    const double s = 1.0 / (1 + z);
    if (groups.Has(Effect::kRadialDistortion)) {
      d[camera::kK1] = -0.12 * s;
      d[camera::kK2] = 0.08 * s;
      d[camera::kK3] = -0.02 * s;
    }
    if (groups.Has(Effect::kTangentialDistortion)) {
      d[camera::kP1] = 8e-4;
      d[camera::kP2] = -5e-4;
    }
    if (groups.Has(Effect::kRationalDistortion)) {
      d[camera::kK4] = 0.05 * s;
      d[camera::kK5] = -0.02 * s;
      d[camera::kK6] = 0.01 * s;
    }
    if (groups.Has(Effect::kThinPrism)) {
      d[camera::kS1] = 6e-4;
      d[camera::kS2] = -2e-4;
      d[camera::kS3] = -4e-4;
      d[camera::kS4] = 1e-4;
    }
    if (groups.Has(Effect::kSensorTilt)) {
      d[camera::kTauX] = 2e-3;
      d[camera::kTauY] = -1.5e-3;
    }
  }
  for (Effect e : groups.List()) {
    if (IsDistortion(e)) m->effects.Add(e);
  }
}

// Simulation options: pixels only (no records), both faces.
inline SimulationOptions PixelsOnly(const InstrumentModel& truth, int shots_per_board,
                                    std::uint64_t seed, double pixel_noise) {
  SimulationOptions o;
  o.seed = seed;
  o.truth = truth;
  o.targets = SceneFor(truth.NumZooms(), truth.cams[0].intrinsics[0]);
  o.shots.shots_per_board = shots_per_board;
  o.plan.faces = {1, 2};
  o.plan.zooms.clear();
  for (int z = 0; z < truth.NumZooms(); ++z) o.plan.zooms.push_back(z);
  o.noise.pixel_px = pixel_noise;
  return o;
}

}  // namespace rtscalib::testing_scene

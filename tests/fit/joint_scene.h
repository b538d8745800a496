// Small simulated scenes for the joint (records + pixels) refinement tests:
// a truth instrument with a few zoom levels and AprilTag boards around the
// station that suit every zoom. Shared by tests/fit/joint_*_test.cc; the
// fits in those tests start from InitFromPixels or the extraction, never from
// this truth.
#pragma once

#include <random>

#include "libcalib/fit/init_from_pixels.h"
#include "libcalib/model/kinematics.h"
#include "libcalib/model/targets.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib::testing_scene {

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
      d[kK1] = -0.12 * s;
      d[kK2] = 0.08 * s;
      d[kK3] = -0.02 * s;
    }
    if (groups.Has(Effect::kTangentialDistortion)) {
      d[kP1] = 8e-4;
      d[kP2] = -5e-4;
    }
    if (groups.Has(Effect::kRationalDistortion)) {
      d[kK4] = 0.05 * s;
      d[kK5] = -0.02 * s;
      d[kK6] = 0.01 * s;
    }
    if (groups.Has(Effect::kThinPrism)) {
      d[kS1] = 6e-4;
      d[kS2] = -2e-4;
      d[kS3] = -4e-4;
      d[kS4] = 1e-4;
    }
    if (groups.Has(Effect::kSensorTilt)) {
      d[kTauX] = 2e-3;
      d[kTauY] = -1.5e-3;
    }
  }
  for (Effect e : groups.List()) {
    if (IsDistortion(e)) m->effects.Add(e);
  }
}

// Starting from the pixels alone (InitFromPixels) with a DH chain, every
// zoom of `truth` at its image size.
inline InitFromPixelsOptions DhFromPixels(const InstrumentModel& truth) {
  InitFromPixelsOptions io;
  io.kinematics = Kinematics::kDh;
  io.cameras.resize(truth.NumZooms());
  for (int z = 0; z < truth.NumZooms(); ++z) {
    io.cameras[z].width = truth.cams[z].width;
    io.cameras[z].height = truth.cams[z].height;
  }
  return io;
}

// Simulation options: pixels only (no records), both faces.
inline SimulationOptions PixelsOnly(const InstrumentModel& truth, int shots_per_board,
                                    std::uint64_t seed, double pixel_noise) {
  SimulationOptions o;
  o.seed = seed;
  o.truth = truth;
  o.targets = ZoomScene(truth, 6, 8, 3.0);
  o.shots.shots_per_board = shots_per_board;
  o.plan.faces = {1, 2};
  o.plan.zooms.clear();
  for (int z = 0; z < truth.NumZooms(); ++z) o.plan.zooms.push_back(z);
  o.noise.pixel_px = pixel_noise;
  return o;
}

}  // namespace rtscalib::testing_scene

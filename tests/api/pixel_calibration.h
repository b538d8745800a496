// The API tests' calibrations: a DH instrument with radial and tangential
// distortion (tests/fit/joint_scene.h) fitted from pixels alone, ~2,000
// corners of one seed (2 boards x 3 shots x 2 faces), started from the
// pixels (InitFromPixels) as a user without records would.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "libcalib/fit/init_from_pixels.h"
#include "libcalib/fit/refine.h"
#include "libcalib/sim/simulator.h"
#include "tests/fit/joint_scene.h"

namespace rtscalib::testing_api {

// A fresh folder under the build's test_tmp/<group>/<name>.
inline std::filesystem::path TestDir(const std::string& group, const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::path(RTSCALIB_BINARY_DIR) / "test_tmp" / group / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline InstrumentModel DistortedTruth() {
  EffectSet groups;
  groups.Add(Effect::kRadialDistortion);
  groups.Add(Effect::kTangentialDistortion);
  InstrumentModel truth = testing_scene::DhTruth(1);
  testing_scene::AddDistortion(groups, &truth);
  return truth;
}

// The calibration from the pixels of simulation seed `seed` with `noise_px`;
// `obs_out`, when given, receives the observations.
inline InstrumentModel FitFromPixels(const InstrumentModel& truth, int seed, double noise_px,
                                     Observations* obs_out = nullptr) {
  SimulatedData data = Simulate(testing_scene::PixelsOnly(truth, 3, seed, noise_px));
  data.obs.records.clear();
  InitFromPixelsOptions io;
  io.kinematics = Kinematics::kDh;
  io.distortion.tangential = true;
  io.cameras.resize(1);
  io.cameras[0].width = truth.cams[0].width;
  io.cameras[0].height = truth.cams[0].height;
  InstrumentModel model = InitFromPixels(data.obs.pixels, io).model;
  for (Effect e : truth.effects.List()) model.effects.Add(e);
  FitOptions fo;
  fo.fit_intrinsics = true;
  const FitSummary s = Refine(data.obs, fo, &model);
  EXPECT_TRUE(model.sigmas.valid) << s.message;
  if (obs_out) *obs_out = data.obs;
  return model;
}

}  // namespace rtscalib::testing_api

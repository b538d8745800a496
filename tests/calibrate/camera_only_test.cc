// Camera-only calibrations (model.kinematics: none, SPEC 7.1) and what the
// configured kinematics need from the data, through Calibrate: synthetic
// photos of a chessboard held at many poses (one placement per photo, no
// readings), projected with a known camera, noise added, calibrated and
// compared with the truth; then the sessions that cannot give what the
// config asks for, each refused with the key or the row that says why.
#include "libcalib/calibrate/calibrate.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include "libcalib/text/errors.h"
#include "libcalib/model/kinematics.h"
#include "tests/calibrate/camera_only_session.h"

namespace rtscalib {
namespace {

using ::testing::HasSubstr;

using testing_camera_only::CameraOnlySession;
using testing_camera_only::TrueCamera;

CalibrationOptions CameraOnlyOptions() {
  CalibrationOptions o;
  o.model.kinematics = Kinematics::kNone;
  o.model.effects.Add(Effect::kRadialDistortion);
  o.model.effects.Add(Effect::kTangentialDistortion);
  o.model.intrinsics = IntrinsicsMode::kFit;
  o.fit.sigma_pixel_px = 0.2;
  o.diagnose.enabled = false;
  return o;
}

// Over ten seeds (0.2 px noise, 15 photos each) the normalised errors
// (fit - truth) / sigma of fx, fy, cx, cy, k1, k2, p1, p2 have a mean square
// in [0.5, 2] (1 when the sigmas hold; 80 values, correlated in pairs: the
// mean square's standard deviation is ~0.2).
TEST(CameraOnly, RecoversTheCameraWithHonestSigmas) {
  const CameraTool cam = TrueCamera();
  double sum_sq = 0;
  int n = 0;
  for (unsigned seed = 1; seed <= 10; ++seed) {
    const Observations obs = CameraOnlySession(cam, 15, 0.2, seed);
    const CalibrationResult r = Calibrate(obs, CameraOnlyOptions());
    const InstrumentModel& m = r.model;
    ASSERT_EQ(m.kinematics, Kinematics::kNone);
    ASSERT_TRUE(m.sigmas.valid);
    EXPECT_EQ(m.boards.size(), 15u);  // one pose per placement
    // No chain was estimated: base and tool stay the identity.
    EXPECT_EQ(m.cams[0].flange_from_cam.t, (std::array<double, 3>{0, 0, 0}));
    EXPECT_EQ(m.base.q, (std::array<double, 4>{0, 0, 0, 1}));
    for (int i = 0; i < 4; ++i) {
      const double e = (m.cams[0].intrinsics[i] - cam.intrinsics[i]) / m.sigmas.intrinsics[0][i];
      sum_sq += e * e;
      ++n;
    }
    for (int k : {kK1, kK2, kP1, kP2}) {
      const double e = (m.cams[0].distortion[k] - cam.distortion[k]) / m.sigmas.distortion[0][k];
      sum_sq += e * e;
      ++n;
    }
    // The reprojection RMS is the noise's (2 coordinates of 0.2 px: 0.28 px)
    // less what the ~150 parameters absorb of ~1,500 observations.
    EXPECT_NEAR(r.final_errors.pixels.rms_px, 0.2 * std::sqrt(2.0), 0.05);
  }
  const double ms = sum_sq / n;
  std::printf("camera-only, 10 seeds: mean square normalised error %.3f over %d values\n", ms, n);
  EXPECT_GT(ms, 0.5);
  EXPECT_LT(ms, 2.0);
}

TEST(CameraOnly, RefusesWhatACameraAloneCannotUse) {
  const Observations good = CameraOnlySession(TrueCamera(), 6, 0.2, 7);
  {
    Observations obs = good;
    Record r;
    r.line = 4;
    obs.records.push_back(r);
    try {
      Calibrate(obs, CameraOnlyOptions());
      FAIL() << "records accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_THAT(e.what(), HasSubstr("model.kinematics: none"));
      EXPECT_THAT(e.what(), HasSubstr("records"));
    }
  }
  {
    CalibrationOptions o = CameraOnlyOptions();
    o.model.effects.Add(Effect::kHzEccentricity);
    try {
      Calibrate(good, o);
      FAIL() << "a kinematic effect accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_THAT(e.what(), HasSubstr("model.effects: hz_eccentricity"));
    }
  }
  {
    // A camera that turned within one placement (readings differ).
    Observations obs = good;
    for (PixelObservation& p : obs.pixels) {
      p.has_reading = true;
      p.placement = "one";
      p.phi = p.shot == "photo3" ? 0.2 : 0.1;
    }
    try {
      Calibrate(obs, CameraOnlyOptions());
      FAIL() << "a turned camera accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file, "photos.csv");
      EXPECT_EQ(e.line, 5);  // photo3's line
      EXPECT_EQ(e.column, "phi");
      EXPECT_THAT(e.expected, HasSubstr("must not turn within a placement"));
    }
  }
  {
    // A surveyed position means nothing in a camera frame.
    Observations obs = good;
    obs.pixels[3].X_known = true;
    try {
      Calibrate(obs, CameraOnlyOptions());
      FAIL() << "a known X accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.line, obs.pixels[3].line);
      EXPECT_EQ(e.column, "X");
    }
  }
}

// The configured kinematics need readings, and pixels alone determine a
// chain only when some placement is seen from two readings: a session of
// photos each with its own board pose (a bench camera's) asks for
// model.kinematics: none, by name.
TEST(CameraOnly, KinematicsTheDataCannotDetermineAreRefusedByName) {
  Observations obs = CameraOnlySession(TrueCamera(), 6, 0.2, 9);
  CalibrationOptions o = CameraOnlyOptions();
  o.model.kinematics = Kinematics::kDh;
  try {
    Calibrate(obs, o);
    FAIL() << "rows without readings accepted by dh";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line, obs.pixels[0].line);
    EXPECT_EQ(e.column, "phi");
    EXPECT_THAT(e.expected, HasSubstr("model.kinematics: none"));
  }
  // With readings, but each placement seen from one reading only.
  for (PixelObservation& p : obs.pixels) {
    p.has_reading = true;
    p.phi = 0.1 * p.line;
  }
  try {
    Calibrate(obs, o);
    FAIL() << "undetermined kinematics accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("model.kinematics: dh cannot be determined"));
    EXPECT_THAT(e.what(), HasSubstr("model.kinematics: none"));
  }
}

}  // namespace
}  // namespace rtscalib

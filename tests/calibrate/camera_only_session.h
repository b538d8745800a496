// A camera on a bench (SPEC 7.1, model.kinematics: none) in synthetic
// photos: a chessboard held at many poses in front of a known camera, one
// placement per photo, no readings, noise added. Shared by the tests of the
// calibration (tests/calibrate/camera_only_test.cc) and of its diagnosis
// (tests/diagnose/camera_only_test.cc).
#pragma once

#include <cmath>
#include <random>
#include <string>

#include "libcalib/geometry/rotation.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/kinematics.h"
#include "libcalib/model/observations.h"

namespace rtscalib::testing_camera_only {

// OpenCV's sample board: 10 x 7 squares of 25 mm, 9 x 6 inner corners.
inline TagBoard Chessboard() {
  TagBoard b;
  b.kind = BoardKind::kChessboard;
  b.family = "chessboard";
  b.rows = 7;
  b.cols = 10;
  b.square_size = 0.025;
  b.pose_known = false;
  return b;
}

inline CameraTool TrueCamera() {
  CameraTool c;
  c.width = 640;
  c.height = 480;
  c.intrinsics = {530.0, 531.5, 322.0, 238.5};
  c.distortion[kK1] = -0.28;
  c.distortion[kK2] = 0.09;
  c.distortion[kP1] = 1.2e-3;
  c.distortion[kP2] = -4e-4;
  return c;
}

// `photos` photos of the board held in front of the camera: 0.25-0.45 m
// away, turned up to 35 degrees out of the image plane and any angle in it,
// shifted so that the corners reach every part of the image. Each photo is
// its own placement; readings empty (has_reading false); pixel noise
// `noise_px` per coordinate. Corners outside the image are not seen.
// `spread` scales the sideways shifts (0.12 m, 0.09 m): a wide lens needs
// more for the boards to reach its image corners.
inline Observations CameraOnlySession(const CameraTool& cam, int photos, double noise_px,
                                      unsigned seed, double spread = 1.0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> n(0.0, 1.0);
  Observations obs;
  obs.targets.boards = {Chessboard()};
  const TagBoard& b = obs.targets.boards[0];
  obs.image_sizes[0] = ImageSize{cam.width, cam.height};
  obs.pixels_source = "photos.csv";
  InstrumentModel truth = IdealModel(Kinematics::kNone, 1, cam);
  for (int k = 0; k < photos; ++k) {
    const double z = 0.35 + 0.1 * u(rng);
    const Eigen::Matrix3d r = Rz(M_PI * u(rng)) * Rx(0.6 * u(rng)) * Ry(0.6 * u(rng));
    const Eigen::Vector3d centre(spread * 0.12 * u(rng), spread * 0.09 * u(rng), z);
    const Rigid3 cam_from_board{r, centre - r * Eigen::Vector3d(b.Width() / 2, b.Height() / 2, 0)};
    for (int i = 0; i < b.NumTags(); ++i) {
      Eigen::Vector2d uv;
      if (!PredictPixel(truth, 0, 0, 0, cam_from_board * b.CornersInBoard(i)[0], &uv)) continue;
      if (uv.x() < 0 || uv.y() < 0 || uv.x() > cam.width - 1 || uv.y() > cam.height - 1) continue;
      PixelObservation p;
      p.has_reading = false;
      p.theta = M_PI / 2;
      p.shot = "photo" + std::to_string(k);
      p.placement = "p" + std::to_string(k);
      p.target = i;
      p.corner = 0;
      p.X_known = false;
      p.uv = uv + noise_px * Eigen::Vector2d(n(rng), n(rng));
      p.line = k + 2;
      obs.pixels.push_back(p);
    }
  }
  return obs;
}

}  // namespace rtscalib::testing_camera_only

// Shared fixture of the render tests: a board 2 m in front of a camera whose
// pose is known exactly, and a display for VTK.
//
// Reference frame = the camera frame of the "home" pose: x right, y down,
// z forward (SPEC 2). The board's printed side faces the camera.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <cstdlib>
#include <memory>

#include "libcalib/geometry/rotation.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/targets.h"
#include "render/headless.h"

namespace rtscalib::render::testing {

// One display per test process (an Xvfb when DISPLAY is unset), created on
// first use and kept until exit, after every renderer.
inline void EnsureDisplay() {
  static std::unique_ptr<HeadlessDisplay> display = std::make_unique<HeadlessDisplay>();
}

// rows x cols tags of tag36h11 (8 cm, 2 cm apart), centred on the optical
// axis of the home pose at `distance` metres.
inline TagBoard FrontBoard(int rows = 3, int cols = 4, double distance = 2.0) {
  TagBoard b;
  b.rows = rows;
  b.cols = cols;
  const double w = cols * b.tag_size + (cols - 1) * b.spacing;
  const double h = rows * b.tag_size + (rows - 1) * b.spacing;
  b.ref_from_board.translation = Eigen::Vector3d(-w / 2, -h / 2, distance);
  return b;
}

inline TargetScene SceneOf(const TagBoard& board) {
  TargetScene s;
  s.boards.push_back(board);
  return s;
}

// 1280 x 960, fx = fy = 1000; a principal point off the pixel grid so that no
// edge falls on a pixel boundary by accident. Optionally the distortion of the
// accuracy requirement: k1 = -0.1, k2 = 0.05, p1 = 1e-4.
inline CameraTool TestCamera(bool distorted) {
  CameraTool cam;
  cam.width = 1280;
  cam.height = 960;
  cam.intrinsics = {1000.0, 1000.0, 640.3, 479.6};
  if (distorted) {
    cam.distortion[kK1] = -0.1;
    cam.distortion[kK2] = 0.05;
    cam.distortion[kP1] = 1e-4;
  }
  return cam;
}

// A camera at `centre` turned so that reference point `target` is seen at
// pixel (u, v) of `cam` (distortion ignored for the aim), rolled by `roll`
// radians about that line of sight.
inline Rigid3 AimAt(const Eigen::Vector3d& centre, const Eigen::Vector3d& target, double u,
                    double v, double roll, const CameraTool& cam) {
  const Eigen::Vector3d ray_cam = Eigen::Vector3d((u - cam.intrinsics[2]) / cam.intrinsics[0],
                                                  (v - cam.intrinsics[3]) / cam.intrinsics[1], 1.0)
                                      .normalized();
  const Eigen::Vector3d ray_ref = (target - centre).normalized();
  const Eigen::Matrix3d turn =
      Eigen::Quaterniond::FromTwoVectors(ray_cam, ray_ref).toRotationMatrix();
  Rigid3 pose;
  pose.rotation = Eigen::AngleAxisd(roll, ray_ref).toRotationMatrix() * turn;
  pose.translation = centre;
  return pose;
}

}  // namespace rtscalib::render::testing

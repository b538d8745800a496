// Camera calibration from pixels alone, for one zoom level: the starting
// point for the joint refinement (init_from_pixels.h, refine.h), which later
// ties each shot's camera pose to the instrument's kinematics.
//
// Input: PixelObservations (SPEC 3, pixels.csv) of known 3D points in the
// reference frame, grouped by `shot` (one image each), and the image size.
// Output: intrinsics fx fy cx cy [px], the 14 OpenCV distortion coefficients
// (only the enabled groups non-zero; opencv_model.h has the formula and order),
// each shot's pose ref_from_cam (camera frame of SPEC 2, metres), and the
// reprojection RMS sqrt(mean(du^2 + dv^2)) [px] (SPEC 6's rms_px).
//
// Method (docs/camera.md):
//   1. Each shot's points are split into planar subsets (the boards; a plane
//      through each target's corners, grown to every point within
//      `plane_tolerance_m`, largest first). The scene across boards is
//      generally not planar, which OpenCV's calibrateCamera cannot start from.
//   2. cv::initCameraMatrix2D on the planar subsets (each in its own plane
//      frame, z = 0; at most 12, evenly spaced over the shots) gives fx, fy;
//      then cv::calibrateCamera on the same subsets
//      with CALIB_USE_INTRINSIC_GUESS estimates intrinsics and the enabled
//      distortion groups; the same with radial k1 k2 only, without
//      distortion, and initCameraMatrix2D alone are the fallbacks.
//   3. cv::solvePnP (SQPnP, then iterative) on all of a shot's points gives
//      the shot's pose for each of those starts (the first two always, the
//      others while none poses every shot within 1 px RMS); of the starts
//      tried, the one that poses the most shots, then with the lowest RMS,
//      is kept.
//   4. Ceres's Levenberg-Marquardt refines intrinsics, the enabled
//      distortion groups and every shot's pose in double precision, with
//      autodiff through the project's own ProjectToPixel (each shot's
//      rotation a unit quaternion on its manifold, the disabled coefficients
//      held at zero by a subset manifold); dense Schur solves, finished by
//      dense QR ones with the nearly redundant rational group. OpenCV works in float
//      object/image points, which limits it to ~1e-5 px; the result here is
//      consistent with opencv_model.h to rounding.
//
// Why its own Ceres problem beside the shared Parameterization
// (parameterization.h) and residuals (cost_functions.h) of every other fit:
// the unknowns here are one free camera pose per shot (cam_from_ref) over
// points known in the reference frame, and no instrument. The
// Parameterization decides the blocks of an InstrumentModel, in which a
// shot's camera pose is no block of its own but a function of the chain at
// the shot's readings (ShotResidual: RefFromFlange(phi, theta) times the
// zoom's camera tool); its camera-only form (Kinematics::kNone) frees a
// pose per board and placement, for corners of a TagBoard in the board's
// frame, not a pose per shot for any known points. This fit gives the chain
// its start (init_from_pixels.h), so it cannot run through that chain. What
// it shares is the camera: the residual projects with opencv_model.h's
// formula and the blocks' manifolds are fit/manifolds.h's. Its solver is
// its own because the problem is one camera and many independent poses
// (dense Schur over the camera block, a dense QR finish for the nearly
// redundant rational group, an absolute RMS tolerance: step 4 above).
//
// Valid input: all observations of one zoom level; every shot one image (the
// same face, zoom, phi, theta on each row). Shots with fewer than
// `min_points_per_shot` points are excluded and listed in `excluded` (never
// silently). Too few usable shots or points throws std::invalid_argument with
// a message naming what is missing; a failed initialisation throws
// std::runtime_error.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "libcalib/camera/opencv_model.h"
#include "libcalib/geometry/rotation.h"
#include "libcalib/model/observations.h"

namespace rtscalib {

// Which OpenCV distortion groups are estimated (SPEC 4 names); the others are
// held at zero.
struct DistortionGroups {
  bool radial = true;        // radial_distortion: k1 k2 k3
  bool tangential = false;   // tangential_distortion: p1 p2
  bool rational = false;     // rational_distortion: k4 k5 k6
  bool thin_prism = false;   // thin_prism: s1 s2 s3 s4
  bool sensor_tilt = false;  // sensor_tilt: taux tauy

  // Indices (DistortionIndex) of the free coefficients, ascending.
  std::vector<int> FreeCoefficients() const;
  std::string Names() const;  // e.g. "radial+tangential", "none"
};

struct CalibrateViewsOptions {
  DistortionGroups distortion;
  int min_shots = 2;                // usable shots needed (>= 1)
  int min_points_per_shot = 4;      // fewer: the shot is excluded (>= 4)
  int min_points_per_plane = 8;     // planar subsets used by OpenCV's initialisation (>= 4)
  double plane_tolerance_m = 1e-3;  // distance within which points count as coplanar [m]
  int max_iterations = 100;         // Levenberg-Marquardt steps of step 4 (accepted or not)
  // Step 4 has converged when an iteration improves the RMS by less than this
  // [px] (far below any detector's noise; exact data reach ~1e-13 px).
  double rms_tolerance_px = 1e-10;
  // Threads for step 2: OpenCV's starts are made two at a time with 2 or more
  // (the same starts, the same choice).
  int threads = 1;
  // Empty if valid, otherwise what is wrong.
  std::string Check() const;
};

struct ShotPose {
  std::string shot;
  int face = 1;
  double phi = 0, theta = 0;  // the shot's readings [rad]
  Rigid3 ref_from_cam;
  int num_points = 0;
  double rms_px = 0;  // this shot's reprojection RMS
};

struct ExcludedShot {
  std::string shot;
  int num_points = 0;
  std::string reason;
};

struct ViewsCalibration {
  int zoom = 0;
  int width = 0, height = 0;
  std::array<double, kNumIntrinsics> intrinsics{};  // fx fy cx cy [px]
  std::array<double, kNumDistortion> distortion{};  // OpenCV order
  std::vector<ShotPose> shots;                      // usable shots, in order of first appearance
  std::vector<ExcludedShot> excluded;               // shots left out, with the reason
  int num_points = 0;                               // observations used
  double rms_px = 0;                                // sqrt(mean(du^2 + dv^2)) over the used points
  double opencv_rms_px = 0;                         // the same after step 3 (OpenCV's estimate)
  std::string init_note;   // how step 2 went (e.g. the radial-only fallback)
  int iterations = 0;      // of step 4
  bool converged = false;  // step 4 met its tolerance within max_iterations
  // MaxTrustedRadius of the result and how many used points lie beyond it
  // (their pixels cannot be back-projected; > 0 means the distortion model
  // folds inside the data and should be questioned).
  double max_trusted_radius = 0;
  int points_beyond_trusted_radius = 0;
};

ViewsCalibration CalibrateViews(const std::vector<PixelObservation>& pixels, int width, int height,
                                const CalibrateViewsOptions& options = {});

}  // namespace rtscalib

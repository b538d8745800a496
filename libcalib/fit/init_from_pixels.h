// Starting models from image observations alone, initialisation without the
// truth: nothing here reads a simulator or a truth.
//
// Pixels only (no records.csv):
//   1. per zoom level, intrinsics, the enabled distortion groups and every
//      shot's pose ref_from_cam from OpenCV (calibrate_views.h: an OpenCV start refined with
//      Ceres);
//   2. the chain: a `spherical` model (SPEC 4 without effects)
//        ref_from_cam(phi, theta) = B * A(phi, theta) * C_z,
//        A(phi, theta) = Rz(-phi) Rx(-theta)                       (SPEC 1, Klug Eq. 90)
//      fitted in closed form to the shot poses:
//        C_z rotation: relative rotations of shot pairs of one zoom satisfy
//          log(R_i^T R_j) = C_z^T log(A_i^T A_j)   (rotation vectors; Park-Martin
//          hand-eye), solved as orthogonal Procrustes (Kabsch, Klug Eq. 51-57);
//        B rotation: chordal mean of R_i C_z^T A_i^T over all shots;
//        translations: linear least squares in t_B and every t_Cz of
//          t_i = t_B + R_B A_i t_Cz;
//   3. `dh` when asked: the dh model with the same predictions (DhFromSpherical).
// The EDM tool is not observed by pixels; it is left ideal (the refinement
// does not see it either).
//
// Boards of unknown pose (SPEC 7; pixels with X_known == false, boards in
// `targets`): step 1 sees each (shot, board) as one view of a planar target
// in its board frame (TagBoard::CornersInBoard): classic camera calibration,
// giving board_from_cam per view. Each board is its own frame in step 2:
//   board_from_cam_i = B_b * A(phi_i, theta_i) * C_z
// (hand-eye pairs only within one frame; B_b per frame by chordal mean;
// translations jointly in every t_Bb and t_Cz). The reference frame is that
// of the known points when there are any (its B is the base), else the
// instrument's ideal base frame (B = identity, SPEC 7); each board's pose is
// ref_from_board = base * B_b^-1, stored in model.boards.
//
// Records and pixels, a zoom with pixels but no camera rows:
// InitCameraFromPixels adds that zoom's camera to an extracted model: step 1,
// then the camera tool = mean over shots of ref_from_flange(phi, theta)^-1 *
// ref_from_cam (rotation chordal mean, translation mean).
#pragma once

#include <string>
#include <vector>

#include "libcalib/fit/calibrate_views.h"
#include "libcalib/model/critical_region.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"

namespace rtscalib {

struct InitFromPixelsOptions {
  Kinematics kinematics = Kinematics::kDh;
  // Distortion groups estimated per zoom (from model.effects); the others 0.
  DistortionGroups distortion;
  // Image sizes (and nothing else) per zoom from the config's model.cameras;
  // a zoom without an entry gets the size from its pixels' extent (a note says so).
  std::vector<CameraTool> cameras;
  // The boards the pixels with X_known == false are corners of (SPEC 7).
  TargetScene targets;
  // The pixels' file (Observations::pixels_source), for messages that name a line.
  std::string source = "pixels";
  // Observations in the critical regions are not used (Calibrate passes
  // FitOptions::critical_region).
  CriticalRegion critical_region;
  int threads = 1;  // CalibrateViewsOptions::threads
  std::string Check() const;
};

struct InitFromPixelsResult {
  InstrumentModel model;  // no effects enabled; the caller adds them
  // Per zoom (index = zoom); zooms without pixels have zoom = -1.
  std::vector<ViewsCalibration> views;
  // How far the shot poses are from the fitted chain: RMS rotation [rad] and
  // RMS position [m] over the shots (OpenCV's pose noise plus model error).
  double chain_rms_rad = 0, chain_rms_m = 0;
  std::vector<std::string> notes;
};

// Throws std::invalid_argument when the pixels cannot define a model (no
// usable shots, fewer than two shots of some zoom...).
InitFromPixelsResult InitFromPixels(const std::vector<PixelObservation>& pixels,
                                    const InitFromPixelsOptions& options);

// The `dh` model whose predictions equal a `spherical` model without
// effects (IdealModel's dh form, instrument.cc):
//   base_dh = B * Rx(pi),  link 1 = {0, -pi/2, pi/2, 0},  link 2 = 0,
//   tool_dh = M_T * tool,  M_T = Rz(pi) Ry(pi/2) Rx(-pi/2),
// so that base_dh * Z1 X1 Z2 X2 * M_T = B * Rz(-phi) Rx(-theta).
// Throws std::invalid_argument if `spherical` has kinematic effects enabled.
InstrumentModel DhFromSpherical(const InstrumentModel& spherical);

// Sets zoom `zoom`'s camera of `model` (extending model->cams if needed)
// from that zoom's pixels, given the rest of the chain (see above). Returns
// notes for the run log. Throws std::invalid_argument naming the line when
// the zoom's pixels show a board of unknown pose (SPEC 7: not started here).
std::vector<std::string> InitCameraFromPixels(const std::vector<PixelObservation>& pixels, int zoom,
                                              const InitFromPixelsOptions& options,
                                              InstrumentModel* model);

// Distortion groups enabled in an effect set.
DistortionGroups DistortionGroupsOf(const EffectSet& effects);

}  // namespace rtscalib

// Geometric extraction of a DH instrument model from device-API records
// (Klug et al. Sec. 3; docs/extraction.md has the whole walk-through).
//
//   1. sweeps (sweeps.h): face-1 rows outside the critical zenith region,
//      joint-1 sweep = constant theta, joint-2 sweep = constant phi, EDM rows
//      at the smallest distance (camera principal-point rows without EDM);
//   2. joint features (joint_features.h): plane + circle fits, Eq. 13-32;
//      both joints must be revolute;
//   3. frames (dh_frames.h): frame 1 on axis 1 (Eq. 43-45), frame 2 on axis 2
//      as recorded in the joint-2 sweep (Eq. 46-48), frame 3 = frame 2 (Eq. 50);
//   4. DH parameters (Eq. 49 with a_i along x_{i+1}):
//        link 1 = {d_1, gamma_1 - phi_2, alpha_1, a_1}, phi_2 = the phi of the
//                 joint-2 sweep (frame 2 is where link 1 is at that reading);
//        link 2 = {0, 0, 0, 0} (frame 3 = frame 2; the tools carry the rest);
//   5. base (Eq. 58-61), camera tool per zoom (Eq. 62-73), EDM tool (Eq. 74-82)
//      (tools.h).
// The result has kinematics = dh and no effects; for records of an instrument
// without effects it reproduces every EDM point exactly and every camera
// point exactly with ExtractOptions::exact_camera_rays (see tools.h for the
// paper's approximation).
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "libcalib/extract/dh_frames.h"
#include "libcalib/extract/joint_features.h"
#include "libcalib/extract/options.h"
#include "libcalib/extract/sweeps.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"

namespace rtscalib {

struct ExtractionResult {
  InstrumentModel model;               // kinematics = dh
  std::array<JointFeature, 2> joints;  // joint 1 (phi), joint 2 (theta)
  // Frames 1..3 (index 0..2) in the reference frame, at the configuration of
  // the joint-2 sweep (phi = sweeps[1].constant_control); frame 3 = frame 2.
  std::array<LinkFrame, 3> frames;
  std::array<Sweep, 2> sweeps;  // the sweeps the joints were fitted to
  std::vector<Sweep> candidate_sweeps;
  ExcludedRows excluded;
  int usable_rows = 0;
  std::vector<std::optional<PrincipalPoint>> principal_points;  // per zoom
  std::vector<int> camera_poses;   // per zoom: poses used for the camera tool (0 = none)
  int edm_poses = 0;               // poses used for the EDM tool
  std::vector<std::string> notes;  // human-readable account of every step
};

// Throws std::invalid_argument when options.Check() fails and ExtractionError
// when the records cannot give a model (messages name the sweep and remedy).
// `cameras` are the configured cameras per zoom (intrinsics, distortion, image
// size; their flange_from_cam is ignored); may be empty.
ExtractionResult ExtractDhModel(const std::vector<Record>& records,
                                const std::vector<CameraTool>& cameras,
                                const ExtractOptions& options = ExtractOptions());

}  // namespace rtscalib

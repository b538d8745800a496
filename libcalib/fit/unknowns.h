// Starting values of the boards of unknown pose and the points of unknown
// position (SPEC 7), from the observations and a start model, without any
// truth:
//   board: per shot that sees at least one of its tags, cam_from_board from
//     cv::solvePnP (IPPE, planar) on its corners in the board frame
//     (TagBoard::CornersInBoard) with the zoom's start intrinsics and
//     distortion; ref_from_board = ref_from_cam(phi, theta) * cam_from_board
//     with the start model's chain (Klug Eq. 9); averaged over shots
//     (rotation: chordal mean, the nearest rotation to the summed matrices;
//     translation: mean);
//   point: mean over its records of the start model's F_EDM / F_CAM (Klug
//     Eq. 11/12), e.g. the ideal EDM point d * [sin phi sin theta,
//     cos phi sin theta, cos theta] for the ideal instrument (SPEC 1).
#pragma once

#include <string>
#include <vector>

#include "libcalib/fit/parameterization.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"

namespace rtscalib {

// Makes the model hold every board of obs.targets without a pose that a
// used pixel sees, and every point a used record names, with the starting
// values above; boards and points the model already holds keep their values.
// With the effect board_warp, every board gets a warp (zero; one it already
// has is kept: SyncBoardWarps).
// When `facts` say no position is known, first re-expresses the start in the
// instrument's ideal base frame (SPEC 7; ToIdealBaseFrame,
// libcalib/model/gauge.h: base and, dh, link 1's held d and gamma_offset
// at their ideal values), so that the starts are expressed in it. Returns notes for the run log. Throws
// std::invalid_argument naming the file and line for a pixel whose target is
// on no board, and for a board no shot sees with a usable pose.
std::vector<std::string> StartUnknowns(const Observations& obs, const UsedRows& rows,
                                       const DataFacts& facts, InstrumentModel* model);

// A copy of `obs` whose pixels of the model's estimated boards carry their
// corner's position (ref_from_board * corner_in_board, warped by the
// board's board_warp) as a known X, and
// whose records of the model's estimated points carry the point as a known x
// (`point` cleared): for evaluations that need positions (errors, checks of
// a start or a fit, the diagnosis's residuals), which then see the boards
// and points fixed at the model's estimate. Rows of boards or points the
// model does not hold stay as they are.
Observations WithEstimates(const Observations& obs, const InstrumentModel& model);

// cam_from_board of one shot from its corners (board frame) and pixels, with
// the given intrinsics and distortion (OpenCV order). False when OpenCV fails
// or fewer than 4 corners are given.
bool BoardPoseFromCorners(const std::vector<Eigen::Vector3d>& in_board,
                          const std::vector<Eigen::Vector2d>& uv, const CameraTool& camera,
                          Rigid3* cam_from_board);

}  // namespace rtscalib

// Where to hold the board for a camera on its own (SPEC 7.1, model.kinematics:
// none): the candidate photos of `rtscalib plan` for a camera that does not
// turn. Its session is better where the board fills the image's corners, is
// tilted (a board square to the optical axis cannot tell the focal length
// from its distance) and is seen near and far; each candidate is a
// placement of its own, the board's pose in the camera's frame, one photo.
//
// The candidates of a zoom: the board at three sizes in the image (its width
// kBoardSpans of the image's), its centre at 3 x 3 places that keep it in
// the image when it faces the camera (the middle and the edges of the room
// left beside it), and five orientations: facing the camera, and turned by
// kBoardTurnDeg about the image's vertical or horizontal either way.
// 3 x 9 x 5 = 135 per zoom and board. A pose where the board would not be
// whole in the image is still a candidate (the planner counts the corners
// the photo shows), except for a chessboard, which OpenCV finds only whole:
// its printed pattern must lie inside the image.
#pragma once

#include <string>
#include <vector>

#include "libcalib/geometry/rotation.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/targets.h"

namespace rtscalib {

constexpr double kBoardSpans[] = {0.3, 0.5, 0.75};
constexpr double kBoardTurnDeg = 35.0;

// A board pose in words a person holding the board can follow.
struct BoardPoseInWords {
  Eigen::Vector2d centre_px = Eigen::Vector2d::Zero();  // where the board's centre is seen
  double distance_m = 0;                                // camera to the board's centre
  double turn_deg = 0;  // about the image's vertical; > 0: its right edge nearer the camera
  double tilt_deg = 0;  // about the image's horizontal; > 0: its bottom edge nearer
};

struct CandidatePose {
  std::string placement;  // "z<zoom>_pose<k>"
  int zoom = 0;
  Rigid3 cam_from_board;
  BoardPoseInWords words;
};

// The candidates of `board` for zoom `zoom` of `model` (its camera's
// intrinsics and image size; a camera on its own, whose frame is the
// reference).
std::vector<CandidatePose> CandidateBoardPoses(const InstrumentModel& model, int zoom,
                                               const TagBoard& board);

// The board pose in words: where its centre is seen (the camera's
// projection, distortion included), how far, turned and tilted.
BoardPoseInWords DescribeBoardPose(const InstrumentModel& model, int zoom, const TagBoard& board,
                                   const Rigid3& cam_from_board);

// The image outline of the board's printed pattern at `cam_from_board`
// (its four outer corners, projected; a corner the model cannot project is
// left out).
std::vector<Eigen::Vector2d> BoardOutline(const InstrumentModel& model, int zoom,
                                          const TagBoard& board, const Rigid3& cam_from_board);

}  // namespace rtscalib

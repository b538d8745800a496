#include "libcalib/plan/board_poses.h"

#include <cmath>

#include "libcalib/model/kinematics.h"

namespace rtscalib {
namespace {

constexpr double kRadPerDeg = M_PI / 180.0;
// Readings of a camera on its own: unused (its frame is the reference).
constexpr double kPhi = 0.0, kTheta = M_PI / 2;

// Centres as fractions of the room beside a board that faces the camera:
// the middle and almost at either edge (the image's corners are where the
// distortion's higher terms are learnt).
constexpr double kPlaces[] = {-0.95, 0.0, 0.95};

// OpenCV finds a chessboard only whole, with the paper around its outer
// squares: the printed pattern's outline inside the image.
bool WholeInImage(const InstrumentModel& model, int zoom, const TagBoard& board,
                  const CandidatePose& c) {
  const CameraTool& cam = model.cams.at(zoom);
  const std::vector<Eigen::Vector2d> outline = BoardOutline(model, zoom, board, c.cam_from_board);
  if (outline.size() != 4) return false;
  for (const Eigen::Vector2d& p : outline) {
    if (p.x() < 0 || p.y() < 0 || p.x() > cam.width - 1 || p.y() > cam.height - 1) return false;
  }
  return true;
}

}  // namespace

std::vector<CandidatePose> CandidateBoardPoses(const InstrumentModel& model, int zoom,
                                               const TagBoard& board) {
  const CameraTool& cam = model.cams.at(zoom);
  const double fx = cam.intrinsics[0], fy = cam.intrinsics[1];
  const double cx = cam.intrinsics[2], cy = cam.intrinsics[3];
  const double w = board.Width(), h = board.Height();
  const Eigen::Vector3d centre_in_board(w / 2, h / 2, 0);
  const double turn = kBoardTurnDeg * kRadPerDeg;
  const Eigen::Matrix3d orientations[] = {Eigen::Matrix3d::Identity(), Ry(turn), Ry(-turn),
                                          Rx(-turn), Rx(turn)};
  std::vector<CandidatePose> out;
  for (double span : kBoardSpans) {
    // At distance d the board is fx w / d pixels wide.
    const double distance = fx * w / (span * cam.width);
    const double half_w = 0.5 * span * cam.width;
    const double half_h = 0.5 * fy * h / distance;
    for (double pv : kPlaces) {
      for (double pu : kPlaces) {
        const double u = cam.width / 2.0 + pu * std::max(0.0, cam.width / 2.0 - half_w);
        const double v = cam.height / 2.0 + pv * std::max(0.0, cam.height / 2.0 - half_h);
        // The centre on the pinhole ray of (u, v) at the distance.
        const Eigen::Vector3d ray = Eigen::Vector3d((u - cx) / fx, (v - cy) / fy, 1.0).normalized();
        const Eigen::Vector3d centre = distance * ray;
        for (const Eigen::Matrix3d& r : orientations) {
          CandidatePose c;
          c.zoom = zoom;
          c.placement = "z" + std::to_string(zoom) + "_pose" + std::to_string(out.size());
          c.cam_from_board.rotation = r;
          c.cam_from_board.translation = centre - r * centre_in_board;
          if (board.kind == BoardKind::kChessboard && !WholeInImage(model, zoom, board, c)) {
            continue;
          }
          c.words = DescribeBoardPose(model, zoom, board, c.cam_from_board);
          out.push_back(c);
        }
      }
    }
  }
  return out;
}

BoardPoseInWords DescribeBoardPose(const InstrumentModel& model, int zoom, const TagBoard& board,
                                   const Rigid3& cam_from_board) {
  BoardPoseInWords out;
  const Eigen::Vector3d centre =
      cam_from_board * Eigen::Vector3d(board.Width() / 2, board.Height() / 2, 0);
  out.distance_m = centre.norm();
  Eigen::Vector2d uv;
  if (PredictPixel(model, zoom, kPhi, kTheta, centre, &uv)) out.centre_px = uv;
  // The board's rows (x) and columns (y) in the camera's frame: a turn
  // about the image's vertical brings the right edge (+x) nearer (-z), a
  // tilt about its horizontal the bottom edge (+y).
  const Eigen::Matrix3d& r = cam_from_board.rotation;
  out.turn_deg = std::atan2(-r(2, 0), std::hypot(r(0, 0), r(1, 0))) / kRadPerDeg;
  out.tilt_deg = std::atan2(-r(2, 1), std::hypot(r(0, 1), r(1, 1))) / kRadPerDeg;
  return out;
}

std::vector<Eigen::Vector2d> BoardOutline(const InstrumentModel& model, int zoom,
                                          const TagBoard& board, const Rigid3& cam_from_board) {
  std::vector<Eigen::Vector2d> out;
  const double w = board.Width(), h = board.Height();
  for (const Eigen::Vector3d& corner : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(w, 0, 0),
                                        Eigen::Vector3d(w, h, 0), Eigen::Vector3d(0, h, 0)}) {
    Eigen::Vector2d uv;
    if (PredictPixel(model, zoom, kPhi, kTheta, cam_from_board * corner, &uv)) out.push_back(uv);
  }
  return out;
}

}  // namespace rtscalib

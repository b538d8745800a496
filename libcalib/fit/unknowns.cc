#include "libcalib/fit/unknowns.h"

#include <Eigen/Dense>
#include <map>
#include <opencv2/calib3d.hpp>
#include <stdexcept>
#include <string>
#include <tuple>

#include "libcalib/model/gauge.h"
#include "libcalib/model/kinematics.h"

namespace rtscalib {
namespace {

Eigen::Matrix3d NearestRotation(const Eigen::Matrix3d& m) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixU() * d * svd.matrixV().transpose();
}

const TagBoard* UnknownBoardOf(const TargetScene& scene, int id) {
  for (const TagBoard& b : scene.boards) {
    if (b.HasId(id) && !b.pose_known) return &b;
  }
  return nullptr;
}

}  // namespace

bool BoardPoseFromCorners(const std::vector<Eigen::Vector3d>& in_board,
                          const std::vector<Eigen::Vector2d>& uv, const CameraTool& camera,
                          Rigid3* cam_from_board) {
  if (in_board.size() < 4 || in_board.size() != uv.size()) return false;
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  for (size_t i = 0; i < in_board.size(); ++i) {
    object.emplace_back(in_board[i].x(), in_board[i].y(), in_board[i].z());
    image.emplace_back(uv[i].x(), uv[i].y());
  }
  const cv::Matx33d k(camera.intrinsics[0], 0, camera.intrinsics[2], 0, camera.intrinsics[1],
                      camera.intrinsics[3], 0, 0, 1);
  const std::vector<double> dist(camera.distortion.begin(), camera.distortion.end());
  cv::Mat rvec, tvec;
  try {
    if (!cv::solvePnP(object, image, k, dist, rvec, tvec, false, cv::SOLVEPNP_IPPE)) return false;
  } catch (const cv::Exception&) {
    return false;
  }
  cv::Matx33d r;
  cv::Rodrigues(rvec, r);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) cam_from_board->rotation(i, j) = r(i, j);
    cam_from_board->translation[i] = tvec.at<double>(i);
  }
  // The board must lie in front of the camera.
  return cam_from_board->translation.z() > 0;
}

std::vector<std::string> StartUnknowns(const Observations& obs, const UsedRows& rows,
                                       const DataFacts& facts, InstrumentModel* model) {
  std::vector<std::string> notes;
  InstrumentModel& m = *model;
  // The start re-expressed, not overwritten: its boards, points and tools
  // stay consistent with its base (libcalib/model/gauge.h).
  if (!facts.known_positions) ToIdealBaseFrame(&m);

  // Boards: the corners of each unknown board pose (board, placement and,
  // camera-only, zoom: EstimatedBoard) per shot.
  struct ShotCorners {
    int zoom = 0;
    double phi = 0, theta = 0;
    std::vector<Eigen::Vector3d> in_board;
    std::vector<Eigen::Vector2d> uv;
  };
  using PoseKey = std::tuple<int, std::string, int>;  // first_id, placement, zoom or -1
  const bool per_zoom = m.kinematics == Kinematics::kNone;
  std::map<PoseKey, std::map<std::tuple<std::string, int, double, double>, ShotCorners>> per_pose;
  std::map<PoseKey, int> first_line;
  for (int i : rows.pixels) {
    const PixelObservation& p = obs.pixels[i];
    if (p.X_known) continue;
    const std::string where = obs.pixels_source + ":" + std::to_string(p.line) + ": ";
    const TagBoard* b = UnknownBoardOf(obs.targets, p.target);
    if (!b) {
      bool surveyed = false;
      for (const TagBoard& tb : obs.targets.boards) surveyed = surveyed || tb.HasId(p.target);
      if (surveyed) continue;  // a corner of a surveyed board: known
      throw std::invalid_argument(
          where + "X, Y, Z are empty but target " + std::to_string(p.target) +
          " is not a tag of a board in the targets (SPEC 7: empty X, Y, Z need one)");
    }
    if (p.corner < 0 || p.corner > 3) {
      throw std::invalid_argument(where + "corner must be 0..3, got " + std::to_string(p.corner));
    }
    if (m.BoardOf(p.target, p.placement, p.zoom)) continue;  // already estimated: keep it
    const PoseKey key{b->first_id, p.placement, per_zoom ? p.zoom : -1};
    ShotCorners& s = per_pose[key][std::make_tuple(p.shot, p.zoom, p.phi, p.theta)];
    s.zoom = p.zoom;
    s.phi = p.phi;
    s.theta = p.theta;
    s.in_board.push_back(b->CornersInBoard(p.target - b->first_id)[p.corner]);
    s.uv.push_back(p.uv);
    if (!first_line.count(key)) first_line[key] = p.line;
  }
  for (const auto& [key, shots] : per_pose) {
    const auto& [first_id, placement, zoom] = key;
    const TagBoard* b = UnknownBoardOf(obs.targets, first_id);
    EstimatedBoard eb;
    eb.board = *b;
    eb.placement = placement;
    eb.zoom = zoom;
    Eigen::Matrix3d sum_r = Eigen::Matrix3d::Zero();
    Eigen::Vector3d sum_t = Eigen::Vector3d::Zero();
    int n = 0;
    for (const auto& [shot, s] : shots) {
      if (s.zoom < 0 || s.zoom >= m.NumZooms()) continue;
      Rigid3 cam_from_board;
      if (!BoardPoseFromCorners(s.in_board, s.uv, m.cams[s.zoom], &cam_from_board)) continue;
      const Rigid3 ref_from_board = RefFromCam(m, s.zoom, s.phi, s.theta) * cam_from_board;
      sum_r += ref_from_board.rotation;
      sum_t += ref_from_board.translation;
      ++n;
    }
    if (n == 0) {
      throw std::invalid_argument(obs.pixels_source + ":" + std::to_string(first_line[key]) +
                                  ": " + eb.Name() +
                                  " has no pose: no shot shows 4 of its corners with a usable "
                                  "camera pose (its pose cannot be started)");
    }
    eb.board.ref_from_board = Rigid3{NearestRotation(sum_r), sum_t / n};
    eb.pose = PoseBlock::FromRigid(eb.board.ref_from_board);
    m.boards.push_back(eb);
    notes.push_back(eb.Name() + ": pose started from " + std::to_string(n) +
                    " shot(s) (PnP and the start model's chain)");
  }

  // board_warp: a warp per board of unknown pose (zero to start; kept when
  // the model already has one).
  SyncBoardWarps(&m);

  // Points: the mean of the start model's predictions of their records.
  std::map<std::string, std::pair<Eigen::Vector3d, int>> sums;
  std::vector<std::string> order;
  for (int i : rows.records) {
    const Record& r = obs.records[i];
    if (r.point.empty() || m.Point(r.point)) continue;
    const Eigen::Vector3d x = r.tool == Tool::kEdm
                                  ? PredictEdm(m, r.phi, r.theta, r.d)
                                  : PredictCam(m, r.zoom, r.phi, r.theta, r.u, r.v, r.d);
    auto it = sums.find(r.point);
    if (it == sums.end()) {
      order.push_back(r.point);
      it = sums.emplace(r.point, std::make_pair(Eigen::Vector3d::Zero(), 0)).first;
    }
    it->second.first += x;
    ++it->second.second;
  }
  for (const std::string& name : order) {
    EstimatedPoint p;
    p.name = name;
    const Eigen::Vector3d x = sums[name].first / sums[name].second;
    p.x = {x.x(), x.y(), x.z()};
    m.points.push_back(p);
  }
  return notes;
}

Observations WithEstimates(const Observations& obs, const InstrumentModel& model) {
  Observations out = obs;
  for (Record& r : out.records) {
    if (r.point.empty()) continue;
    const EstimatedPoint* q = model.Point(r.point);
    if (!q) continue;
    r.x = Eigen::Vector3d(q->x[0], q->x[1], q->x[2]);
    r.point.clear();
  }
  for (PixelObservation& p : out.pixels) {
    if (p.X_known || p.corner < 0 || p.corner > 3) continue;
    const EstimatedBoard* b = model.BoardOf(p.target, p.placement, p.zoom);
    if (!b) continue;
    p.X = b->pose.ToRigid() * b->board.CornersInBoard(p.target - b->board.first_id)[p.corner];
    p.X_known = true;
  }
  return out;
}

}  // namespace rtscalib

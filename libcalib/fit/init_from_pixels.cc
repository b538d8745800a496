#include "libcalib/fit/init_from_pixels.h"

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>

#include "libcalib/model/kinematics.h"

namespace rtscalib {
namespace {

// Nearest rotation (Frobenius) to a 3x3 matrix: the chordal mean of the
// rotations that were summed into it.
Eigen::Matrix3d ProjectToRotation(const Eigen::Matrix3d& m) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixU() * d * svd.matrixV().transpose();
}

Eigen::Vector3d LogRotation(const Eigen::Matrix3d& r) {
  const Eigen::AngleAxisd aa(r);
  return aa.angle() * aa.axis();
}

Eigen::Matrix3d IdealLineOfSight(double phi, double theta) { return Rz(-phi) * Rx(-theta); }

// One shot's pose from OpenCV and its readings; `frame` 0 = the reference
// frame (known points), f > 0 = the frame of the (f-1)-th unknown board.
struct PosedShot {
  int zoom;
  double phi, theta;
  Rigid3 ref_from_cam;
  int frame = 0;
};

// Separator of a (shot, board) view's name: the shot, then the board's first id.
constexpr char kViewSeparator = '\x1f';

// One frame of the start (besides frame 0, the reference frame): a board of
// unknown pose in one placement (SPEC 7.1) and, camera-only, at one zoom
// (EstimatedBoard's key).
struct BoardFrame {
  const TagBoard* board = nullptr;
  std::string placement;
  int zoom = -1;
  bool operator==(const BoardFrame& o) const {
    return board == o.board && placement == o.placement && zoom == o.zoom;
  }
};

// SPEC 7: pixels of boards of unknown pose become views of their board alone
// in one placement (and, with `per_zoom`, one zoom), X in the board frame;
// `frame_of_view` maps such a view's name to its frame (1 + index into
// `frames`, in the order first seen).
std::vector<PixelObservation> BoardViews(const std::vector<PixelObservation>& pixels,
                                         const std::string& source,
                                         const TargetScene& targets, bool per_zoom,
                                         std::vector<BoardFrame>* frames,
                                         std::map<std::string, int>* frame_of_view) {
  std::vector<PixelObservation> out;
  out.reserve(pixels.size());
  for (PixelObservation p : pixels) {
    if (!p.X_known) {
      const TagBoard* board = nullptr;
      for (const TagBoard& b : targets.boards) {
        if (b.HasId(p.target)) board = &b;
      }
      if (!board) {
        throw std::invalid_argument(source + ":" + std::to_string(p.line) +
                                    ": X, Y, Z are empty but target " + std::to_string(p.target) +
                                    " is not a tag of a board in the targets (SPEC 7)");
      }
      if (p.corner < 0 || p.corner > 3) {
        throw std::invalid_argument(source + ":" + std::to_string(p.line) +
                                    ": corner must be 0..3, got " + std::to_string(p.corner));
      }
      const Eigen::Vector3d in_board = board->CornersInBoard(p.target - board->first_id)[p.corner];
      if (board->pose_known) {
        p.X = board->ref_from_board * in_board;
      } else {
        const BoardFrame key{board, p.placement, per_zoom ? p.zoom : -1};
        const auto it = std::find(frames->begin(), frames->end(), key);
        int frame = static_cast<int>(it - frames->begin()) + 1;
        if (it == frames->end()) {
          frames->push_back(key);
          frame = static_cast<int>(frames->size());
        }
        p.X = in_board;
        p.shot += kViewSeparator + std::to_string(frame);
        (*frame_of_view)[p.shot] = frame;
      }
      p.X_known = true;
    }
    out.push_back(std::move(p));
  }
  return out;
}

EstimatedBoard StartedBoard(const BoardFrame& frame, const Rigid3& ref_from_board) {
  EstimatedBoard eb;
  eb.board = *frame.board;
  eb.placement = frame.placement;
  eb.zoom = frame.zoom;
  eb.board.ref_from_board = ref_from_board;
  eb.pose = PoseBlock::FromRigid(ref_from_board);
  return eb;
}

CameraTool SizeFor(const InitFromPixelsOptions& o, int zoom,
                   const std::vector<PixelObservation>& pixels, std::vector<std::string>* notes) {
  if (zoom < static_cast<int>(o.cameras.size())) return o.cameras[zoom];
  CameraTool cam;
  double umax = 0, vmax = 0;
  for (const PixelObservation& p : pixels) {
    umax = std::max(umax, p.uv.x());
    vmax = std::max(vmax, p.uv.y());
  }
  // Observed corners come within a few pixels of the border; round up to even.
  cam.width = 2 * static_cast<int>(std::ceil((umax + 1.0) / 2.0));
  cam.height = 2 * static_cast<int>(std::ceil((vmax + 1.0) / 2.0));
  notes->push_back("zoom " + std::to_string(zoom) + ": no model.cameras entry; image size " +
                   std::to_string(cam.width) + " x " + std::to_string(cam.height) +
                   " px taken from the extent of its pixels");
  return cam;
}

std::map<int, std::vector<PixelObservation>> ByZoom(const std::vector<PixelObservation>& pixels,
                                                    const InitFromPixelsOptions& o, int* excluded) {
  std::map<int, std::vector<PixelObservation>> out;
  for (const PixelObservation& p : pixels) {
    if (o.critical_region.Contains(p.theta)) {
      ++*excluded;
      continue;
    }
    out[p.zoom].push_back(p);
  }
  return out;
}

CalibrateViewsOptions ViewsOptions(const InitFromPixelsOptions& o) {
  CalibrateViewsOptions v;
  v.distortion = o.distortion;
  v.threads = o.threads;
  return v;
}

// CalibrateViews on one zoom's pixels; its messages name the pixels' file.
ViewsCalibration CalibrateZoom(const std::vector<PixelObservation>& pixels, const CameraTool& cam,
                               const InitFromPixelsOptions& o) {
  try {
    return CalibrateViews(pixels, cam.width, cam.height, ViewsOptions(o));
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(o.source + ": " + e.what());
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(o.source + ": " + e.what());
  }
}

std::string Describe(const ViewsCalibration& v) {
  std::ostringstream s;
  s << "zoom " << v.zoom << ": OpenCV start from " << v.shots.size() << " shots, " << v.num_points
    << " points, rms " << v.rms_px << " px, fx " << v.intrinsics[0] << " fy " << v.intrinsics[1]
    << " cx " << v.intrinsics[2] << " cy " << v.intrinsics[3];
  if (!v.excluded.empty()) s << ", " << v.excluded.size() << " shot(s) excluded";
  if (!v.init_note.empty()) s << " (" << v.init_note << ")";
  return s.str();
}

}  // namespace

std::string InitFromPixelsOptions::Check() const {
  if (const std::string region = critical_region.Check(); !region.empty()) return region;
  for (size_t z = 0; z < cameras.size(); ++z) {
    if (cameras[z].width <= 0 || cameras[z].height <= 0) {
      return "cameras[" + std::to_string(z) + "] needs a positive image size";
    }
  }
  return "";
}

// DistortionGroups (calibrate_views.h) is CalibrateViews' own closed set of
// OpenCV groups (it does not know the effect catalogue); this is the one mapping,
// checked against the catalogue's coefficients in tests/fit/joint_init_test.cc.
static_assert(kNumDistortionGroups == 5,
              "a distortion group was added to the effect catalogue: map it here and in "
              "DistortionGroups");
DistortionGroups DistortionGroupsOf(const EffectSet& effects) {
  DistortionGroups g;
  g.radial = effects.Has(Effect::kRadialDistortion);
  g.tangential = effects.Has(Effect::kTangentialDistortion);
  g.rational = effects.Has(Effect::kRationalDistortion);
  g.thin_prism = effects.Has(Effect::kThinPrism);
  g.sensor_tilt = effects.Has(Effect::kSensorTilt);
  return g;
}

InstrumentModel DhFromSpherical(const InstrumentModel& s) {
  if (s.kinematics != Kinematics::kSpherical) {
    throw std::invalid_argument("DhFromSpherical: the model is not spherical");
  }
  for (Effect e : s.effects.List()) {
    if (IsKinematic(e)) {
      throw std::invalid_argument(std::string("DhFromSpherical: effect ") + Info(e).name +
                                  " has no exact dh equivalent here; convert without effects");
    }
  }
  // IdealModel(kDh) holds exactly the base Rx(pi), the links and M_T of the
  // ideal instrument; prepend the spherical base and append the tools.
  InstrumentModel d = IdealModel(Kinematics::kDh, s.NumZooms(), CameraTool{});
  const Rigid3 ideal_base = d.base.ToRigid();
  const Rigid3 m_t = d.edm.ToRigid();
  d.effects = s.effects;
  d.edm_cyclic_unit_length = s.edm_cyclic_unit_length;
  d.base = PoseBlock::FromRigid(s.base.ToRigid() * ideal_base);
  d.edm = PoseBlock::FromRigid(m_t * s.edm.ToRigid());
  d.cams = s.cams;
  for (CameraTool& c : d.cams)
    c.flange_from_cam = PoseBlock::FromRigid(m_t * c.flange_from_cam.ToRigid());
  return d;
}

InitFromPixelsResult InitFromPixels(const std::vector<PixelObservation>& observed,
                                    const InitFromPixelsOptions& options) {
  const std::string msg = options.Check();
  if (!msg.empty()) throw std::invalid_argument("InitFromPixels: " + msg);
  InitFromPixelsResult result;
  const bool camera_only = options.kinematics == Kinematics::kNone;
  std::vector<BoardFrame> boards;
  std::map<std::string, int> frame_of_view;
  const std::vector<PixelObservation> pixels =
      BoardViews(observed, options.source, options.targets, camera_only, &boards, &frame_of_view);
  const int num_frames = 1 + static_cast<int>(boards.size());
  int excluded = 0;
  const std::map<int, std::vector<PixelObservation>> zooms = ByZoom(pixels, options, &excluded);
  if (excluded > 0) {
    result.notes.push_back(std::to_string(excluded) +
                           " pixel observation(s) in the critical region not used for the start");
  }
  if (zooms.empty()) {
    // Which file gave nothing, and why: none given, or all in the critical region.
    std::ostringstream what;
    what << "nothing to start from: " << options.source << " gave " << observed.size()
         << " pixel observations";
    if (excluded > 0) {
      what << "; " << excluded << " of them lie in the critical region (zenith angle outside "
           << "fit.critical_region's " << options.critical_region.min_zenith_rad * 180 / M_PI << " to "
           << options.critical_region.max_zenith_rad * 180 / M_PI << " deg)";
    }
    throw std::invalid_argument(what.str());
  }
  const int num_zooms = zooms.rbegin()->first + 1;

  // 1. Per zoom: intrinsics, distortion and shot poses from OpenCV.
  InstrumentModel& m = result.model;
  m.kinematics = Kinematics::kSpherical;
  m.cams.resize(num_zooms);
  std::map<int, CameraTool> cam_of_zoom;
  result.views.resize(num_zooms);
  for (auto& v : result.views) v.zoom = -1;
  std::vector<PosedShot> shots;
  for (const auto& [zoom, obs] : zooms) {
    CameraTool cam = SizeFor(options, zoom, obs, &result.notes);
    ViewsCalibration v = CalibrateZoom(obs, cam, options);
    result.notes.push_back(Describe(v));
    cam.intrinsics = v.intrinsics;
    cam.distortion = v.distortion;
    m.cams[zoom] = cam;
    cam_of_zoom[zoom] = cam;
    for (const ShotPose& s : v.shots) {
      const auto f = frame_of_view.find(s.shot);
      shots.push_back(
          {zoom, s.phi, s.theta, s.ref_from_cam, f == frame_of_view.end() ? 0 : f->second});
    }
    result.views[zoom] = std::move(v);
  }
  for (int z = 0; z < num_zooms; ++z) {
    if (result.views[z].zoom < 0) {
      result.notes.push_back("zoom " + std::to_string(z) +
                             " has no pixels: its camera is a copy of the nearest zoom's start");
    }
  }
  if (camera_only) {
    // SPEC 7.1: no chain. Each board frame's pose in its zoom's camera frame
    // is the chordal mean of cam_from_board over its views (the camera did
    // not move within a placement); OpenCV's pose of a view is board_from_cam.
    m = IdealModel(Kinematics::kNone, num_zooms, CameraTool());
    for (int z = 0; z < num_zooms; ++z) {
      if (result.views[z].zoom >= 0) m.cams[z] = CameraTool(cam_of_zoom[z]);
    }
    std::vector<Eigen::Matrix3d> rot(num_frames, Eigen::Matrix3d::Zero());
    std::vector<Eigen::Vector3d> pos(num_frames, Eigen::Vector3d::Zero());
    std::vector<int> count(num_frames, 0);
    for (const PosedShot& s : shots) {
      const Rigid3 cam_from_board = s.ref_from_cam.Inverse();
      rot[s.frame] += cam_from_board.rotation;
      pos[s.frame] += cam_from_board.translation;
      ++count[s.frame];
    }
    for (int f = 1; f < num_frames; ++f) {
      if (count[f] == 0) continue;  // every view of it excluded by OpenCV: no start
      m.boards.push_back(
          StartedBoard(boards[f - 1], Rigid3{ProjectToRotation(rot[f]), pos[f] / count[f]}));
    }
    result.notes.push_back("camera-only start: " + std::to_string(m.boards.size()) +
                           " board pose(s) from OpenCV's views (kinematics none)");
    return result;
  }

  // 2a. Camera tool rotations, per zoom: Park-Martin hand-eye on shot pairs.
  std::vector<Eigen::Matrix3d> cam_rotation(num_zooms, Eigen::Matrix3d::Identity());
  for (const auto& [zoom, obs] : zooms) {
    Eigen::Matrix3d h = Eigen::Matrix3d::Zero();  // sum beta alpha^T
    int pairs = 0;
    for (size_t i = 0; i < shots.size(); ++i) {
      if (shots[i].zoom != zoom) continue;
      for (size_t j = i + 1; j < shots.size(); ++j) {
        // Relative motions are frame-free only within one frame.
        if (shots[j].zoom != zoom || shots[j].frame != shots[i].frame) continue;
        const Eigen::Matrix3d a_ij = IdealLineOfSight(shots[i].phi, shots[i].theta).transpose() *
                                     IdealLineOfSight(shots[j].phi, shots[j].theta);
        const Eigen::Matrix3d b_ij =
            shots[i].ref_from_cam.rotation.transpose() * shots[j].ref_from_cam.rotation;
        const Eigen::Vector3d alpha = LogRotation(a_ij), beta = LogRotation(b_ij);
        // Pairs near a half turn (face 1 vs face 2) have an ill-defined log.
        if (alpha.norm() > 2.5 || alpha.norm() < 1e-6) continue;
        h += beta * alpha.transpose();
        ++pairs;
      }
    }
    // beta = C^T alpha: C^T = argmax tr(C^T^T h)... Procrustes on sum beta alpha^T.
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::Vector3d sv = svd.singularValues();
    if (pairs < 2 || !(sv[1] > 1e-6 * sv[0])) {
      result.notes.push_back("zoom " + std::to_string(zoom) +
                             ": the shots turn about one axis only; camera tool rotation taken "
                             "from the mean with an ideal base");
      Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
      for (const PosedShot& s : shots) {
        if (s.zoom == zoom) {
          sum += IdealLineOfSight(s.phi, s.theta).transpose() * s.ref_from_cam.rotation;
        }
      }
      cam_rotation[zoom] = ProjectToRotation(sum);
      continue;
    }
    const Eigen::Matrix3d ct = ProjectToRotation(h);  // C^T maps alpha to beta
    cam_rotation[zoom] = ct.transpose();
  }

  // 2b. Base rotation (one per frame): chordal mean over the frame's shots.
  std::vector<Eigen::Matrix3d> sums(num_frames, Eigen::Matrix3d::Zero());
  std::vector<int> frame_shots(num_frames, 0);
  for (const PosedShot& s : shots) {
    sums[s.frame] += s.ref_from_cam.rotation * cam_rotation[s.zoom].transpose() *
                     IdealLineOfSight(s.phi, s.theta).transpose();
    ++frame_shots[s.frame];
  }
  std::vector<Eigen::Matrix3d> frame_rotation(num_frames, Eigen::Matrix3d::Identity());
  for (int f = 0; f < num_frames; ++f) {
    if (frame_shots[f] > 0) frame_rotation[f] = ProjectToRotation(sums[f]);
  }

  // 2c. Translations: t_i = t_Bf + R_Bf A_i t_Cz, linear in (t_B0, t_B1, ...,
  // t_C0, t_C1, ...).
  const int n_unknown = 3 * num_frames + 3 * num_zooms;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(3 * shots.size(), n_unknown);
  Eigen::VectorXd b(3 * shots.size());
  for (size_t i = 0; i < shots.size(); ++i) {
    const PosedShot& s = shots[i];
    a.block<3, 3>(3 * i, 3 * s.frame).setIdentity();
    a.block<3, 3>(3 * i, 3 * num_frames + 3 * s.zoom) =
        frame_rotation[s.frame] * IdealLineOfSight(s.phi, s.theta);
    b.segment<3>(3 * i) = s.ref_from_cam.translation;
  }
  // Columns of zooms (frames) without shots are zero: the minimum-norm
  // solution sets them to 0.
  const Eigen::VectorXd x = a.completeOrthogonalDecomposition().solve(b);

  // Without known points the reference frame is the ideal base frame (SPEC 7).
  const Rigid3 base = frame_shots[0] > 0 ? Rigid3{frame_rotation[0], x.head<3>()} : Rigid3{};
  m.base = PoseBlock::FromRigid(base);
  std::vector<Rigid3> frame_from_ref(num_frames);
  for (int f = 1; f < num_frames; ++f) {
    const Rigid3 frame_from_flange_base{frame_rotation[f], x.segment<3>(3 * f)};
    frame_from_ref[f] = frame_from_flange_base * base.Inverse();
    m.boards.push_back(StartedBoard(boards[f - 1], frame_from_ref[f].Inverse()));
  }
  m.edm = PoseBlock();
  for (int z = 0; z < num_zooms; ++z) {
    m.cams[z].flange_from_cam =
        PoseBlock::FromRigid(Rigid3{cam_rotation[z], x.segment<3>(3 * num_frames + 3 * z)});
  }
  // Zooms without pixels: a copy of the nearest zoom with pixels.
  for (int z = 0; z < num_zooms; ++z) {
    if (result.views[z].zoom >= 0) continue;
    int best = -1;
    for (const auto& [zoom, obs] : zooms) {
      if (best < 0 || std::abs(zoom - z) < std::abs(best - z)) best = zoom;
    }
    m.cams[z] = m.cams[best];
  }

  // How well the chain explains the OpenCV poses.
  double sum_rot = 0, sum_pos = 0;
  for (const PosedShot& s : shots) {
    const Rigid3 pred = frame_from_ref[s.frame] * RefFromCam(m, s.zoom, s.phi, s.theta);
    sum_rot += LogRotation(pred.rotation.transpose() * s.ref_from_cam.rotation).squaredNorm();
    sum_pos += (pred.translation - s.ref_from_cam.translation).squaredNorm();
  }
  result.chain_rms_rad = std::sqrt(sum_rot / std::max<size_t>(shots.size(), 1));
  result.chain_rms_m = std::sqrt(sum_pos / std::max<size_t>(shots.size(), 1));
  {
    std::ostringstream s;
    s << "spherical chain fitted to " << shots.size() << " OpenCV shot poses: rms "
      << result.chain_rms_rad << " rad, " << result.chain_rms_m << " m";
    result.notes.push_back(s.str());
  }

  // 3. The requested kinematics.
  if (options.kinematics == Kinematics::kDh) {
    // Same predictions in the same reference frame: the boards carry over.
    const std::vector<EstimatedBoard> estimated = m.boards;
    m = DhFromSpherical(m);
    m.boards = estimated;
  }
  return result;
}

std::vector<std::string> InitCameraFromPixels(const std::vector<PixelObservation>& pixels, int zoom,
                                              const InitFromPixelsOptions& options,
                                              InstrumentModel* model) {
  std::vector<std::string> notes;
  int excluded = 0;
  const std::map<int, std::vector<PixelObservation>> zooms = ByZoom(pixels, options, &excluded);
  auto it = zooms.find(zoom);
  if (it == zooms.end()) {
    throw std::invalid_argument("InitCameraFromPixels: zoom " + std::to_string(zoom) +
                                " has no pixel observations outside the critical region");
  }
  for (const PixelObservation& p : it->second) {
    if (!p.X_known) {
      // The camera tool would need the board's pose and the board's pose the
      // camera tool; with records the chain is the extraction's, which has no
      // camera for this zoom.
      throw std::invalid_argument(
          options.source + ":" + std::to_string(p.line) + ": zoom " + std::to_string(zoom) +
          " has no camera rows in records.csv and its pixels show a board without a pose: add "
          "camera rows of this zoom, a surveyed board, or leave records.csv out (SPEC 7)");
    }
  }
  CameraTool cam = SizeFor(options, zoom, it->second, &notes);
  const ViewsCalibration v = CalibrateZoom(it->second, cam, options);
  notes.push_back(Describe(v));
  cam.intrinsics = v.intrinsics;
  cam.distortion = v.distortion;
  Eigen::Matrix3d rot_sum = Eigen::Matrix3d::Zero();
  Eigen::Vector3d t_sum = Eigen::Vector3d::Zero();
  for (const ShotPose& s : v.shots) {
    const Rigid3 flange_from_cam = RefFromFlange(*model, s.phi, s.theta).Inverse() * s.ref_from_cam;
    rot_sum += flange_from_cam.rotation;
    t_sum += flange_from_cam.translation;
  }
  cam.flange_from_cam = PoseBlock::FromRigid(
      Rigid3{ProjectToRotation(rot_sum), t_sum / static_cast<double>(v.shots.size())});
  if (zoom >= model->NumZooms()) model->cams.resize(zoom + 1, cam);
  model->cams[zoom] = cam;
  notes.push_back("zoom " + std::to_string(zoom) +
                  ": camera tool started from its pixels (no camera rows for it)");
  return notes;
}

}  // namespace rtscalib

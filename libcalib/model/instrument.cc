#include "libcalib/model/instrument.h"

#include <Eigen/Geometry>
#include <stdexcept>

#include "libcalib/model/kinematics.h"

namespace rtscalib {

const char* KinematicsName(Kinematics k) {
  switch (k) {
    case Kinematics::kDh:
      return "dh";
    case Kinematics::kSpherical:
      return "spherical";
    case Kinematics::kNone:
      return "none";
  }
  return "?";
}

Rigid3 PoseBlock::ToRigid() const {
  Eigen::Quaterniond quat(q[3], q[0], q[1], q[2]);
  return {quat.normalized().toRotationMatrix(), Eigen::Vector3d(t[0], t[1], t[2])};
}

PoseBlock PoseBlock::FromRigid(const Rigid3& r) {
  Eigen::Quaterniond quat(r.rotation);
  quat.normalize();
  if (quat.w() < 0) quat.coeffs() *= -1.0;
  PoseBlock out;
  out.q = {quat.x(), quat.y(), quat.z(), quat.w()};
  out.t = {r.translation.x(), r.translation.y(), r.translation.z()};
  return out;
}

Eigen::Vector3d PoseBlock::Euler() const { return EulerFromRotation(ToRigid().rotation); }

int FaceOf(double theta) {
  double t = std::fmod(theta, 2.0 * M_PI);
  if (t < 0) t += 2.0 * M_PI;
  return t <= M_PI ? 1 : 2;
}

InstrumentModel IdealModel(Kinematics k, int num_zooms, const CameraTool& camera) {
  InstrumentModel m;
  m.kinematics = k;
  CameraTool cam = camera;
  if (k == Kinematics::kDh) {
    // Klug Tables 1/2 snapped (Eq. 85-88): M_B = Rx(pi), link 1 = {0, -pi/2, pi/2, 0},
    // link 2 = 0, M_T = Rz(pi) Ry(pi/2) Rx(-pi/2). Their product is Eq. 90.
    m.base = PoseBlock::FromRigid(Rigid3{Rx(M_PI), Eigen::Vector3d::Zero()});
    m.links[0].p = {0.0, -M_PI / 2, M_PI / 2, 0.0};
    m.links[1].p = {0.0, 0.0, 0.0, 0.0};
    const Rigid3 tool{Rz(M_PI) * Ry(M_PI / 2) * Rx(-M_PI / 2), Eigen::Vector3d::Zero()};
    m.edm = PoseBlock::FromRigid(tool);
    cam.flange_from_cam = PoseBlock::FromRigid(tool);
  } else {
    m.base = PoseBlock();
    m.edm = PoseBlock();
    cam.flange_from_cam = PoseBlock();
  }
  m.cams.assign(num_zooms, cam);
  return m;
}

ModelView<double> ViewOf(const InstrumentModel& model) {
  ModelView<double> v;
  v.kinematics = model.kinematics;
  v.base_q = model.base.q.data();
  v.base_t = model.base.t.data();
  v.link[0] = model.links[0].p.data();
  v.link[1] = model.links[1].p.data();
  for (Effect e : model.effects.List()) {
    if (IsKinematic(e)) v.effect[static_cast<int>(e)] = model.EffectValue(e).data();
  }
  v.edm_cyclic_unit_length = model.edm_cyclic_unit_length;
  return v;
}

namespace {
Rigid3 ToRigid3(const RigidT<double>& r) { return {r.R, r.t}; }
const CameraTool& Cam(const InstrumentModel& model, int zoom) {
  if (zoom < 0 || zoom >= model.NumZooms()) {
    throw std::out_of_range("zoom level " + std::to_string(zoom) + " is not in the model (it has " +
                            std::to_string(model.NumZooms()) + " zoom levels)");
  }
  return model.cams[zoom];
}
}  // namespace

Rigid3 RefFromFlange(const InstrumentModel& model, double phi, double theta) {
  return ToRigid3(RefFromFlange(ViewOf(model), phi, theta));
}

Rigid3 RefFromEdm(const InstrumentModel& model, double phi, double theta) {
  return RefFromFlange(model, phi, theta) * model.edm.ToRigid();
}

Rigid3 RefFromCam(const InstrumentModel& model, int zoom, double phi, double theta) {
  return RefFromFlange(model, phi, theta) * Cam(model, zoom).flange_from_cam.ToRigid();
}

Eigen::Vector3d PredictEdm(const InstrumentModel& model, double phi, double theta, double d) {
  return EdmPoint(ViewOf(model), model.edm.q.data(), model.edm.t.data(), phi, theta, d);
}

Eigen::Vector3d PredictCam(const InstrumentModel& model, int zoom, double phi, double theta,
                           double u, double v, double d) {
  const CameraTool& cam = Cam(model, zoom);
  const double pixel[2] = {u, v};
  Eigen::Vector3d out;
  if (!CamPoint(ViewOf(model), cam.flange_from_cam.q.data(), cam.flange_from_cam.t.data(),
                cam.intrinsics.data(), cam.distortion.data(), FocusOf(model, zoom), phi, theta,
                pixel, d, &out)) {
    throw std::runtime_error("pixel (" + std::to_string(u) + ", " + std::to_string(v) +
                             ") cannot be undistorted with zoom " + std::to_string(zoom) +
                             "'s distortion");
  }
  return out;
}

bool PredictPixel(const InstrumentModel& model, int zoom, double phi, double theta,
                  const Eigen::Vector3d& x_ref, Eigen::Vector2d* pixel, double focus_distance) {
  const CameraTool& cam = Cam(model, zoom);
  return ProjectPoint(ViewOf(model), cam.flange_from_cam.q.data(), cam.flange_from_cam.t.data(),
                      cam.intrinsics.data(), cam.distortion.data(), FocusOf(model, zoom),
                      focus_distance, phi, theta, x_ref, pixel->data());
}

const double* FocusOf(const InstrumentModel& model, int zoom) {
  if (!model.effects.Has(Effect::kFocus)) return nullptr;
  return Cam(model, zoom).focus.data();
}

std::string EstimatedBoard::Name() const {
  std::string out = "board " + std::to_string(board.first_id);
  if (!placement.empty()) out += " at placement " + placement;
  if (zoom >= 0) out += (placement.empty() ? " at zoom " : ", zoom ") + std::to_string(zoom);
  return out;
}

std::string EstimatedBoard::Key() const {
  std::string out = "board[" + std::to_string(board.first_id);
  if (!placement.empty()) out += "@" + placement;
  if (zoom >= 0) out += "/z" + std::to_string(zoom);
  return out + "]";
}

const EstimatedBoard* InstrumentModel::BoardOf(int id, const std::string& placement,
                                               int zoom) const {
  for (const EstimatedBoard& b : boards) {
    if (b.Holds(id, placement, zoom)) return &b;
  }
  return nullptr;
}
EstimatedBoard* InstrumentModel::BoardOf(int id, const std::string& placement, int zoom) {
  return const_cast<EstimatedBoard*>(
      static_cast<const InstrumentModel*>(this)->BoardOf(id, placement, zoom));
}
const EstimatedPoint* InstrumentModel::Point(const std::string& name) const {
  for (const EstimatedPoint& p : points) {
    if (p.name == name) return &p;
  }
  return nullptr;
}
EstimatedPoint* InstrumentModel::Point(const std::string& name) {
  return const_cast<EstimatedPoint*>(static_cast<const InstrumentModel*>(this)->Point(name));
}
const BoardWarp* InstrumentModel::WarpOf(int first_id) const {
  for (const BoardWarp& w : board_warps) {
    if (w.first_id == first_id) return &w;
  }
  return nullptr;
}
BoardWarp* InstrumentModel::WarpOf(int first_id) {
  return const_cast<BoardWarp*>(static_cast<const InstrumentModel*>(this)->WarpOf(first_id));
}

void SyncBoardWarps(InstrumentModel* model) {
  const bool on = model->effects.Has(Effect::kBoardWarp);
  if (!on) model->board_warps.clear();
  for (EstimatedBoard& b : model->boards) {
    BoardWarp* w = model->WarpOf(b.board.first_id);
    if (on && !w) {
      BoardWarp fresh;
      fresh.first_id = b.board.first_id;
      model->board_warps.push_back(fresh);
      w = &model->board_warps.back();
    }
    b.board.warp = w ? w->w : std::array<double, kNumBoardWarp>{0, 0};
  }
}

}  // namespace rtscalib

#include "libcalib/api/rtscalib.h"

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>

#include "libcalib/camera/opencv_model.h"
#include "libcalib/fit/parameter_layout.h"
#include "libcalib/io/covariance_io.h"
#include "libcalib/io/model_io.h"
#include "libcalib/model/kinematics.h"
#include "libcalib/text/number_text.h"

namespace rtscalib {

namespace {

std::string Point(const Eigen::Vector3d& x) {
  return "(" + Significant(x[0]) + ", " + Significant(x[1]) + ", " + Significant(x[2]) + ")";
}

void CheckFinite(std::initializer_list<double> values, const char* what) {
  for (double v : values) {
    if (!std::isfinite(v)) {
      throw PredictionError(PredictionFailure::kNonFinite, std::string("finite ") + what,
                            "NaN or infinity");
    }
  }
}

template <typename Derived>
void CheckFiniteResult(const Eigen::MatrixBase<Derived>& v, const char* what) {
  if (!v.allFinite()) {
    throw PredictionError(PredictionFailure::kNonFinite, std::string("a finite ") + what,
                          "NaN or infinity from the model");
  }
}

// The sigmas model.yaml states per parameter, in ParameterLayout order: the
// diagonal approximation of P used when no full covariance came with the model.
Eigen::VectorXd DiagonalVariances(const InstrumentModel& m,
                                  const std::vector<LayoutBlock>& layout) {
  Eigen::VectorXd var = Eigen::VectorXd::Zero(LayoutSize(layout));
  const ModelSigmas& s = m.sigmas;
  if (!s.valid) return var;
  auto put = [&](const std::string& name, const double* sigma) {
    for (const LayoutBlock& b : layout) {
      if (b.name != name) continue;
      for (int i = 0; i < b.size; ++i) var[b.offset + i] = sigma[i] * sigma[i];
    }
  };
  put("base.rotation", s.base.rotation.data());
  put("base.t", s.base.t.data());
  if (m.kinematics == Kinematics::kDh) {
    put("link1", s.links[0].data());
    put("link2", s.links[1].data());
  }
  put("edm.rotation", s.edm.rotation.data());
  put("edm.t", s.edm.t.data());
  for (Effect e : m.effects.List()) {
    if (!IsKinematic(e)) continue;
    // The effect's own 2x2 covariance (row major); the constructor adds its
    // off-diagonal, the one correlation model.yaml stores.
    const std::array<double, 4>& cov = s.effect_cov[static_cast<int>(e)];
    const double sd[2] = {std::sqrt(cov[0]), std::sqrt(cov[3])};
    put(Info(e).name, sd);
  }
  for (int z = 0; z < m.NumZooms(); ++z) {
    if (z >= static_cast<int>(s.cam_tools.size())) break;
    const std::string c = "cam[" + std::to_string(z) + "]";
    put(c + ".rotation", s.cam_tools[z].rotation.data());
    put(c + ".t", s.cam_tools[z].t.data());
    put(c + ".intrinsics", s.intrinsics[z].data());
    put(c + ".distortion", s.distortion[z].data());
    if (z < static_cast<int>(s.focus.size())) put(c + ".focus", s.focus[z].data());
  }
  return var;
}

// The ray through (u, v) with the camera focused at `focus_distance` (SPEC
// 4.1; <= 0: at infinity, the intrinsics as stored).
bool RawRay(const InstrumentModel& m, int zoom, double phi, double theta, double u, double v,
            double focus_distance, Eigen::Matrix<double, 6, 1>* out) {
  const CameraTool& cam = m.cams[zoom];
  const double pixel[2] = {u, v};
  double k[kNumIntrinsics];
  const double* focus = focus_distance > 0 ? FocusOf(m, zoom) : nullptr;
  if (!FocusedIntrinsics(cam.intrinsics.data(), focus, focus_distance, k)) return false;
  double ray[3];
  if (!PixelToRay(k, cam.distortion.data(), pixel, ray)) return false;
  const Rigid3 ref_from_cam = RefFromCam(m, zoom, phi, theta);
  out->head<3>() = ref_from_cam.translation;
  out->tail<3>() = ref_from_cam.rotation * Eigen::Vector3d(ray[0], ray[1], ray[2]);
  return true;
}

}  // namespace

// ---------------------------------------------------------------------------

CalibratedInstrument CalibratedInstrument::Load(const std::string& model_yaml) {
  InstrumentModel model = ReadModelYaml(model_yaml);
  const std::string companion = CovariancePathFor(model_yaml);
  std::error_code ec;
  if (std::filesystem::exists(companion, ec)) ReadCovarianceYaml(companion, &model);
  return CalibratedInstrument(std::move(model));
}

CalibratedInstrument::CalibratedInstrument(InstrumentModel model) : model_(std::move(model)) {
  const std::vector<LayoutBlock> layout = ParameterLayout(model_);
  for (const LayoutBlock& b : layout) blocks_.push_back({b.name, b.offset, b.size, b.unit});
  if (model_.sigmas.covariance.rows() == LayoutSize(layout) && LayoutSize(layout) > 0) {
    // The fit's full covariance (covariance.yaml): correlations included.
    covariance_ = model_.sigmas.covariance;
    has_covariance_ = true;
    full_covariance_ = true;
    return;
  }
  covariance_ = DiagonalVariances(model_, layout).asDiagonal();
  for (const Effect e : model_.effects.List()) {
    if (!IsKinematic(e) || Info(e).num_params < 2 || !model_.sigmas.valid) continue;
    const ParameterBlock& b = Block(Info(e).name);
    const std::array<double, 4>& cov = model_.sigmas.effect_cov[static_cast<int>(e)];
    covariance_(b.offset, b.offset + 1) = cov[1];
    covariance_(b.offset + 1, b.offset) = cov[2];
  }
  has_covariance_ = model_.sigmas.valid;
}

int CalibratedInstrument::NumParameters() const {
  return blocks_.empty() ? 0 : blocks_.back().offset + blocks_.back().size;
}

const ParameterBlock& CalibratedInstrument::Block(const std::string& name) const {
  for (const ParameterBlock& b : blocks_) {
    if (b.name == name) return b;
  }
  throw std::out_of_range("the model has no parameter block '" + name + "'");
}

void CalibratedInstrument::SetParameterCovariance(const Eigen::MatrixXd& covariance) {
  const int n = NumParameters();
  if (covariance.rows() != n || covariance.cols() != n) {
    throw std::invalid_argument("parameter covariance must be " + std::to_string(n) + "x" +
                                std::to_string(n) + ", got " + std::to_string(covariance.rows()) +
                                "x" + std::to_string(covariance.cols()));
  }
  if (!covariance.allFinite()) {
    throw std::invalid_argument("parameter covariance has NaN or infinite entries");
  }
  if ((covariance - covariance.transpose()).cwiseAbs().maxCoeff() >
      1e-12 * covariance.cwiseAbs().maxCoeff()) {
    throw std::invalid_argument("parameter covariance is not symmetric");
  }
  covariance_ = covariance;
  has_covariance_ = true;
  full_covariance_ = true;
}

InstrumentModel CalibratedInstrument::Plus(const Eigen::VectorXd& delta) const {
  if (delta.size() != NumParameters()) {
    throw std::invalid_argument("Plus: delta has " + std::to_string(delta.size()) +
                                " values, the parameter vector " + std::to_string(NumParameters()));
  }
  InstrumentModel out = model_;
  for (const LayoutBlock& b : ParameterLayout(model_)) {
    LayoutPlus(b, delta.data() + b.offset, &out);
  }
  return out;
}

void CalibratedInstrument::CheckZoom(int zoom) const {
  if (zoom < 0 || zoom >= NumZooms()) {
    throw PredictionError(
        PredictionFailure::kNoSuchZoom,
        NumZooms() == 0 ? std::string("no camera rows (the model has no camera)")
                        : "a zoom level of the model (0.." + std::to_string(NumZooms() - 1) + ")",
        std::to_string(zoom));
  }
}

void CalibratedInstrument::CheckCameraDetermined(int zoom) const {
  CheckZoom(zoom);
  if (!model_.cams[zoom].determined) {
    throw PredictionError(PredictionFailure::kNotDetermined,
                          "a zoom whose camera the model determines (the calibration data had no "
                          "camera rows or pixels of this zoom)",
                          std::to_string(zoom));
  }
}

int CalibratedInstrument::ImageWidth(int zoom) const {
  CheckZoom(zoom);
  return model_.cams[zoom].width;
}

int CalibratedInstrument::ImageHeight(int zoom) const {
  CheckZoom(zoom);
  return model_.cams[zoom].height;
}

namespace {

void CheckInImage(const CameraTool& cam, int zoom, double u, double v, const char* what) {
  // Pixel centres run from 0 to width - 1; the image's border is half a pixel out.
  const double mu = kImageMargin * cam.width, mv = kImageMargin * cam.height;
  const double u0 = -0.5 - mu, u1 = cam.width - 0.5 + mu;
  const double v0 = -0.5 - mv, v1 = cam.height - 0.5 + mv;
  if (!(u >= u0 && u <= u1 && v >= v0 && v <= v1)) {
    throw PredictionError(PredictionFailure::kOutsideImage,
                          std::string(what) + " within zoom " + std::to_string(zoom) + "'s " +
                              std::to_string(cam.width) + "x" + std::to_string(cam.height) +
                              " image and " + Significant(100 * kImageMargin) + "% beyond (u in [" +
                              Significant(u0) + ", " + Significant(u1) + "], v in [" +
                              Significant(v0) + ", " + Significant(v1) + "])",
                          "(" + Significant(u) + ", " + Significant(v) + ")");
  }
}

}  // namespace

Eigen::Vector3d CalibratedInstrument::EdmPoint(double phi, double theta, double d) const {
  if (model_.kinematics == Kinematics::kNone) {
    throw PredictionError(PredictionFailure::kNotDetermined,
                          "a model with kinematics (this one is camera-only, kinematics none: "
                          "it has no EDM)",
                          "edm");
  }
  if (!model_.edm_determined) {
    throw PredictionError(PredictionFailure::kNotDetermined,
                          "a tool the model determines (the calibration data had no EDM rows)",
                          "edm");
  }
  CheckFinite({phi, theta, d}, "readings phi, theta, d");
  const Eigen::Vector3d x = PredictEdm(model_, phi, theta, d);
  CheckFiniteResult(x, "EDM point");
  return x;
}

Ray CalibratedInstrument::CameraRay(int zoom, double phi, double theta, double u, double v,
                                    double focus_distance) const {
  CheckFinite({phi, theta, u, v, focus_distance}, "readings phi, theta, pixel u, v and focus distance");
  CheckCameraDetermined(zoom);
  CheckInImage(model_.cams[zoom], zoom, u, v, "a pixel");
  Eigen::Matrix<double, 6, 1> r;
  if (!RawRay(model_, zoom, phi, theta, u, v, focus_distance, &r)) {
    throw PredictionError(PredictionFailure::kUntrustedPixel,
                          "a pixel zoom " + std::to_string(zoom) +
                              "'s distortion can undistort (inside its trusted region)",
                          "(" + Significant(u) + ", " + Significant(v) + ")");
  }
  CheckFiniteResult(r, "camera ray");
  return {r.head<3>(), r.tail<3>()};
}

Eigen::Vector3d CalibratedInstrument::CameraPoint(int zoom, double phi, double theta, double u,
                                                  double v, double d) const {
  CheckFinite({d}, "ray length d");
  CameraRay(zoom, phi, theta, u, v, d);  // the checks; F_CAM itself is the model's
  const Eigen::Vector3d x = PredictCam(model_, zoom, phi, theta, u, v, d);
  CheckFiniteResult(x, "camera point");
  return x;
}

Eigen::Vector3d CalibratedInstrument::BoardCorner(int target, int corner,
                                                  const std::string& placement, int zoom) const {
  const EstimatedBoard* b = model_.BoardOf(target, placement, zoom);
  if (!b) {
    std::string where = "target " + std::to_string(target);
    if (!placement.empty()) where += " at placement '" + placement + "'";
    if (zoom >= 0 && model_.kinematics == Kinematics::kNone) {
      where += " at zoom " + std::to_string(zoom);
    }
    throw PredictionError(PredictionFailure::kNoSuchBoard,
                          "a tag of a board the model estimated there (model.yaml boards, with "
                          "their placement)",
                          where);
  }
  if (corner < 0 || corner > 3) {
    throw PredictionError(PredictionFailure::kNoSuchBoard, "a corner 0..3", std::to_string(corner));
  }
  return b->pose.ToRigid() * b->board.CornersInBoard(target - b->board.first_id)[corner];
}

Eigen::Vector2d CalibratedInstrument::BoardCornerPixel(int zoom, double phi, double theta,
                                                       int target, int corner,
                                                       const std::string& placement,
                                                       double focus_distance) const {
  return Pixel(zoom, phi, theta, BoardCorner(target, corner, placement, zoom), focus_distance);
}

Eigen::Vector2d CalibratedInstrument::Pixel(int zoom, double phi, double theta,
                                            const Eigen::Vector3d& x_ref,
                                            double focus_distance) const {
  CheckFinite({phi, theta, x_ref[0], x_ref[1], x_ref[2], focus_distance},
              "readings phi, theta, point X, Y, Z and focus distance");
  CheckCameraDetermined(zoom);
  const CameraTool& cam = model_.cams[zoom];
  const Eigen::Vector3d x_cam = RefFromCam(model_, zoom, phi, theta).Inverse() * x_ref;
  if (!(x_cam.z() > 0)) {
    throw PredictionError(PredictionFailure::kBehindCamera,
                          "a point in front of zoom " + std::to_string(zoom) + "'s camera",
                          Point(x_ref) + ", at depth " + Significant(x_cam.z()) + " m");
  }
  // Beyond the trusted radius the distortion folds the image back: the
  // projection would be a pixel where the point is not seen.
  const double r = x_cam.head<2>().norm() / x_cam.z();
  const double r_max = MaxTrustedRadius(cam.distortion.data());
  if (!(r < r_max)) {
    throw PredictionError(PredictionFailure::kUntrustedPoint,
                          "a point inside zoom " + std::to_string(zoom) +
                              "'s trusted field of view (tan of the off-axis angle < " +
                              Significant(r_max) + ")",
                          Point(x_ref) + " at " + Significant(r));
  }
  Eigen::Vector2d uv;
  if (!PredictPixel(model_, zoom, phi, theta, x_ref, &uv, focus_distance)) {
    throw PredictionError(PredictionFailure::kBehindCamera,
                          "a point in front of zoom " + std::to_string(zoom) + "'s camera",
                          Point(x_ref));
  }
  CheckFiniteResult(uv, "pixel");
  CheckInImage(cam, zoom, uv[0], uv[1], "a projection");
  return uv;
}

// ---------------------------------------------------------------------------
// Uncertainty: J by central differences in the tangent coordinates, over the
// blocks the prediction depends on; P restricted to them.

namespace {

// Step of one coordinate: 1e-6, relative to values beyond 1 (focal lengths,
// principal points). Central differences then err by ~h^2 (truncation,
// 1e-12 relative) plus eps |f| / h (rounding: 2e-7 px on a 1e3 px pixel,
// against derivatives of ~1e3 px per radian): far below what a covariance
// needs.
double Step(LayoutTangent tangent, double value) {
  if (tangent != LayoutTangent::kEuclidean) return 1e-6;
  return 1e-6 * std::max(1.0, std::abs(value));
}

// The derivatives of a prediction by the parameters of the blocks it
// depends on (those of `use` and the shared ones): their indices into the
// parameter vector and one column each.
template <int N>
void Linearize(
    const InstrumentModel& model, int use,
    const std::function<bool(const InstrumentModel&, Eigen::Matrix<double, N, 1>*)>& evaluate,
    std::vector<int>* index, std::vector<Eigen::Matrix<double, N, 1>>* columns) {
  const std::vector<LayoutBlock> blocks = ParameterLayout(model);
  // One copy of the model without its covariance (N^2 numbers), moved
  // along each coordinate and put back: LayoutPlus changes only the block's
  // stored values, so restoring them restores the model exactly.
  InstrumentModel m = model;
  m.sigmas.covariance.resize(0, 0);
  for (size_t b = 0; b < blocks.size(); ++b) {
    const int u = blocks[b].use;
    if (!(u == kLayoutShared || u == use)) continue;
    double* stored = blocks[b].data(m);
    const std::vector<double> kept(stored, stored + blocks[b].ambient);
    for (int i = 0; i < blocks[b].size; ++i) {
      const double h = Step(blocks[b].tangent, kept[i]);
      Eigen::Matrix<double, N, 1> f[2];
      for (int side = 0; side < 2; ++side) {
        double delta[kNumDistortion] = {};  // the largest block
        delta[i] = side == 0 ? h : -h;
        LayoutPlus(blocks[b], delta, &m);
        const bool evaluated = evaluate(m, &f[side]);
        std::copy(kept.begin(), kept.end(), stored);
        if (!evaluated) {
          throw PredictionError(PredictionFailure::kNonFinite,
                                "a prediction that stays defined when the model moves by its "
                                "finite-difference step",
                                "a failure when '" + blocks[b].name + "' moved");
        }
      }
      index->push_back(blocks[b].offset + i);
      columns->push_back((f[0] - f[1]) / (2 * h));
    }
  }
}

template <int N>
Uncertain<N> Propagate(
    const InstrumentModel& model, const Eigen::MatrixXd& covariance, int use,
    const Eigen::Matrix<double, N, 1>& value,
    const std::function<bool(const InstrumentModel&, Eigen::Matrix<double, N, 1>*)>& evaluate) {
  std::vector<int> index;
  std::vector<Eigen::Matrix<double, N, 1>> columns;
  Linearize<N>(model, use, evaluate, &index, &columns);
  const int n = static_cast<int>(index.size());
  Eigen::Matrix<double, N, Eigen::Dynamic> J(N, n);
  Eigen::MatrixXd P(n, n);
  for (int a = 0; a < n; ++a) {
    J.col(a) = columns[a];
    for (int c = 0; c < n; ++c) P(a, c) = covariance(index[a], index[c]);
  }
  Uncertain<N> out;
  out.value = value;
  out.covariance = J * P * J.transpose();
  return out;
}

void RequireCovariance(bool has) {
  if (!has) {
    throw std::logic_error(
        "the model has no uncertainties (model.yaml `uncertainties: false`); set a parameter "
        "covariance first");
  }
}

}  // namespace

Uncertain<3> CalibratedInstrument::EdmPointWithUncertainty(double phi, double theta,
                                                           double d) const {
  RequireCovariance(has_covariance_);
  const Eigen::Vector3d x = EdmPoint(phi, theta, d);
  return Propagate<3>(model_, covariance_, kLayoutEdmOnly, x,
                      [&](const InstrumentModel& m, Eigen::Vector3d* out) {
                        *out = PredictEdm(m, phi, theta, d);
                        return out->allFinite();
                      });
}

Uncertain<6> CalibratedInstrument::CameraRayWithUncertainty(int zoom, double phi, double theta,
                                                            double u, double v,
                                                            double focus_distance) const {
  RequireCovariance(has_covariance_);
  const Ray r = CameraRay(zoom, phi, theta, u, v, focus_distance);
  Eigen::Matrix<double, 6, 1> value;
  value << r.origin, r.direction;
  return Propagate<6>(model_, covariance_, zoom, value,
                      [&](const InstrumentModel& m, Eigen::Matrix<double, 6, 1>* out) {
                        return RawRay(m, zoom, phi, theta, u, v, focus_distance, out) &&
                               out->allFinite();
                      });
}

Uncertain<2> CalibratedInstrument::PixelWithUncertainty(int zoom, double phi, double theta,
                                                        const Eigen::Vector3d& x_ref,
                                                        double focus_distance) const {
  RequireCovariance(has_covariance_);
  const Eigen::Vector2d uv = Pixel(zoom, phi, theta, x_ref, focus_distance);
  return Propagate<2>(model_, covariance_, zoom, uv,
                      [&](const InstrumentModel& m, Eigen::Vector2d* out) {
                        return PredictPixel(m, zoom, phi, theta, x_ref, out, focus_distance) &&
                               out->allFinite();
                      });
}

Eigen::Matrix<double, 2, Eigen::Dynamic> CalibratedInstrument::PixelJacobian(
    int zoom, double phi, double theta, const Eigen::Vector3d& x_ref, double focus_distance) const {
  Pixel(zoom, phi, theta, x_ref, focus_distance);  // checks the zoom, throws where undefined
  std::vector<int> index;
  std::vector<Eigen::Vector2d> columns;
  Linearize<2>(
      model_, zoom,
      [&](const InstrumentModel& m, Eigen::Vector2d* out) {
        return PredictPixel(m, zoom, phi, theta, x_ref, out, focus_distance) && out->allFinite();
      },
      &index, &columns);
  Eigen::Matrix<double, 2, Eigen::Dynamic> j =
      Eigen::Matrix<double, 2, Eigen::Dynamic>::Zero(2, NumParameters());
  for (size_t a = 0; a < index.size(); ++a) j.col(index[a]) = columns[a];
  return j;
}

}  // namespace rtscalib

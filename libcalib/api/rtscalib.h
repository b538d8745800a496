// The public API for programs that use a calibrated instrument: load the
// model.yaml that `rtscalib --config` wrote and predict with it. This is the
// header a user of the installed library includes (docs/library.md):
//
//   #include <libcalib/api/rtscalib.h>
//   const auto inst = rtscalib::CalibratedInstrument::Load("out/zoom3/model.yaml");
//   Eigen::Vector3d x = inst.EdmPoint(phi, theta, d);
//
// Units (SPEC 1, 2): metres, radians, OpenCV pixels ((0, 0) is the centre of the
// top-left pixel). Readings phi, theta are the instrument's own in either face
// (face 2 is theta > pi); the model knows both faces, so no call takes a face.
//
// Every prediction calls the model's own functions (libcalib/model/kinematics.h,
// libcalib/camera/opencv_model.h), so answers equal `rtscalib predict`'s:
//   EdmPoint(phi, theta, d)       = F_EDM (Klug Eq. 11) = PredictEdm
//   CameraRay(z, phi, theta, u, v): origin = camera centre, direction = unit ray
//                                   through (u, v); origin + d direction =
//                                   F_CAM (Klug Eq. 12, SPEC 2) = PredictCam
//   CameraPoint(z, phi, theta, u, v, d) = PredictCam (F_CAM itself)
//   Pixel(z, phi, theta, X)       = project(cam_from_ref X) (Klug Eq. 62) = PredictPixel
// With the `focus` effect (SPEC 4.1) the camera's intrinsics depend on the
// focus distance D [m]: CameraPoint uses D = d (F_CAM); Pixel and
// CameraRay take D as an optional last argument. Pixel's default (0) is the
// point's own distance from the camera; a photo's pixels are those at the
// photo's D (its focus_distance, or the distance to the centroid of the
// points it shows: `rtscalib predict --pixels` does that). CameraRay's
// default (0) is the camera focused at infinity; CameraRay(.., D).At(D) is
// CameraPoint(.., D). Without the effect D plays no role.
// A prediction that the model cannot make throws PredictionError saying why
// (no such zoom, pixel outside the image by more than kImageMargin, pixel or
// point outside the distortion's trusted region, point behind the camera,
// non-finite result) instead of returning a number nobody should use.
//
// Uncertainty: first-order propagation
//   covariance(prediction) = J P J^T,   J = d prediction / d p  (central differences)
// over the model's parameter vector p (ParameterBlocks(): tangent coordinates
// of the same manifolds the fit uses, libcalib/fit/parameter_layout.h). P is
// the fit's full joint covariance when covariance.yaml lies beside model.yaml
// (a run writes it; HasFullParameterCovariance()), correlations included.
// Without it, P is built from model.yaml's one sigma per parameter (and each
// effect's own 2x2 block): diagonal otherwise, an APPROXIMATION that ignores
// the fit's correlations (they can make the true uncertainty larger or
// smaller). SetParameterCovariance replaces P.
#pragma once

#include <Eigen/Core>
#include <stdexcept>
#include <string>
#include <vector>

#include "libcalib/model/instrument.h"

namespace rtscalib {

// Why a prediction was refused.
enum class PredictionFailure {
  kNoSuchZoom,      // zoom level not in the model
  kNotDetermined,   // the tool (EDM, or this zoom's camera) had no calibration data
  kOutsideImage,    // pixel beyond the image by more than kImageMargin
  kUntrustedPixel,  // pixel cannot be undistorted (outside the trusted region)
  kBehindCamera,    // point on or behind the image plane
  kUntrustedPoint,  // point outside the distortion's trusted region (image would fold)
  kNonFinite,       // NaN or infinity in the readings or the result
  kNoSuchBoard,     // the tag is on no board the model estimated (SPEC 7)
};
// what() is one sentence; expected/got are its parts for messages that name a
// file, line and column (`rtscalib predict`, text/errors.h style).
struct PredictionError : std::runtime_error {
  PredictionError(PredictionFailure why, const std::string& expected_text,
                  const std::string& got_text)
      : std::runtime_error("expected " + expected_text + ", got " + got_text),
        failure(why),
        expected(expected_text),
        got(got_text) {}
  PredictionFailure failure;
  std::string expected;
  std::string got;
};

// How far beyond the image a pixel may lie, as a fraction of the image's width
// (for u) and height (for v): the distortion was fitted on points inside the
// image, so it is trusted a little beyond its border and not further.
constexpr double kImageMargin = 0.1;

// A ray in the reference frame: origin [m] and unit direction.
struct Ray {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d At(double length) const { return origin + length * direction; }
};

// A prediction and its first-order covariance (units of value squared).
template <int N>
struct Uncertain {
  Eigen::Matrix<double, N, 1> value;
  Eigen::Matrix<double, N, N> covariance;
  // Standard deviation of each component.
  Eigen::Matrix<double, N, 1> Sigma() const { return covariance.diagonal().cwiseSqrt(); }
};

// One block of the parameter vector p: name as in the fit ("base.rotation",
// "link1", "edm.t", "hz_eccentricity", "cam[0].intrinsics", ...), where it
// starts in p, how many coordinates, and their unit.
//   *.rotation of base and cam[z]: Ceres' EigenQuaternionManifold tangent,
//       q -> exp(delta) q with rotation angle 2 |delta| [rad] (what the fit's
//       sigma.rotation of these blocks is the deviation of)
//   edm.rotation: 2 coordinates, q -> q exp([d0, d1, 0]) (angle |delta|, no roll)
//   everything else: the block's own values (model.yaml order and units)
struct ParameterBlock {
  std::string name;
  int offset = 0;
  int size = 0;
  std::string unit;
};

class CalibratedInstrument {
 public:
  // Reads model.yaml (libcalib/io/model_io.h) and, when present, the
  // covariance.yaml beside it (beside the file model.yaml's symlinks resolve
  // to, so that both come from one run; libcalib/io/covariance_io.h); throws
  // InputError naming file and key for anything malformed, or for a
  // covariance.yaml that belongs to another model.
  static CalibratedInstrument Load(const std::string& model_yaml);
  explicit CalibratedInstrument(InstrumentModel model);

  const InstrumentModel& Model() const { return model_; }
  int NumZooms() const { return model_.NumZooms(); }
  // Image size of a zoom level [px]; throws PredictionError for an unknown zoom.
  int ImageWidth(int zoom) const;
  int ImageHeight(int zoom) const;

  // The point the EDM measures at distance d [m] for readings phi, theta [rad].
  Eigen::Vector3d EdmPoint(double phi, double theta, double d) const;
  // The line of sight of pixel (u, v) of zoom level `zoom`, the camera
  // focused at `focus_distance` [m] (<= 0: at infinity; header).
  Ray CameraRay(int zoom, double phi, double theta, double u, double v,
                double focus_distance = 0) const;
  // The point at ray length d [m] through pixel (u, v): F_CAM, what
  // `rtscalib predict --records` writes for a cam row (= CameraRay(..).At(d)
  // up to rounding).
  Eigen::Vector3d CameraPoint(int zoom, double phi, double theta, double u, double v,
                              double d) const;
  // The pixel at which zoom level `zoom` sees the reference-frame point x_ref,
  // the camera focused at `focus_distance` [m] (<= 0: at the point's own
  // distance; header).
  Eigen::Vector2d Pixel(int zoom, double phi, double theta, const Eigen::Vector3d& x_ref,
                        double focus_distance = 0) const;
  // SPEC 7: corner `corner` (0..3) of tag `target` of a board the model
  // estimated (ref_from_board * TagBoard::CornersInBoard), in the reference
  // frame, as the board stood in `placement` (SPEC 7.1; "" for a session
  // without placements) and, for a camera-only model whose board poses are
  // per zoom, as zoom `zoom` saw it (-1: a pose of every zoom); throws
  // PredictionError (kNoSuchBoard) when no estimated board pose holds the
  // tag there or the corner is not 0..3.
  Eigen::Vector3d BoardCorner(int target, int corner, const std::string& placement = "",
                              int zoom = -1) const;
  // The pixel at which zoom level `zoom` sees that corner
  // (= Pixel(zoom, phi, theta, BoardCorner(target, corner, placement, zoom))).
  Eigen::Vector2d BoardCornerPixel(int zoom, double phi, double theta, int target, int corner,
                                   const std::string& placement = "",
                                   double focus_distance = 0) const;

  // The same with first-order covariances (header). The ray's value is
  // [origin; direction] (6 values: metres, then unitless). Throw
  // std::logic_error when the model has no uncertainties.
  Uncertain<3> EdmPointWithUncertainty(double phi, double theta, double d) const;
  Uncertain<6> CameraRayWithUncertainty(int zoom, double phi, double theta, double u, double v,
                                        double focus_distance = 0) const;
  Uncertain<2> PixelWithUncertainty(int zoom, double phi, double theta,
                                    const Eigen::Vector3d& x_ref,
                                    double focus_distance = 0) const;

  // The derivatives of Pixel(zoom, phi, theta, x_ref, focus_distance) by
  // the parameters of ParameterBlocks() (2 x NumParameters(), zero where the
  // pixel does not depend on one): what PixelWithUncertainty propagates the
  // covariance with. Needs no covariance.
  Eigen::Matrix<double, 2, Eigen::Dynamic> PixelJacobian(int zoom, double phi, double theta,
                                                         const Eigen::Vector3d& x_ref,
                                                         double focus_distance = 0) const;

  // The parameter vector the covariance refers to.
  const std::vector<ParameterBlock>& ParameterBlocks() const { return blocks_; }
  int NumParameters() const;
  // Index of a block by name; throws std::out_of_range if there is none.
  const ParameterBlock& Block(const std::string& name) const;
  bool HasParameterCovariance() const { return has_covariance_; }
  // Whether P is a full covariance (covariance.yaml or SetParameterCovariance),
  // not the diagonal approximation from model.yaml's sigmas.
  bool HasFullParameterCovariance() const { return full_covariance_; }
  const Eigen::MatrixXd& ParameterCovariance() const { return covariance_; }
  // Replaces P (NumParameters() square, symmetric); throws std::invalid_argument
  // for a wrong size or a non-finite entry.
  void SetParameterCovariance(const Eigen::MatrixXd& covariance);
  // The model moved by `delta` in the tangent coordinates of ParameterBlocks().
  InstrumentModel Plus(const Eigen::VectorXd& delta) const;

 private:
  void CheckZoom(int zoom) const;
  // CheckZoom, and the zoom's camera was determined by the calibration data.
  void CheckCameraDetermined(int zoom) const;
  InstrumentModel model_;
  std::vector<ParameterBlock> blocks_;
  Eigen::MatrixXd covariance_;
  bool has_covariance_ = false;
  bool full_covariance_ = false;
};

}  // namespace rtscalib

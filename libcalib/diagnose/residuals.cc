#include "libcalib/diagnose/residuals.h"

#include <cmath>
#include <cstdio>

#include "libcalib/camera/opencv_model.h"
#include "libcalib/model/focus.h"
#include "libcalib/fit/unknowns.h"
#include "libcalib/model/kinematics.h"

namespace rtscalib {
namespace {

// Horizontal-direction and zenith components of a small change `delta` of a
// direction `dir` (unit), both in radians of arc on the unit sphere.
void AngularComponents(const Eigen::Vector3d& dir, const Eigen::Vector3d& delta, double* dhz,
                       double* dz) {
  const double hz = std::atan2(dir.x(), dir.y());
  const double z = std::acos(std::clamp(dir.z(), -1.0, 1.0));
  const double sz = std::max(std::sin(z), 1e-9);
  *dhz = delta.dot(Eigen::Vector3d(std::cos(hz), -std::sin(hz), 0.0)) / sz;
  *dz = delta.dot(
      Eigen::Vector3d(std::sin(hz) * std::cos(z), std::cos(hz) * std::cos(z), -std::sin(z)));
}

}  // namespace

std::vector<ObservationResidual> ObservationResiduals(const Observations& obs,
                                                      const InstrumentModel& model,
                                                      const FitOptions& fit) {
  std::vector<ObservationResidual> out;
  out.reserve(obs.records.size() + obs.pixels.size());
  for (size_t i = 0; i < obs.records.size(); ++i) {
    const Record& r = obs.records[i];
    ObservationResidual o;
    o.group = r.tool == Tool::kEdm ? ObsGroup::kEdm : ObsGroup::kCam;
    o.index = static_cast<int>(i);
    o.face = r.face;
    o.zoom = r.tool == Tool::kEdm ? 0 : r.zoom;
    o.phi = r.phi;
    o.theta = r.theta;
    o.d = r.d;
    o.u = r.u;
    o.v = r.v;
    o.critical = fit.critical_region.Contains(r.theta);
    try {
      Eigen::Vector3d calc, origin;
      if (r.tool == Tool::kEdm) {
        calc = PredictEdm(model, r.phi, r.theta, r.d);
        origin = RefFromEdm(model, r.phi, r.theta).translation;
      } else {
        calc = PredictCam(model, r.zoom, r.phi, r.theta, r.u, r.v, r.d);
        origin = RefFromCam(model, r.zoom, r.phi, r.theta).translation;
      }
      const Eigen::Vector3d ray = calc - origin;
      const double len = ray.norm();
      if (len > 0) {
        const Eigen::Vector3d dir = ray / len;
        o.delta = r.x - calc;
        o.along = o.delta.dot(dir);
        AngularComponents(dir, o.delta / len, &o.hz, &o.zenith);
        o.size = o.delta.norm();
        o.observed = r.x;
        o.predicted = calc;
        o.target_distance = (r.x - origin).norm();
        o.valid = true;
      }
      if (r.tool == Tool::kCam && r.zoom >= 0 && r.zoom < model.NumZooms()) {
        const CameraTool& cam = model.cams[r.zoom];
        o.image_radius = std::hypot(r.u - cam.intrinsics[2], r.v - cam.intrinsics[3]);
        Eigen::Vector2d pred;
        if (PredictPixel(model, r.zoom, r.phi, r.theta, r.x, &pred))
          o.image_delta = Eigen::Vector2d(r.u, r.v) - pred;
      }
    } catch (const std::exception&) {
      o.valid = false;
    }
    out.push_back(o);
  }
  const std::vector<double> focus = PredictionFocusDistances(model, obs.pixels, &obs.targets);
  for (size_t i = 0; i < obs.pixels.size(); ++i) {
    const PixelObservation& p = obs.pixels[i];
    ObservationResidual o;
    o.group = ObsGroup::kPixel;
    o.index = static_cast<int>(i);
    o.face = p.face;
    o.zoom = p.zoom;
    o.phi = p.phi;
    o.theta = p.theta;
    o.u = p.uv.x();
    o.v = p.uv.y();
    o.critical = fit.critical_region.Contains(p.theta);
    Eigen::Vector2d pred;
    if (p.zoom >= 0 && p.zoom < model.NumZooms() &&
        PredictPixel(model, p.zoom, p.phi, p.theta, p.X, &pred, focus[i])) {
      const CameraTool& cam = model.cams[p.zoom];
      const Rigid3 ref_from_cam = RefFromCam(model, p.zoom, p.phi, p.theta);
      // The photo's intrinsics (SPEC 4.1: focused at its D, else at the point).
      double k[kNumIntrinsics];
      const double distance =
          focus[i] > 0 ? focus[i] : (p.X - ref_from_cam.translation).norm();
      double ray_obs[3], ray_pred[3];
      if (FocusedIntrinsics(cam.intrinsics.data(), FocusOf(model, p.zoom), distance, k) &&
          PixelToRay(k, cam.distortion.data(), p.uv.data(), ray_obs) &&
          PixelToRay(k, cam.distortion.data(), pred.data(), ray_pred)) {
        // A camera on its own (Kinematics::kNone) has its own frame as the
        // reference, z along the optical axis: there is no horizontal
        // direction or zenith angle, and taking that axis for the vertical
        // would divide the horizontal component by the distance from the
        // principal point (hundreds of arc seconds for 0.2 px near the
        // centre). Its residuals are the pixel ones (image_delta).
        if (model.kinematics == Kinematics::kNone) {
          o.hz = o.zenith = std::nan("");
        } else {
          const Eigen::Matrix3d rot = ref_from_cam.rotation;
          const Eigen::Vector3d a = rot * Eigen::Vector3d(ray_obs).normalized();
          const Eigen::Vector3d b = rot * Eigen::Vector3d(ray_pred).normalized();
          AngularComponents(b, a - b, &o.hz, &o.zenith);
        }
        o.delta = Eigen::Vector3d(p.uv.x() - pred.x(), p.uv.y() - pred.y(), 0.0);
        o.size = o.delta.norm();
        o.image_delta = p.uv - pred;
        o.observed = Eigen::Vector3d(p.uv.x(), p.uv.y(), 0.0);
        o.predicted = Eigen::Vector3d(pred.x(), pred.y(), 0.0);
        o.target_distance = (p.X - RefFromCam(model, p.zoom, p.phi, p.theta).translation).norm();
        o.image_radius = std::hypot(p.uv.x() - cam.intrinsics[2], p.uv.y() - cam.intrinsics[3]);
        o.valid = true;
      }
    }
    out.push_back(o);
  }
  return out;
}

const char* ResidualStatusName(ResidualStatus s) {
  switch (s) {
    case ResidualStatus::kFitted:
      return "fitted";
    case ResidualStatus::kCriticalRegion:
      return "critical_region";
    case ResidualStatus::kGrossError:
      return "gross_error";
    case ResidualStatus::kNotPredicted:
      return "not_predicted";
  }
  return "?";
}

std::vector<ObservationResidual> ResidualTable(const Observations& obs,
                                               const InstrumentModel& model, const FitOptions& fit,
                                               const FitSummary& summary,
                                               const std::vector<ExcludedRow>& gross) {
  // The boards and points of unknown position at the model's estimate:
  // the rows' positions as the fit placed them.
  std::vector<ObservationResidual> out =
      ObservationResiduals(WithEstimates(obs, model), model, fit);
  const double sigma_edm = summary.sigma_edm_m > 0 ? summary.sigma_edm_m : fit.sigma_edm_m;
  const double sigma_cam = summary.sigma_cam_m > 0 ? summary.sigma_cam_m : fit.sigma_cam_m;
  const double sigma_px = summary.sigma_pixel_px > 0 ? summary.sigma_pixel_px : fit.sigma_pixel_px;
  const size_t num_records = obs.records.size();
  for (ObservationResidual& o : out) {
    if (o.group == ObsGroup::kPixel) {
      const PixelObservation& p = obs.pixels[o.index];
      o.line = p.line;
      o.shot = p.shot;
      o.placement = p.placement;
      o.target = p.target;
      o.corner = p.corner;
      const bool zoom_sigma = p.zoom >= 0 &&
                              p.zoom < static_cast<int>(summary.sigma_pixel_px_zoom.size()) &&
                              summary.sigma_pixel_px_zoom[p.zoom] > 0;
      o.sigma = zoom_sigma ? summary.sigma_pixel_px_zoom[p.zoom] : sigma_px;
    } else {
      const Record& r = obs.records[o.index];
      o.line = r.line;
      o.point = r.point;
      o.sigma = o.group == ObsGroup::kEdm ? sigma_edm : sigma_cam;
    }
    if (o.valid && o.sigma > 0) o.normalised = o.size / o.sigma;
    if (!o.valid) {
      o.status = ResidualStatus::kNotPredicted;
      o.reason = "the model cannot predict it (point behind the camera or outside its image model)";
    } else if (o.critical) {
      o.status = ResidualStatus::kCriticalRegion;
      o.reason =
          "zenith angle in a critical region (critical_region.min_zenith_deg, max_zenith_deg)";
    }
  }
  for (const ExcludedRow& e : gross) {
    const size_t i = e.pixel ? num_records + e.index : e.index;
    if (i >= out.size()) continue;
    out[i].status = ResidualStatus::kGrossError;
    out[i].reason = e.reason;
  }
  return out;
}

std::string Where(const Observations& obs, ObsGroup group, int index) {
  char buf[256];
  if (group == ObsGroup::kPixel) {
    const PixelObservation& p = obs.pixels[index];
    std::snprintf(buf, sizeof(buf), "shot %s, target %d corner %d", p.shot.c_str(), p.target,
                  p.corner);
    if (p.line > 0) return obs.pixels_source + ":" + std::to_string(p.line) + " (" + buf + ")";
    return obs.pixels_source + ", row " + std::to_string(index + 1) + " (" + buf + ")";
  }
  const Record& r = obs.records[index];
  std::snprintf(buf, sizeof(buf), "%s, face %d, phi %.2f deg, theta %.2f deg, d %.3g m",
                r.tool == Tool::kEdm ? "edm" : "cam", r.face, r.phi * 180 / M_PI,
                r.theta * 180 / M_PI, r.d);
  if (r.line > 0) return obs.records_source + ":" + std::to_string(r.line) + " (" + buf + ")";
  return obs.records_source + ", row " + std::to_string(index + 1) + " (" + buf + ")";
}

}  // namespace rtscalib

#include "libcalib/extract/joint_features.h"

#include <cmath>
#include <limits>
#include <sstream>

#include "libcalib/geometry/fits.h"

namespace rtscalib {

const char* TrajectoryName(Trajectory t) {
  switch (t) {
    case Trajectory::kCircle:
      return "circle";
    case Trajectory::kLine:
      return "line";
    case Trajectory::kOnAxis:
      return "on axis";
    case Trajectory::kNeither:
      return "neither circle nor line";
  }
  return "?";
}

JointFeature AnalyseSweep(const std::vector<Record>& records, const Sweep& sweep,
                          const ExtractOptions& options) {
  JointFeature f;
  f.joint = sweep.joint;
  f.num_points = sweep.NumPoints();
  std::vector<Eigen::Vector3d> pts;
  pts.reserve(sweep.rows.size());
  for (int i : sweep.rows) pts.push_back(records[i].x);
  if (pts.size() < 3) {
    f.trajectory = Trajectory::kNeither;
    return f;
  }

  const LineFit line = FitLine(pts);
  const CircleFit circle = FitCircle(pts);
  f.line_rms = line.rms;
  f.circle_rms = circle.rms;
  f.plane_rms = circle.plane.rms;
  f.radius = circle.radius;
  for (const auto& p : pts) f.spread = std::max(f.spread, (p - line.point).norm());

  if (f.spread < options.min_radius_m) {
    f.trajectory = Trajectory::kOnAxis;
    f.center = line.point;
    return f;
  }
  if (line.rms <= options.max_fit_rms_m) {
    f.trajectory = Trajectory::kLine;
    f.center = line.point;
    f.axis = CorrectDirectionSign(line.direction, pts.front(), pts.back());
    f.sign_rows[0] = sweep.rows.front();
    f.sign_rows[1] = sweep.rows.back();
    return f;
  }
  if (!circle.valid || circle.rms > options.max_fit_rms_m) {
    f.trajectory = Trajectory::kNeither;
    f.center = circle.valid ? circle.center : line.point;
    return f;
  }
  f.center = circle.center;
  if (circle.radius < options.min_radius_m) {
    f.trajectory = Trajectory::kOnAxis;
    return f;
  }
  f.trajectory = Trajectory::kCircle;
  // Eq. 31 with the best-conditioned consecutive pair less than pi apart.
  double best = -1.0;
  int best_k = -1;
  for (int k = 0; k + 1 < f.num_points; ++k) {
    const double delta = sweep.Control(records, k + 1) - sweep.Control(records, k);
    if (!(delta > 0.0 && delta < M_PI)) continue;
    const double s =
        std::abs((pts[k] - circle.center).cross(pts[k + 1] - circle.center).dot(circle.normal));
    if (s > best) {
      best = s;
      best_k = k;
    }
  }
  if (best_k < 0) {
    // Every step is >= pi: the rotation sense is not observable.
    f.trajectory = Trajectory::kNeither;
    return f;
  }
  f.axis = CorrectNormalSign(circle.normal, circle.center, pts[best_k], pts[best_k + 1]);
  f.sign_rows[0] = sweep.rows[best_k];
  f.sign_rows[1] = sweep.rows[best_k + 1];
  return f;
}

void RequireRevolute(const JointFeature& f, const Sweep& sweep, const std::vector<Record>& records,
                     const ExtractOptions& options) {
  if (f.trajectory == Trajectory::kCircle) return;
  std::ostringstream s;
  s.precision(3);
  s << "cannot extract joint " << f.joint << " from its " << sweep.Describe(records) << ": ";
  const char* other = f.joint == 1 ? "theta" : "phi";
  switch (f.trajectory) {
    case Trajectory::kOnAxis:
      s << "the recorded point lies on the joint axis (points spread " << f.spread
        << " m, circle radius " << f.radius << " m, fit RMS " << f.circle_rms
        << " m; need a radius of at least " << options.min_radius_m
        << " m), so the axis direction is not observable. Remedy (Klug et al. footnote 4): "
           "record points that do not coincide with the end effector origin, e.g. a longer "
           "EDM distance or a pixel off the principal point, or repeat the sweep with another "
           "fixed "
        << other << (f.joint == 1 ? " (e.g. pi/2)" : "") << ".";
      break;
    case Trajectory::kLine:
      s << "the points lie on a line (line fit RMS " << f.line_rms
        << " m): a prismatic joint, but the instrument model has revolute joints only. If the "
           "joint is revolute, the sweep does not turn it: check that "
        << (f.joint == 1 ? "phi" : "theta") << " really varies in these rows.";
      break;
    case Trajectory::kNeither:
    default:
      s << "the points lie neither on a circle (fit RMS " << f.circle_rms << " m) nor on a line "
        << "(fit RMS " << f.line_rms << " m); the tolerance is " << options.max_fit_rms_m
        << " m (ExtractOptions::max_fit_rms_m). The joint is not revolute or prismatic, the rows "
           "do not come from one joint sweep, or the end effector coincides with the rotation "
           "axis. Remedy (Klug et al. Sec. 3.1.2, footnote 4): repeat the recording with other "
           "fixed joint settings (another "
        << other
        << "), or record points that do not coincide with the end effector origin, e.g. a "
           "longer EDM distance or a pixel off the principal point.";
      break;
  }
  throw ExtractionError(s.str());
}

}  // namespace rtscalib

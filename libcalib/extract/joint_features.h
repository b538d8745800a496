// The feature of one joint from its sweep (Klug et al. Sec. 3.1.2-3.1.4): the
// recorded end-effector points are fitted with a line and a circle
// (libcalib/geometry/fits.h) and classified
//   on axis  the points' spread or the circle radius is below min_radius_m:
//            the recorded point lies on the joint axis (footnote 4);
//   line     line-fit RMS <= max_fit_rms_m: a prismatic joint;
//   circle   circle-fit RMS <= max_fit_rms_m: a revolute joint; the axis is
//            the circle's normal through its centre, sign-corrected by Eq. 31;
//   neither  otherwise.
// The sign of Eq. 31 uses two consecutive samples in increasing control order
// less than pi apart (footnote 6); of all such pairs the one with the largest
// |((x_1 - c) x (x_2 - c))^T n| (the best-conditioned sign) is taken.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "libcalib/extract/options.h"
#include "libcalib/extract/sweeps.h"
#include "libcalib/geometry/lines.h"
#include "libcalib/model/observations.h"

namespace rtscalib {

enum class Trajectory { kCircle, kLine, kOnAxis, kNeither };
const char* TrajectoryName(Trajectory t);

struct JointFeature {
  int joint = 1;
  Trajectory trajectory = Trajectory::kNeither;
  int num_points = 0;
  // Circle: centre c (Eq. 30) and sign-corrected normal n~ (Eq. 31), the joint
  // axis L = c + s n~. Line: the centroid and the direction of increasing control.
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  double radius = 0.0;          // circle radius r (Eq. 30) [m]; +inf when the circle fit fails
  double circle_rms = 0.0;      // RMS distance of the points to the circle [m]
  double plane_rms = 0.0;       // RMS distance of the points to the plane [m]
  double line_rms = 0.0;        // RMS distance of the points to the fitted line [m]
  double spread = 0.0;          // largest distance of a point from the centroid [m]
  int sign_rows[2] = {-1, -1};  // record indices used for the sign (Eq. 31)
  // Constellation of this joint's axis with the next one's (Eq. 40/47); for
  // the last joint, with itself (Eq. 50: identical). Filled by the frames.
  LineConstellation constellation = LineConstellation::kIdentical;
  double next_axis_distance = 0.0;  // closest distance to the next axis [m]
  double next_axis_angle = 0.0;     // angle between this axis and the next [rad]
};

// Fits and classifies; never throws for bad geometry (see RequireRevolute).
JointFeature AnalyseSweep(const std::vector<Record>& records, const Sweep& sweep,
                          const ExtractOptions& options);

// Throws ExtractionError unless the feature is a circle (a revolute joint):
// the message names the sweep, its number of points and fit residuals, and
// the paper's remedy (footnote 4: record points that do not coincide with the
// end effector origin, or repeat with other fixed joint settings).
void RequireRevolute(const JointFeature& feature, const Sweep& sweep,
                     const std::vector<Record>& records, const ExtractOptions& options);

}  // namespace rtscalib

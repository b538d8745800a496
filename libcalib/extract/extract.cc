#include "libcalib/extract/extract.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "libcalib/extract/tools.h"
#include "libcalib/text/number_text.h"

namespace rtscalib {
namespace {

std::string NoSweepMessage(int joint, const SweepSearch& search, const ExtractOptions& o) {
  std::ostringstream s;
  s << "no joint-" << joint << " sweep found: need at least " << o.min_sweep_points
    << " usable rows (face 1, zenith in ["
    << Significant(o.critical_region.min_zenith_rad * 180 / M_PI, 4) << ", "
    << Significant(o.critical_region.max_zenith_rad * 180 / M_PI, 4)
    << "] deg) of one tool, distance and pixel with "
    << (joint == 1 ? "the same theta and different phi" : "the same phi and different theta")
    << " (Klug Sec. 3.1.2: "
    << (joint == 1 ? "theta = pi/2, phi over [0, 2 pi)" : "phi = 0, theta over [0, pi]") << "). "
    << search.usable.size() << " rows were usable; " << search.excluded.face2 << " face-2 rows and "
    << search.excluded.critical_zenith << " rows in the critical zenith regions were excluded.";
  return s.str();
}

std::string DescribeFeature(const JointFeature& f) {
  std::ostringstream s;
  s << "joint " << f.joint << ": " << TrajectoryName(f.trajectory) << " through " << f.num_points
    << " points, centre (" << Significant(f.center.x()) << ", " << Significant(f.center.y()) << ", "
    << Significant(f.center.z()) << ") m, axis (" << Significant(f.axis.x()) << ", "
    << Significant(f.axis.y()) << ", " << Significant(f.axis.z()) << "), radius "
    << Significant(f.radius) << " m, circle fit RMS " << Significant(f.circle_rms, 3) << " m";
  return s.str();
}

}  // namespace

ExtractionResult ExtractDhModel(const std::vector<Record>& records,
                                const std::vector<CameraTool>& cameras,
                                const ExtractOptions& options) {
  if (const std::string err = options.Check(); !err.empty()) {
    throw std::invalid_argument("ExtractOptions: " + err);
  }
  ExtractionResult out;
  std::vector<std::string>& notes = out.notes;

  // 1. Sweeps.
  out.principal_points = FindPrincipalPoints(records, cameras, options);
  const SweepSearch search = FindSweeps(records, out.principal_points, options);
  out.excluded = search.excluded;
  out.usable_rows = static_cast<int>(search.usable.size());
  out.candidate_sweeps = search.candidates;
  notes.push_back(std::to_string(records.size()) +
                  " records: " + std::to_string(search.usable.size()) + " usable, " +
                  std::to_string(search.excluded.face2) + " face-2 rows not used, " +
                  std::to_string(search.excluded.critical_zenith) +
                  " face-1 rows excluded in the critical zenith regions");
  if (!search.joint1) throw ExtractionError(NoSweepMessage(1, search, options));
  if (!search.joint2) throw ExtractionError(NoSweepMessage(2, search, options));
  out.sweeps = {*search.joint1, *search.joint2};
  for (const Sweep& s : out.sweeps) notes.push_back("using the " + s.Describe(records));

  // 2. Joint features.
  for (int j = 0; j < 2; ++j) {
    out.joints[j] = AnalyseSweep(records, out.sweeps[j], options);
    RequireRevolute(out.joints[j], out.sweeps[j], records, options);
    notes.push_back(DescribeFeature(out.joints[j]));
  }

  // 3. Frames.
  const Line3 axis1{out.joints[0].center, out.joints[0].axis};
  const Line3 axis2{out.joints[1].center, out.joints[1].axis};
  ClosestPoints cp12, cp23;
  out.frames[0] = FirstFrame(axis1);
  out.frames[1] = NextFrame(out.frames[0], axis2, options.axis_tolerances, &cp12);
  out.frames[2] = NextFrame(out.frames[1], Line3{out.frames[1].o, out.frames[1].z},
                            options.axis_tolerances, &cp23);
  out.joints[0].constellation = cp12.constellation;
  out.joints[0].next_axis_distance = cp12.distance;
  const Eigen::Vector3d& z1 = out.frames[0].z;
  const Eigen::Vector3d& z2 = out.frames[1].z;
  out.joints[0].next_axis_angle = std::atan2(z1.cross(z2).norm(), z1.dot(z2));
  out.joints[1].constellation = cp23.constellation;
  notes.push_back(std::string("axes 1 and 2: ") + LineConstellationName(cp12.constellation) +
                  ", closest distance " + Significant(cp12.distance, 3) + " m, angle " +
                  Significant(out.joints[0].next_axis_angle * 180 / M_PI, 8) + " deg");

  // 4. DH parameters.
  InstrumentModel& m = out.model;
  m.kinematics = Kinematics::kDh;
  const std::array<double, 4> link1 = DhParametersBetween(out.frames[0], out.frames[1]);
  const std::array<double, 4> link2 = DhParametersBetween(out.frames[1], out.frames[2]);
  const double phi2 = out.sweeps[1].constant_control;
  m.links[0].p = link1;
  m.links[0].p[kDhGamma] = WrapAngle(link1[kDhGamma] - phi2);
  m.links[1].p = link2;
  notes.push_back("link 1 (Eq. 49, a along x_2): d = " + Significant(link1[kDhD]) +
                  " m, gamma = phi + " + Significant(m.links[0].p[kDhGamma]) +
                  " rad (gamma_1 = " + Significant(link1[kDhGamma]) +
                  " at phi = " + Significant(phi2) + "), alpha = " + Significant(link1[kDhAlpha]) +
                  " rad, a = " + Significant(link1[kDhA]) + " m");
  notes.push_back("link 2: frame 3 = frame 2 (Eq. 50), {d, gamma, alpha, a} = {" +
                  Significant(link2[0]) + ", " + Significant(link2[1]) + ", " +
                  Significant(link2[2]) + ", " + Significant(link2[3]) +
                  "}; the tool transforms carry the rest");

  // 5. Base and tools.
  m.base = PoseBlock::FromRigid(BaseFromFirstFrame(out.frames[0]));
  const int num_zooms = static_cast<int>(out.principal_points.size());
  m.cams.assign(num_zooms, CameraTool{});
  out.camera_poses.assign(num_zooms, 0);
  int reference_zoom = -1;
  for (int z = 0; z < num_zooms; ++z) {
    const CameraTool* given = z < static_cast<int>(cameras.size()) ? &cameras[z] : nullptr;
    if (given) m.cams[z] = *given;
    if (!out.principal_points[z]) {
      notes.push_back("zoom " + std::to_string(z) +
                      ": no camera given and no usable camera rows; its camera is left at the "
                      "defaults");
      continue;
    }
    const auto cam =
        ExtractCameraTool(records, search.usable, m, z, *out.principal_points[z], given, options);
    if (!cam) {
      notes.push_back("zoom " + std::to_string(z) +
                      ": no usable camera rows; its flange_from_cam is left as configured");
      continue;
    }
    m.cams[z] = cam->camera;
    out.camera_poses[z] = cam->poses;
    notes.push_back(cam->note);
    if (reference_zoom < 0) reference_zoom = z;
  }
  const auto edm = ExtractEdmTool(records, search.usable, m, reference_zoom, options);
  if (edm) {
    m.edm = edm->flange_from_edm;
    out.edm_poses = edm->poses;
    notes.push_back("EDM tool: " + std::to_string(edm->poses) + " poses, x axis from " +
                    edm->x_reference + " (Eq. 79), alignment RMS " + Significant(edm->rms, 3) +
                    " m");
  } else {
    notes.push_back(
        "EDM tool: no usable pose has EDM rows at two distances (Eq. 78); flange_from_edm left "
        "at identity");
  }
  return out;
}

}  // namespace rtscalib

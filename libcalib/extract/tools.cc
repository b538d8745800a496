#include "libcalib/extract/tools.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

#include "libcalib/camera/opencv_model.h"
#include "libcalib/extract/dh_frames.h"
#include "libcalib/geometry/kabsch.h"
#include "libcalib/model/kinematics.h"
#include "libcalib/text/number_text.h"

namespace rtscalib {
namespace {

// RobustKabsch's floor: correspondences within 0.1 mm of the robust fit are
// always kept (exact data leave round-off, which no robust sigma should cut).
constexpr double kKabschFloorM = 1e-4;

double AngleDiff(double a, double b) { return std::abs(WrapAngle(a - b)); }

// Rows taken at the same pointing (phi modulo 2 pi) within the tolerance:
// each row joins the first pose (in order of creation) whose first row is
// within `tol` in phi and theta, else starts a pose. The poses are found
// through a grid of cells of `tol` (a match lies in a neighbouring cell),
// so the cost is linear in the rows (it was rows x poses: a quarter of a
// million-row calibration's time).
std::vector<std::vector<int>> GroupByPose(const std::vector<Record>& records,
                                          const std::vector<int>& rows, double tol) {
  std::vector<std::vector<int>> poses;
  const double cell = std::max(tol, 1e-12);
  const long long phi_cells = std::max(1LL, static_cast<long long>(std::floor(2 * M_PI / cell)));
  auto phi_cell = [&](double phi) {
    double p = std::fmod(phi, 2 * M_PI);
    if (p < 0) p += 2 * M_PI;
    return std::min(phi_cells - 1, static_cast<long long>(p / cell));
  };
  std::map<std::pair<long long, long long>, std::vector<int>> grid;  // cell -> poses
  for (int i : rows) {
    const Record& r = records[i];
    const long long pc = phi_cell(r.phi);
    const long long tc = static_cast<long long>(std::floor(r.theta / cell));
    int found = -1;
    for (long long dp = -1; dp <= 1; ++dp) {
      for (long long dt = -1; dt <= 1; ++dt) {
        const auto it = grid.find({((pc + dp) % phi_cells + phi_cells) % phi_cells, tc + dt});
        if (it == grid.end()) continue;
        for (int pose : it->second) {
          if (found >= 0 && pose >= found) break;  // poses in a cell ascend
          const Record& p = records[poses[pose].front()];
          if (AngleDiff(r.phi, p.phi) <= tol && std::abs(r.theta - p.theta) <= tol) {
            found = pose;
            break;
          }
        }
      }
    }
    if (found >= 0) {
      poses[found].push_back(i);
    } else {
      grid[{pc, tc}].push_back(static_cast<int>(poses.size()));
      poses.push_back({i});
    }
  }
  return poses;
}

Eigen::Vector3d ToFlange(const InstrumentModel& model, const Record& r, const Eigen::Vector3d& x) {
  return RefFromFlange(model, r.phi, r.theta).Inverse() * x;
}

}  // namespace

Rigid3 BaseFromFirstFrame(const LinkFrame& f) {
  const std::vector<Eigen::Vector3d> a{Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(),
                                       Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()};
  const std::vector<Eigen::Vector3d> b{f.o, f.o + f.x, f.o + f.y, f.o + f.z};
  return Kabsch(a, b).b_from_a;
}

std::optional<CameraToolEstimate> ExtractCameraTool(const std::vector<Record>& records,
                                                    const std::vector<int>& usable,
                                                    const InstrumentModel& model, int zoom,
                                                    const PrincipalPoint& principal_point,
                                                    const CameraTool* given,
                                                    const ExtractOptions& options) {
  std::vector<int> rows;
  for (int i : usable) {
    if (records[i].tool == Tool::kCam && records[i].zoom == zoom) rows.push_back(i);
  }
  if (rows.empty()) return std::nullopt;
  // Where the zoom's rows are, for every message below.
  const int first_line = records[rows[0]].line;
  const std::string where =
      "zoom " + std::to_string(zoom) + " (" + std::to_string(rows.size()) + " camera rows" +
      (first_line > 0 ? ", the first on line " + std::to_string(first_line) : std::string()) + ")";

  // Pixel triplets {c, c + [1, 0], c + [0, 1]} at one pose and ray length.
  struct Triplet {
    int row[3];
    double d;
  };
  std::vector<Triplet> triplets;
  const Eigen::Vector2d c = principal_point.pixel;
  const Eigen::Vector2d steps[3] = {{0, 0}, {1, 0}, {0, 1}};
  for (const auto& pose : GroupByPose(records, rows, options.angle_tolerance_rad)) {
    std::map<long long, std::array<int, 3>> by_d;
    for (int i : pose) {
      const Record& r = records[i];
      const Eigen::Vector2d off = Eigen::Vector2d(r.u, r.v) - c;
      for (int k = 0; k < 3; ++k) {
        if ((off - steps[k]).norm() <= options.pixel_tolerance_px) {
          auto it = by_d.try_emplace(std::llround(r.d / options.distance_tolerance_m),
                                     std::array<int, 3>{-1, -1, -1})
                        .first;
          if (it->second[k] < 0) it->second[k] = i;
        }
      }
    }
    for (const auto& [dq, idx] : by_d) {  // smallest complete ray length
      if (idx[0] >= 0 && idx[1] >= 0 && idx[2] >= 0) {
        triplets.push_back({{idx[0], idx[1], idx[2]}, records[idx[0]].d});
        break;
      }
    }
  }
  // Without any triplet, known intrinsics still give exact camera-frame
  // points for every row (header).
  const bool all_rows = triplets.empty() && given && options.exact_camera_rays;
  if (triplets.empty() && !all_rows) {
    std::ostringstream s;
    s << "cannot extract the camera tool of " << where
      << ": no pose has rows at the principal point (" << Significant(c.x()) << ", "
      << Significant(c.y()) << ")" << (principal_point.detected ? " (detected)" : "")
      << " and at +1 px in u and in v with the same ray length (Klug Sec. 3.1.10, Eq. 67). "
         "Record F_CAM at these three pixels at each pose, or give the camera's intrinsics "
         "(then every camera row is used, with exact_camera_rays).";
    throw ExtractionError(s.str());
  }

  CameraToolEstimate out;
  if (given) {
    out.camera = *given;
  } else {
    // Chord between the unit-length-d rays one pixel apart (header).
    // The median over the poses: one wrong row cannot move it.
    std::vector<double> fu, fv;
    for (const Triplet& t : triplets) {
      const Eigen::Vector3d& x0 = records[t.row[0]].x;
      auto focal = [&](const Eigen::Vector3d& x) {
        const double half = std::asin(std::min(1.0, (x - x0).norm() / (2.0 * t.d)));
        return 1.0 / std::tan(2.0 * half);
      };
      fu.push_back(focal(records[t.row[1]].x));
      fv.push_back(focal(records[t.row[2]].x));
    }
    auto median = [](std::vector<double> v) {
      std::sort(v.begin(), v.end());
      const size_t n = v.size();
      return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
    };
    out.camera = CameraTool{};
    out.camera.intrinsics = {median(fu), median(fv), c.x(), c.y()};
    out.camera.distortion.fill(0.0);
    out.camera.width = static_cast<int>(std::lround(2.0 * c.x() + 1.0));
    out.camera.height = static_cast<int>(std::lround(2.0 * c.y() + 1.0));
    out.intrinsics_estimated = true;
  }

  std::vector<Eigen::Vector3d> a, b;
  // Exact correspondence of one row: d * ray(u, v) in the camera frame.
  auto add_exact = [&](const Record& r) {
    const double pixel[2] = {r.u, r.v};
    double ray[3];
    if (!PixelToRay(out.camera.intrinsics.data(), out.camera.distortion.data(), pixel, ray)) {
      throw ExtractionError("cannot extract the camera tool of " + where + ": pixel (" +
                            Significant(r.u) + ", " + Significant(r.v) + ") of line " +
                            std::to_string(r.line) +
                            " cannot be undistorted with the given distortion");
    }
    a.push_back(r.d * Eigen::Vector3d(ray[0], ray[1], ray[2]));
    b.push_back(ToFlange(model, r, r.x));
  };
  if (all_rows) {
    for (int i : rows) add_exact(records[i]);
  }
  for (const Triplet& t : triplets) {
    const Record& r0 = records[t.row[0]];
    if (options.exact_camera_rays) {
      for (int k = 0; k < 3; ++k) add_exact(records[t.row[k]]);
    } else {
      // Eq. 69/70: unit axes from the principal-point row.
      const Eigen::Vector3d ct(0, 0, t.d);
      const Eigen::Vector3d& x1 = r0.x;
      const Eigen::Vector3d x2 = x1 + (records[t.row[1]].x - x1).normalized();
      const Eigen::Vector3d x3 = x1 + (records[t.row[2]].x - x1).normalized();
      a.insert(a.end(), {ct, ct + Eigen::Vector3d::UnitX(), ct + Eigen::Vector3d::UnitY()});
      b.insert(b.end(),
               {ToFlange(model, r0, x1), ToFlange(model, r0, x2), ToFlange(model, r0, x3)});
    }
  }
  if (a.size() < 3) {
    throw ExtractionError("cannot extract the camera tool of " + where + ": only " +
                          std::to_string(a.size()) +
                          " usable camera rows (need 3 at different pixels or ray lengths)");
  }
  std::vector<int> dropped;
  const KabschResult k = RobustKabsch(a, b, kKabschFloorM, &dropped);
  if (k.rank < 2) {
    throw ExtractionError("cannot extract the camera tool of " + where +
                          ": its usable camera rows lie on one line in the camera frame (one "
                          "pixel direction only); record the principal point and +1 px in u "
                          "and in v (Klug Eq. 67)");
  }
  out.camera.flange_from_cam = PoseBlock::FromRigid(k.b_from_a);
  out.poses = all_rows
                  ? static_cast<int>(GroupByPose(records, rows, options.angle_tolerance_rad).size())
                  : static_cast<int>(triplets.size());
  out.rms = k.rms;
  std::ostringstream note;
  note << "camera tool zoom " << zoom << ": " << out.poses << " poses"
       << (all_rows ? " (no pixel triplet: every camera row, exact rays)" : "")
       << ", principal point (" << Significant(c.x()) << ", " << Significant(c.y()) << ") "
       << (principal_point.detected ? "detected (most shared triplet centre)"
                                    : "from the intrinsics")
       << (options.exact_camera_rays ? ", exact back-projected rays"
                                     : ", paper's unit axes (Eq. 69/70)")
       << ", alignment RMS " << Significant(k.rms) << " m";
  if (!dropped.empty()) {
    note << "; " << dropped.size() << " of " << a.size()
         << " correspondences left out (off by more than 8 robust sigmas: gross errors)";
  }
  if (out.intrinsics_estimated) {
    note << "; no intrinsics given: fx = " << Significant(out.camera.intrinsics[0])
         << ", fy = " << Significant(out.camera.intrinsics[1])
         << " px estimated from the 1 px chords, distortion 0";
  }
  out.note = note.str();
  return out;
}

std::optional<EdmToolEstimate> ExtractEdmTool(const std::vector<Record>& records,
                                              const std::vector<int>& usable,
                                              const InstrumentModel& model, int reference_zoom,
                                              const ExtractOptions& options) {
  std::vector<int> rows;
  for (int i : usable) {
    if (records[i].tool == Tool::kEdm) rows.push_back(i);
  }
  std::vector<Eigen::Vector3d> a, b;
  int used[4] = {0, 0, 0, 0};  // camera x, camera y, flange x, flange y
  int poses = 0;
  for (const auto& pose : GroupByPose(records, rows, options.angle_tolerance_rad)) {
    // The two smallest distinct distances at this pose.
    std::map<long long, int> by_d;
    for (int i : pose) by_d.emplace(std::llround(records[i].d / options.distance_tolerance_m), i);
    if (by_d.size() < 2) continue;
    const Record& ra = records[by_d.begin()->second];
    const Record& rb = records[std::next(by_d.begin())->second];
    const Eigen::Vector3d z = (rb.x - ra.x).normalized();
    const Eigen::Matrix3d ref = reference_zoom >= 0
                                    ? RefFromCam(model, reference_zoom, ra.phi, ra.theta).rotation
                                    : RefFromFlange(model, ra.phi, ra.theta).rotation;
    Eigen::Vector3d x = Eigen::Vector3d::Zero();
    for (int k = 0; k < 2; ++k) {  // Eq. 79 with x, then footnote 8's y
      const Eigen::Vector3d axis = ref.col(k);
      const Eigen::Vector3d p = axis - axis.dot(z) * z;
      if (p.norm() >= kMinReferenceProjection) {
        x = p.normalized();
        ++used[(reference_zoom >= 0 ? 0 : 2) + k];
        break;
      }
    }
    if (x.isZero()) continue;  // cannot happen: x and y cannot both be parallel to z
    const double da = ra.d;
    a.insert(a.end(),
             {Eigen::Vector3d(0, 0, da), Eigen::Vector3d(1, 0, da), Eigen::Vector3d(0, 0, da + 1)});
    b.insert(b.end(), {ToFlange(model, ra, ra.x), ToFlange(model, ra, ra.x + x),
                       ToFlange(model, ra, ra.x + z)});
    ++poses;
  }
  if (poses == 0) return std::nullopt;
  std::vector<int> dropped;
  const KabschResult k = RobustKabsch(a, b, kKabschFloorM, &dropped);
  EdmToolEstimate out;
  out.flange_from_edm = PoseBlock::FromRigid(k.b_from_a);
  out.poses = poses;
  out.rms = k.rms;
  const char* names[4] = {"camera x", "camera y (footnote 8)", "flange x (no camera)",
                          "flange y (no camera)"};
  std::ostringstream s;
  bool first = true;
  for (int i = 0; i < 4; ++i) {
    if (!used[i]) continue;
    s << (first ? "" : ", ") << names[i];
    if (i < 2) s << " of zoom " << reference_zoom;
    s << " at " << used[i] << " poses";
    first = false;
  }
  if (!dropped.empty()) {
    s << "; " << dropped.size() << " of " << a.size()
      << " correspondences left out of the tool's Kabsch fit (off by more than 8 robust sigmas: "
         "gross errors)";
  }
  out.x_reference = s.str();
  return out;
}

}  // namespace rtscalib

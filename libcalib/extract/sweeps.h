// Finding the joint sweeps of Klug et al. Sec. 3.1.2 in a list of records,
// without relying on the `set` label (it is only a tie-breaking hint).
//
// Rows are usable when they are face 1 and their zenith angle lies inside
// [min_zenith, max_zenith] (ExtractOptions); the others are counted. Usable
// rows are grouped by (tool, zoom for camera rows, distance d, pixel offset
// from the zoom's principal point). Within a group
//   a joint-1 sweep = rows with the same theta and at least min_sweep_points
//                     different phi values,
//   a joint-2 sweep = rows with the same phi and at least min_sweep_points
//                     different theta values,
// "same" meaning within ExtractOptions::angle_tolerance_rad (phi compared
// modulo 2 pi). Repeated control values keep their first row.
//
// The sweeps used for the joint circles are chosen in this order:
//   1. EDM rows before camera rows (camera rows only when there is no EDM
//      sweep); camera rows at the principal point before other pixels, lower
//      zoom levels first;
//   2. the smallest distance d (the paper's d = 1 m arm);
//   3. rows whose (most frequent) `set` label equals the joint's hint
//      ("sweep1"/"sweep2");
//   4. the largest sqrt(N) * sin(zenith) for joint 1 (the circle radius grows
//      with sin(theta)), sqrt(N) for joint 2; then the larger control span.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "libcalib/extract/options.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"

namespace rtscalib {

struct Sweep {
  int joint = 1;  // 1: theta constant, phi varies; 2: phi constant, theta varies
  int face = 1;
  Tool tool = Tool::kEdm;
  int zoom = 0;                                            // camera sweeps only
  double d = 1.0;                                          // EDM distance or camera ray length [m]
  Eigen::Vector2d pixel_offset = Eigen::Vector2d::Zero();  // camera: pixel - principal point [px]
  double constant_control = 0.0;  // the fixed theta (joint 1) or phi (joint 2) [rad]
  // Indices into the records, one per control value, in increasing control order.
  std::vector<int> rows;
  // The most frequent `set` label of the rows (a pose shared by both sweeps
  // carries the other sweep's label), "" when absent.
  std::string set;

  int NumPoints() const { return static_cast<int>(rows.size()); }
  // The varying control of row i of this sweep: phi in [0, 2 pi) for joint 1,
  // theta for joint 2.
  double Control(const std::vector<Record>& records, int i) const;
  // "joint-1 sweep (face 1, edm, d = 1 m, theta = 1.5708 rad constant, 15 points,
  // lines 2-30, set 'sweep1')"
  std::string Describe(const std::vector<Record>& records) const;
};

struct ExcludedRows {
  int face2 = 0;            // extraction uses face 1 only
  int critical_zenith = 0;  // face-1 rows outside [min_zenith, max_zenith]
  int Total() const { return face2 + critical_zenith; }
};

struct PrincipalPoint {
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();
  bool detected = false;  // false: from the given intrinsics (cx, cy)
};

// One entry per zoom level 0 .. max(cameras.size(), largest camera-row zoom + 1) - 1:
// (cx, cy) of cameras[z] when given; otherwise detected from the usable
// camera rows of that zoom: the pixel shared by the most rows among the
// pixels whose +1 px neighbours in u and in v also occur (centres of the
// paper's pixel triplet, Eq. 67; rows elsewhere in the image, e.g. a grid, are
// not candidates), or the most shared pixel when no triplet exists;
// std::nullopt when the zoom has neither intrinsics nor camera rows.
// Throws ExtractionError when the largest zoom exceeds cameras.size() plus
// the number of records (a mistyped zoom; memory would grow with it).
std::vector<std::optional<PrincipalPoint>> FindPrincipalPoints(
    const std::vector<Record>& records, const std::vector<CameraTool>& cameras,
    const ExtractOptions& options);

struct SweepSearch {
  std::vector<int> usable;  // indices of the usable rows (face 1, outside critical regions)
  ExcludedRows excluded;
  std::vector<Sweep> candidates;        // every sweep found, both joints
  std::optional<Sweep> joint1, joint2;  // the chosen ones (see above)
};

// Camera rows of a zoom without a principal point are grouped by their
// absolute pixel instead.
SweepSearch FindSweeps(const std::vector<Record>& records,
                       const std::vector<std::optional<PrincipalPoint>>& principal_points,
                       const ExtractOptions& options);

// True when the row is face 1 with a zenith inside the options' limits.
bool IsUsableForExtraction(const Record& r, const ExtractOptions& options);

}  // namespace rtscalib

// shots.csv (SPEC 7): the photos of a real instrument, one per row.
//
// Columns (header required, any order, `#` comments; csv.h has the syntax):
//   face         1 or 2
//   zoom         zoom level, integer >= 0
//   phi, theta   control angles of the photo, finite, in `unit` (data.angle_unit;
//                stored in radians, libcalib/model/angle_unit.h); both may be
//                empty (a camera-only session, SPEC 7.1: has_reading false;
//                a calibration with kinematics refuses such a photo by line)
//   image        the image file, relative to the CSV's folder (absolute paths
//                are taken as they are); the file must exist
//   shot         optional shot id; default: the image file's stem
//   placement    optional text (SPEC 7.1): the boards without a pose stood
//                still for all photos of one placement and moved between
//                placements; without the column (or empty) every photo is of
//                the one placement ""
//   focus_distance  optional, metres > 0 (SPEC 4.1): the distance the camera
//                was focused at (what the instrument reports); empty = unknown
// Shot ids must be unique (they key the photo's pixels in pixels.csv). Every
// violation is an InputError naming file, line and column; a missing image
// names the line and the path that was tried.
#pragma once

#include <string>
#include <vector>

#include "libcalib/model/angle_unit.h"

namespace rtscalib {

struct PhotoShot {
  int face = 1;
  int zoom = 0;
  double phi = 0, theta = 0;  // [rad], whatever unit the file gave
  bool has_reading = true;    // false: phi, theta empty (camera-only, SPEC 7.1)
  std::string image;          // as written in the CSV
  std::string image_path;     // resolved against the CSV's folder
  std::string shot;           // unique id
  std::string placement;      // SPEC 7.1 (empty: the one placement)
  double focus_distance = 0;  // [m], SPEC 4.1; 0 = not given
  int line = 0;               // 1-based line in the CSV
  std::vector<double> covariates;  // ShotsFile::covariates' values (NaN: empty)
};

struct ShotsFile {
  std::string path;
  AngleUnit angle_unit = AngleUnit::kRad;  // the unit the file gave phi, theta in
  std::vector<PhotoShot> shots;
  bool has_placements = false;  // the file has a `placement` column (SPEC 7.1)
  // Extra numeric columns (temperature, time, ...) kept as covariates; each
  // photo's pixel observations carry them (docs/diagnostics.md).
  std::vector<std::string> covariates;
  std::vector<std::string> notes;  // e.g. ignored extra columns
};

ShotsFile ReadShots(const std::string& path, AngleUnit unit = AngleUnit::kRad);

}  // namespace rtscalib

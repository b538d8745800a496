// In-memory observations: the device-API records (SPEC 3, records.csv), image
// observations (pixels.csv, or the corners detected in photos, SPEC 7) and the
// boards those images show. Files are read and written by libcalib/io; the
// numerics only see these structs.
//
// Points of unknown position (SPEC 7): a record with a non-empty `point` name
// observes one fixed point shared by every record of that name (x is then
// not an observation); a pixel observation with `X_known == false` observes
// corner `corner` of tag `target` of a board in `Observations::targets` whose
// pose is unknown (TagBoard::pose_known == false). Both are estimated with
// everything else.
//
// Placements (SPEC 7.1): a board without a pose stays put for all shots of
// one `placement` (shots.csv's column of that name, any text; empty = the
// one placement of a session without the column) and has one pose per
// placement. A camera-only calibration (model.kinematics: none) needs no
// readings: `has_reading == false` marks a shot whose phi and theta were
// left empty (phi, theta are then 0 and must not be used).
#pragma once

#include <Eigen/Core>
#include <map>
#include <string>
#include <vector>

#include "libcalib/model/angle_unit.h"
#include "libcalib/model/targets.h"

namespace rtscalib {

enum class Tool { kEdm, kCam };

struct Record {
  int face = 1;
  int zoom = 0;  // ignored for EDM rows
  double phi = 0, theta = 0;
  Tool tool = Tool::kEdm;
  double u = 0, v = 0;                          // cam rows only
  double d = 1;                                 // EDM distance or camera ray length [m]
  Eigen::Vector3d x = Eigen::Vector3d::Zero();  // point in the reference frame [m]
  std::string set;                              // free label, may be empty
  // SPEC 7: the name of a fixed point of unknown position; x is unknown when
  // this is not empty.
  std::string point;
  int line = 0;  // 1-based line in the source file (0 = not from a file)
  // Values of the file's extra numeric columns (Observations::record_covariates,
  // e.g. temperature, time), NaN where a cell is empty.
  std::vector<double> covariates;
};

struct PixelObservation {
  int face = 1;
  int zoom = 0;
  double phi = 0, theta = 0;
  bool has_reading = true;  // false: phi, theta were empty (camera-only data, SPEC 7.1)
  std::string shot;
  std::string placement;  // SPEC 7.1: where the boards without a pose stood (empty: one placement)
  double focus_distance = 0;  // [m] the shot's focus distance (SPEC 4.1); 0 = not given
  int target = 0, corner = 0;
  Eigen::Vector3d X = Eigen::Vector3d::Zero();  // known point, reference frame [m]
  // False: X is unknown, the point is corner (target, corner) of a board of
  // Observations::targets without a pose (SPEC 7).
  bool X_known = true;
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();  // observed pixel
  int line = 0;
  // Values of the extra numeric columns of shots.csv / pixels.csv
  // (Observations::pixel_covariates), NaN where a cell is empty.
  std::vector<double> covariates;
};

// A row taken out of a calibration as a gross error (libcalib/screen/gross.h
// before the fit, libcalib/fit/robust.h after the robust fit): which row,
// its line in its file, and why, with the numbers (SPEC 3: rows are never
// silently dropped).
struct ExcludedRow {
  bool pixel = false;  // a pixels.csv row (else a records.csv row)
  int index = 0;       // into Observations::pixels or ::records as given
  int line = 0;
  std::string reason;

  // The order they are listed in: records first, then pixels, each in
  // their order as given.
  bool operator<(const ExcludedRow& o) const {
    return pixel != o.pixel ? !pixel : index < o.index;
  }
};

// Width and height of one zoom's images [px], from the photos (SPEC 7: never
// guessed from where the points fall).
struct ImageSize {
  int width = 0, height = 0;
};

struct Observations {
  std::vector<Record> records;
  std::vector<PixelObservation> pixels;
  // The boards the pixels see: those with a pose give known X; those without
  // are estimated (pixels with X_known == false refer to them by tag id).
  TargetScene targets;
  // Per zoom, the image size of its photos, when the observations come from
  // photos (empty otherwise: sizes then come from model.cameras).
  std::map<int, ImageSize> image_sizes;
  // Names of the extra numeric columns of records.csv and of shots.csv /
  // pixels.csv (covariates such as temperature or time, kept in the rows'
  // `covariates` in this order): the diagnosis tests the residuals against
  // them (docs/diagnostics.md).
  std::vector<std::string> record_covariates;
  std::vector<std::string> pixel_covariates;
  std::string records_source = "records";  // file names for messages
  std::string pixels_source = "pixels";
  // The unit the files gave phi and theta in (data.angle_unit); the values
  // above are radians whatever it was. For messages and reports.
  AngleUnit angle_unit = AngleUnit::kRad;
};

}  // namespace rtscalib

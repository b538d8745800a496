// In-memory observations: the device-API records (SPEC 3, records.csv) and
// image observations of known points (pixels.csv). Files are read and written
// by libcalib/io; the numerics only see these structs.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

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
  int line = 0;  // 1-based line in the source file (0 = not from a file)
};

struct PixelObservation {
  int face = 1;
  int zoom = 0;
  double phi = 0, theta = 0;
  std::string shot;
  int target = 0, corner = 0;
  Eigen::Vector3d X = Eigen::Vector3d::Zero();   // known point, reference frame [m]
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();  // observed pixel
  int line = 0;
};

struct Observations {
  std::vector<Record> records;
  std::vector<PixelObservation> pixels;
  std::string records_source = "records";  // file names for messages
  std::string pixels_source = "pixels";
};

}  // namespace rtscalib

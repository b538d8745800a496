// Model error measures (Klug Sec. 4.2).
//
//   mean  d = sum ||x_meas - x_calc|| / N                               (Eq. 92)
//   std   s = sqrt(sum (||x_meas - x_calc|| - d)^2 / (N - 1))            (Eq. 93)
//   rms     = sqrt(sum ||x_meas - x_calc||^2 / N)
// Methods (Table 3):
//   A: only points on the tool axes: EDM rows, and camera rows at the
//      principal point (rotation about the rays does not count);
//   B: all camera rows (points off the principal ray, so rotation about the
//      optical axis counts) and, for the EDM, points 1 m off its ray along the
//      EDM x axis that the measurements define by Eq. 79 (camera x projected
//      onto the plane normal to the measured EDM ray) at every pose that has
//      two EDM distances and camera rows at the principal point and +u.
// Compound = all points of both tools together.
#pragma once

#include <string>
#include <vector>

#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"

namespace rtscalib {

struct ErrorStats {
  double mean_m = 0;  // Eq. 92
  double std_m = 0;   // Eq. 93
  double rms_m = 0;
  double max_m = 0;
  int n = 0;
};
ErrorStats StatsOf(const std::vector<double>& distances);

struct PixelStats {
  double rms_px = 0;   // sqrt(mean(du^2 + dv^2))
  double mean_px = 0;  // mean |du, dv|
  double max_px = 0;
  int n = 0;
  int failed = 0;  // points behind the camera under the model
};

enum class ErrorMethod { kA, kB };

struct ModelErrors {
  ErrorStats edm, cam, compound;
};

// One evaluated record (for maps and diagnostics).
struct RecordResidual {
  int index = -1;         // into the records vector
  double distance = 0;    // ||x_meas - x_calc||
  Eigen::Vector3d delta;  // x_meas - x_calc
  bool valid = true;      // false if the model could not evaluate it
};

struct PixelResidual {
  int index = -1;
  Eigen::Vector2d delta;  // observed - predicted
  bool valid = true;
};

std::vector<RecordResidual> RecordResiduals(const InstrumentModel& model,
                                            const std::vector<Record>& records);
std::vector<PixelResidual> PixelResiduals(const InstrumentModel& model,
                                          const std::vector<PixelObservation>& pixels);

// Per-tool and compound statistics by method A or B.
ModelErrors EvaluateRecords(const InstrumentModel& model, const std::vector<Record>& records,
                            ErrorMethod method);
PixelStats EvaluatePixels(const InstrumentModel& model,
                          const std::vector<PixelObservation>& pixels);

// Klug Eq. 98 scalarised objective w_d * mean + w_s * std over all points.
double ScalarisedObjective(const ErrorStats& s, double w_d = 1.0, double w_s = 1.0);

}  // namespace rtscalib

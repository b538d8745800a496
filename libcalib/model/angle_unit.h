// The unit in which a user's files give the instrument's readings phi and
// theta (the config's `data.angle_unit`, `--angle-unit` of predict and
// detect). Inside rtscalib every angle is in radians (SPEC 1): readings are
// converted once, when a file is read (CsvTable::Angle, libcalib/io/csv.h),
// and written back in the file's unit by the commands that echo a user's
// rows (FormatReading, libcalib/text/number_text.h).
//
//   rad   radians (SPEC 1; the default)
//   deg   degrees, a full turn is 360:  rad = deg * pi / 180
//   gon   gon (grad), a full turn is 400: rad = gon * pi / 200
#pragma once

#include <cmath>
#include <optional>
#include <string_view>

namespace rtscalib {

enum class AngleUnit { kRad, kDeg, kGon };

// Config and command-line names, in enum order.
inline constexpr const char* kAngleUnitNames[] = {"rad", "deg", "gon"};

inline const char* AngleUnitName(AngleUnit u) { return kAngleUnitNames[static_cast<int>(u)]; }

inline std::optional<AngleUnit> AngleUnitFromName(std::string_view name) {
  for (int i = 0; i < 3; ++i) {
    if (name == kAngleUnitNames[i]) return static_cast<AngleUnit>(i);
  }
  return std::nullopt;
}

// Units per half turn (pi radians).
inline double HalfTurn(AngleUnit u) {
  switch (u) {
    case AngleUnit::kRad:
      return M_PI;
    case AngleUnit::kDeg:
      return 180.0;
    case AngleUnit::kGon:
      return 200.0;
  }
  return M_PI;
}

// A reading in `u` as radians: (reading / half turn) * pi, so that the
// quarter and half turns of deg and gon files (90, 180, 100, 200, ...) are
// exactly the M_PI / 2, M_PI of a rad file (a face-1 zenith angle of 200 gon
// stays within [0, pi]); otherwise two roundings, within ~2 ulp (~4.4e-16
// relative) of the exact value.
inline double ReadingToRadians(double reading, AngleUnit u) {
  return u == AngleUnit::kRad ? reading : reading / HalfTurn(u) * M_PI;
}

}  // namespace rtscalib

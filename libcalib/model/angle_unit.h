// The unit in which a user's files give the instrument's readings phi and
// theta (the config's `data.angle_unit`, `--angle-unit` of predict and
// detect). Inside rtscalib every angle is in radians (SPEC 1): readings are
// converted once, when a file is read (CsvTable::Angle, libcalib/io/csv.h),
// and written back in the file's unit by the commands that echo a user's
// rows (FormatReading, libcalib/io/number_text.h).
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

// Radians per unit.
inline double RadiansPer(AngleUnit u) {
  switch (u) {
    case AngleUnit::kRad:
      return 1.0;
    case AngleUnit::kDeg:
      return M_PI / 180.0;
    case AngleUnit::kGon:
      return M_PI / 200.0;
  }
  return 1.0;
}

// A reading in `u` as radians: one multiplication, so that deg and gon files
// give the radians of a rad file to within an ulp or two (~2e-16 relative).
inline double ReadingToRadians(double reading, AngleUnit u) {
  return u == AngleUnit::kRad ? reading : reading * RadiansPer(u);
}

}  // namespace rtscalib

// records.csv and pixels.csv (SPEC 3): files <-> the observation structs of
// libcalib/model/observations.h.
//
// records.csv columns: face, zoom, phi, theta, tool, u, v, d, x, y, z [, set]
//   face   1 or 2                      zoom  integer >= 0 (may be empty on edm rows -> 0)
//   tool   edm | cam                   u, v  pixels; required on cam rows, may be empty on edm rows
//   d      > 0 [m]                     phi, theta, x, y, z  finite [`unit`, m]
//   set    optional free label (the column may be absent)
// pixels.csv columns: face, zoom, phi, theta, shot, target, corner, X, Y, Z, u, v
//   shot   free label of one image     target  integer >= 0     corner  0..3
// phi and theta are read in `unit` (data.angle_unit, default rad) and
// stored in radians (libcalib/model/angle_unit.h); the writers write them in
// `unit` again, so that a command echoing a user's rows keeps their unit.
// Every violation is an InputError naming file, line and column (csv.h has the
// shared syntax rules); each struct keeps the line it came from so that later
// messages (critical region, outliers) can point at it.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "libcalib/model/angle_unit.h"
#include "libcalib/model/observations.h"

namespace rtscalib {

// Extra numeric columns (temperature, time, ...) are kept as covariates
// (Record::covariates, in the order of `covariates`); the diagnosis tests
// the residuals against them. Other extra columns are ignored with a note.
struct RecordsFile {
  std::vector<Record> records;
  std::vector<std::string> covariates;
  std::vector<std::string> notes;  // e.g. ignored extra columns
};
RecordsFile ReadRecords(const std::string& path, AngleUnit unit = AngleUnit::kRad);
// Writes all columns including `set`, numbers with %.17g (phi, theta in
// `unit`, FormatReading); u, v empty on edm rows; then the `covariates`
// columns (the records' values, empty for NaN).
void WriteRecords(const std::string& path, const std::vector<Record>& records,
                  AngleUnit unit = AngleUnit::kRad,
                  const std::vector<std::string>& covariates = {});

// pixels.csv (SPEC 3, SPEC 7) with the optional columns `width`, `height`
// that `rtscalib detect` writes: the size of the image a row was seen in,
// read from the photo (SPEC 7: sizes are never guessed from the points).
// Both or neither; a row may leave both empty; one size per zoom level.
// Optional `placement` (SPEC 7.1, text) and `focus_distance` (SPEC 4.1,
// metres > 0, may be empty) columns; phi and theta may both be empty (a
// camera-only session, SPEC 7.1: has_reading false).
// Extra numeric columns are kept as covariates, as in records.csv.
struct PixelsFile {
  std::vector<PixelObservation> pixels;
  std::map<int, ImageSize> image_sizes;  // per zoom, from `width`, `height`
  std::vector<std::string> covariates;
  std::vector<std::string> notes;
};
PixelsFile ReadPixels(const std::string& path, AngleUnit unit = AngleUnit::kRad);
// The one pixels.csv writer (the detection's, the demo's, predict's): SPEC 3's
// columns, then `placement` and `focus_distance` when some row has one, and
// `width`, `height` of each row's zoom when `image_sizes` has it (empty
// cells for zooms it lacks), then the `covariates` columns. phi, theta in
// `unit`; empty for rows without a reading.
void WritePixels(const std::string& path, const std::vector<PixelObservation>& pixels,
                 AngleUnit unit = AngleUnit::kRad,
                 const std::map<int, ImageSize>& image_sizes = {},
                 const std::vector<std::string>& covariates = {});

}  // namespace rtscalib

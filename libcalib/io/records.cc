#include "libcalib/io/records.h"

#include <cmath>
#include <limits>
#include <map>

#include "libcalib/io/csv.h"
#include "libcalib/text/errors.h"
#include "libcalib/text/number_text.h"

namespace rtscalib {
namespace {

int ReadFace(const CsvTable& t, int row) {
  const std::optional<long long> face = ParseInteger(t.Text(row, "face"));
  if (!face || (*face != 1 && *face != 2)) t.Fail(row, "face", "1 or 2");
  return static_cast<int>(*face);
}

int ReadNonNegativeInt(const CsvTable& t, int row, const std::string& column, int max,
                       const std::string& expected) {
  const std::optional<long long> value = ParseInteger(t.Text(row, column));
  if (!value || *value < 0 || *value > max) t.Fail(row, column, expected);
  return static_cast<int>(*value);
}

int ReadZoom(const CsvTable& t, int row) {
  return ReadNonNegativeInt(t, row, "zoom", std::numeric_limits<int>::max(),
                            "a zoom level (integer >= 0)");
}

Eigen::Vector3d ReadPoint(const CsvTable& t, int row, const char* x, const char* y, const char* z) {
  return {t.Number(row, x), t.Number(row, y), t.Number(row, z)};
}

}  // namespace

RecordsFile ReadRecords(const std::string& path, AngleUnit unit) {
  const CsvTable t = CsvTable::Read(
      path,
      {{"face", "zoom", "phi", "theta", "tool", "d", "x", "y", "z"}, {"u", "v", "set", "point"},
       /*covariates=*/true});
  RecordsFile out;
  out.notes = t.notes();
  out.covariates = t.covariates();
  out.records.reserve(t.NumRows());
  for (int row = 0; row < t.NumRows(); ++row) {
    Record r;
    r.line = t.Line(row);
    r.face = ReadFace(t, row);
    const std::string& tool = t.Text(row, "tool");
    if (tool == "edm") {
      r.tool = Tool::kEdm;
    } else if (tool == "cam") {
      r.tool = Tool::kCam;
    } else {
      t.Fail(row, "tool", "edm or cam");
    }
    // The zoom of an EDM row means nothing (SPEC 3), so it may be left empty.
    r.zoom = (r.tool == Tool::kEdm && t.Empty(row, "zoom")) ? 0 : ReadZoom(t, row);
    r.phi = t.Angle(row, "phi", unit);
    r.theta = t.Angle(row, "theta", unit);
    if (r.tool == Tool::kCam) {
      for (const char* column : {"u", "v"}) {
        if (!t.Has(column)) {
          throw InputError::Cell(t.file(), r.line, column,
                                 "a pixel coordinate for a cam row (the header has no '" +
                                     std::string(column) + "' column)",
                                 "");
        }
        if (t.Empty(row, column)) t.Fail(row, column, "a pixel coordinate for a cam row");
      }
    }
    // EDM rows may carry u, v (ignored), but not garbage.
    if (!t.Empty(row, "u")) r.u = t.Number(row, "u");
    if (!t.Empty(row, "v")) r.v = t.Number(row, "v");
    r.d = t.Number(row, "d");
    if (!(r.d > 0)) {
      t.Fail(row, "d", r.tool == Tool::kEdm ? "an EDM distance > 0 [m]" : "a ray length > 0 [m]");
    }
    // SPEC 7: a row naming a point of unknown position may leave x, y, z
    // empty (they are then not an observation); any other row needs them.
    r.point = t.Has("point") ? t.Text(row, "point") : std::string();
    if (r.point.empty()) {
      r.x = ReadPoint(t, row, "x", "y", "z");
    } else {
      for (int i = 0; i < 3; ++i) {
        const char* column = i == 0 ? "x" : i == 1 ? "y" : "z";
        if (!t.Empty(row, column)) r.x[i] = t.Number(row, column);
      }
    }
    r.set = t.Text(row, "set");
    for (size_t k = 0; k < out.covariates.size(); ++k) {
      r.covariates.push_back(t.Covariate(row, static_cast<int>(k)));
    }
    out.records.push_back(std::move(r));
  }
  return out;
}

namespace {
// A covariate cell: its number, empty for NaN or a row without it.
std::string CovariateCell(const std::vector<double>& values, size_t k) {
  return k < values.size() && std::isfinite(values[k]) ? FormatDouble(values[k]) : "";
}
}  // namespace

void WriteRecords(const std::string& path, const std::vector<Record>& records, AngleUnit unit,
                  const std::vector<std::string>& covariates) {
  // The `point` column (SPEC 7) only when some row names a point, so that
  // files without such points keep their columns.
  bool points = false;
  for (const Record& r : records) points = points || !r.point.empty();
  std::vector<std::string> header = {"face", "zoom", "phi", "theta", "tool", "u",
                                     "v",    "d",    "x",   "y",     "z",    "set"};
  if (points) header.push_back("point");
  header.insert(header.end(), covariates.begin(), covariates.end());
  CsvWriter w(path, header);
  for (const Record& r : records) {
    const bool cam = r.tool == Tool::kCam;
    const bool unknown = !r.point.empty();
    std::vector<std::string> row = {std::to_string(r.face),
                                    std::to_string(r.zoom),
                                    FormatReading(r.phi, unit),
                                    FormatReading(r.theta, unit),
                                    cam ? "cam" : "edm",
                                    cam ? FormatDouble(r.u) : "",
                                    cam ? FormatDouble(r.v) : "",
                                    FormatDouble(r.d),
                                    unknown ? "" : FormatDouble(r.x.x()),
                                    unknown ? "" : FormatDouble(r.x.y()),
                                    unknown ? "" : FormatDouble(r.x.z()),
                                    r.set};
    if (points) row.push_back(r.point);
    for (size_t k = 0; k < covariates.size(); ++k) row.push_back(CovariateCell(r.covariates, k));
    w.Row(row);
  }
  w.Close();
}

PixelsFile ReadPixels(const std::string& path, AngleUnit unit) {
  const CsvTable t = CsvTable::Read(
      path,
      {{"face", "zoom", "phi", "theta", "shot", "target", "corner", "X", "Y", "Z", "u", "v"},
       {"width", "height", "placement", "focus_distance"},
       /*covariates=*/true});
  PixelsFile out;
  out.notes = t.notes();
  out.covariates = t.covariates();
  out.pixels.reserve(t.NumRows());
  if (t.Has("width") != t.Has("height") && t.NumRows() > 0) {
    const char* given = t.Has("width") ? "width" : "height";
    t.Fail(0, given,
           std::string("a '") + (t.Has("width") ? "height" : "width") + "' column beside '" +
               given + "' (the image size: both columns or neither)");
  }
  const bool sizes = t.Has("width") && t.Has("height");
  std::map<int, int> size_line;  // zoom -> the line its size was first read from
  for (int row = 0; row < t.NumRows(); ++row) {
    PixelObservation p;
    p.line = t.Line(row);
    p.face = ReadFace(t, row);
    p.zoom = ReadZoom(t, row);
    p.has_reading = t.OptionalReading(row, unit, &p.phi, &p.theta);
    p.shot = t.Text(row, "shot");
    if (p.shot.empty()) t.Fail(row, "shot", "a shot id (one per image)");
    p.placement = t.Text(row, "placement");
    if (!t.Empty(row, "focus_distance")) {
      p.focus_distance = t.Number(row, "focus_distance");
      if (!(p.focus_distance > 0)) {
        t.Fail(row, "focus_distance", "the focus distance in metres (> 0), or empty");
      }
    }
    p.target = ReadNonNegativeInt(t, row, "target", std::numeric_limits<int>::max(),
                                  "a target id (integer >= 0)");
    p.corner = ReadNonNegativeInt(t, row, "corner", 3, "a corner index 0, 1, 2 or 3");
    // SPEC 7: X, Y, Z all empty = a corner of a board without a pose (the
    // calibration checks that `target` is on one and names this line if not).
    if (t.Empty(row, "X") && t.Empty(row, "Y") && t.Empty(row, "Z")) {
      p.X_known = false;
    } else {
      p.X = ReadPoint(t, row, "X", "Y", "Z");
    }
    p.uv = {t.Number(row, "u"), t.Number(row, "v")};
    for (size_t k = 0; k < out.covariates.size(); ++k) {
      p.covariates.push_back(t.Covariate(row, static_cast<int>(k)));
    }
    if (sizes && !(t.Empty(row, "width") && t.Empty(row, "height"))) {
      constexpr int kMaxSide = 1 << 20;
      const ImageSize size{
          ReadNonNegativeInt(t, row, "width", kMaxSide, "an image width in pixels (1 .. 2^20)"),
          ReadNonNegativeInt(t, row, "height", kMaxSide, "an image height in pixels (1 .. 2^20)")};
      if (size.width == 0) t.Fail(row, "width", "an image width in pixels (1 .. 2^20)");
      if (size.height == 0) t.Fail(row, "height", "an image height in pixels (1 .. 2^20)");
      const auto [it, first] = out.image_sizes.emplace(p.zoom, size);
      if (first) {
        size_line[p.zoom] = p.line;
      } else if (it->second.width != size.width || it->second.height != size.height) {
        t.Fail(row, it->second.width != size.width ? "width" : "height",
               "the image size " + std::to_string(it->second.width) + "x" +
                   std::to_string(it->second.height) + " of zoom " + std::to_string(p.zoom) +
                   " (line " + std::to_string(size_line[p.zoom]) +
                   "; one camera per zoom level, SPEC 2)");
      }
    }
    out.pixels.push_back(std::move(p));
  }
  return out;
}

void WritePixels(const std::string& path, const std::vector<PixelObservation>& pixels,
                 AngleUnit unit, const std::map<int, ImageSize>& image_sizes,
                 const std::vector<std::string>& covariates) {
  // Optional columns only when they carry something, so that files without
  // placements or focus distances keep SPEC 3's columns.
  bool placements = false, focus = false;
  for (const PixelObservation& p : pixels) {
    placements = placements || !p.placement.empty();
    focus = focus || p.focus_distance > 0;
  }
  std::vector<std::string> header = {"face", "zoom",   "phi", "theta", "shot", "target",
                                     "corner", "X",    "Y",   "Z",     "u",    "v"};
  if (placements) header.push_back("placement");
  if (focus) header.push_back("focus_distance");
  if (!image_sizes.empty()) {
    header.push_back("width");
    header.push_back("height");
  }
  header.insert(header.end(), covariates.begin(), covariates.end());
  CsvWriter w(path, header);
  for (const PixelObservation& p : pixels) {
    std::vector<std::string> row = {
        std::to_string(p.face),
        std::to_string(p.zoom),
        p.has_reading ? FormatReading(p.phi, unit) : "",
        p.has_reading ? FormatReading(p.theta, unit) : "",
        p.shot,
        std::to_string(p.target),
        std::to_string(p.corner),
        p.X_known ? FormatDouble(p.X.x()) : "",
        p.X_known ? FormatDouble(p.X.y()) : "",
        p.X_known ? FormatDouble(p.X.z()) : "",
        FormatDouble(p.uv.x()),
        FormatDouble(p.uv.y())};
    if (placements) row.push_back(p.placement);
    if (focus) row.push_back(p.focus_distance > 0 ? FormatDouble(p.focus_distance) : "");
    if (!image_sizes.empty()) {
      const auto it = image_sizes.find(p.zoom);
      row.push_back(it == image_sizes.end() ? "" : std::to_string(it->second.width));
      row.push_back(it == image_sizes.end() ? "" : std::to_string(it->second.height));
    }
    for (size_t k = 0; k < covariates.size(); ++k) row.push_back(CovariateCell(p.covariates, k));
    w.Row(row);
  }
  w.Close();
}

}  // namespace rtscalib

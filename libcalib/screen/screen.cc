#include "libcalib/screen/screen.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <set>
#include <stdexcept>

#include "libcalib/text/number_text.h"
#include "libcalib/screen/duplicates.h"
#include "libcalib/screen/gross.h"

namespace rtscalib {
namespace {

constexpr double kTwoPi = 2.0 * M_PI;
// Lines named beside the first offending one in a message.
constexpr size_t kListedLines = 5;
// Angles in degrees or gon reach at most 360 or 400.
constexpr double kFullCircleDeg = 360.0, kFullCircleGon = 400.0;
// u and v are called swapped when at least this many rows and 1/20 of a
// zoom's rows leave the image.
constexpr size_t kMinSwappedRows = 3, kSwappedFractionInverse = 20;
// Millimetres read as metres: every coordinate and distance 1000 times too large.
constexpr double kMmPerM = 1000.0;

std::string Num(double x) { return FormatShortestDouble(x); }

std::string JoinInts(const std::vector<int>& v, size_t max_items) {
  std::string out;
  for (size_t i = 0; i < v.size() && i < max_items; ++i)
    out += (i ? ", " : "") + std::to_string(v[i]);
  if (v.size() > max_items) out += ", ... (" + std::to_string(v.size()) + " in all)";
  return out;
}

// One row of records.csv or pixels.csv, as far as the shared checks go.
struct RowView {
  int line = 0, face = 1, zoom = 0;
  double phi = 0, theta = 0;
  bool has_pixel = false;  // cam rows and pixel observations
  double u = 0, v = 0;
  bool has_reading = true;  // false: phi, theta left empty (camera-only, SPEC 7.1)
};

std::vector<RowView> RowsOf(const std::vector<Record>& records) {
  std::vector<RowView> out;
  out.reserve(records.size());
  for (const Record& r : records) {
    out.push_back({r.line, r.face, r.zoom, r.phi, r.theta, r.tool == Tool::kCam, r.u, r.v});
  }
  return out;
}

std::vector<RowView> RowsOf(const std::vector<PixelObservation>& pixels) {
  std::vector<RowView> out;
  out.reserve(pixels.size());
  for (const PixelObservation& p : pixels) {
    out.push_back(
        {p.line, p.face, p.zoom, p.phi, p.theta, true, p.uv.x(), p.uv.y(), p.has_reading});
  }
  return out;
}

// The rows of one file that fail one check; reported once, at the first.
// Several rows may share a line (the corners of one photo of shots.csv):
// lines are listed once each.
struct Offenders {
  std::vector<int> lines;  // distinct, in the order met
  std::set<int> seen;
  size_t rows = 0;
  std::string first_got;
  void Add(int line, const std::string& got) {
    if (rows++ == 0) first_got = got;
    if (seen.insert(line).second) lines.push_back(line);
  }
  bool Empty() const { return rows == 0; }
  // "; also line 7" / "; also lines 7, 9, 12 and 40 more rows" / "; also
  // lines 3, 4, 5, 6, 7 and 74 more lines (5,204 rows in all)"
  std::string Also() const {
    if (lines.size() < 2) return "";
    std::string out = lines.size() == 2 ? "; also line " : "; also lines ";
    const size_t listed = std::min(lines.size() - 1, kListedLines);
    for (size_t i = 1; i <= listed; ++i) out += (i > 1 ? ", " : "") + std::to_string(lines[i]);
    if (lines.size() - 1 > listed) {
      const size_t more = lines.size() - 1 - listed;
      out += rows == lines.size()
                 ? " and " + std::to_string(more) + " more rows"
                 : " and " + std::to_string(more) + " more lines (" + std::to_string(rows) +
                       " rows in all)";
    }
    return out;
  }
  void Report(const std::string& file, const std::string& column, const std::string& expected,
              ScreenFindings* out) const {
    if (Empty()) return;
    out->errors.push_back(
        InputError::Cell(file, lines.front(), column, expected + Also(), first_got));
  }
};

bool InAngleRange(double x) { return x >= -kTwoPi && x < 2.0 * kTwoPi; }

// Why a file's angles leave [-2 pi, 4 pi) once read in `unit`
// (data.angle_unit). Read as radians: degrees or gon, told apart by the
// largest value (gon reach 400) and by where face-1 zenith angles cluster
// (horizontal is 90 degrees, 100 gon); the cause names the config key that
// reads them so. Read in degrees or gon already: the unit is wrong too.
std::string UnitCause(const std::vector<RowView>& rows, AngleUnit unit) {
  if (unit != AngleUnit::kRad) {
    return std::string("; the file's angles leave that range even read in ") + AngleUnitName(unit) +
           " (data.angle_unit: " + AngleUnitName(unit) + "): check the key and the file";
  }
  double max_abs = 0;
  std::vector<double> theta1;
  for (const RowView& r : rows) {
    if (!r.has_reading) continue;
    max_abs = std::max({max_abs, std::fabs(r.phi), std::fabs(r.theta)});
    if (r.face == 1) theta1.push_back(r.theta);
  }
  if (max_abs > kFullCircleGon) return "";
  bool gon = max_abs > kFullCircleDeg;
  if (!gon && !theta1.empty()) {
    std::nth_element(theta1.begin(), theta1.begin() + theta1.size() / 2, theta1.end());
    const double median = theta1[theta1.size() / 2];
    gon = std::fabs(median - 100.0) < std::fabs(median - 90.0);
  }
  return gon ? "; the file's angles look like gon: give `data.angle_unit: gon` in the config "
               "(--angle-unit gon for predict and detect) and they are read as gon"
             : "; the file's angles look like degrees: give `data.angle_unit: deg` in the config "
               "(--angle-unit deg for predict and detect) and they are read as degrees";
}

// A reading as the file wrote it (radians converted back to `unit`).
std::string AsWritten(double rad, AngleUnit unit) {
  if (unit == AngleUnit::kRad) return Num(rad);
  const std::optional<double> x = ParseDouble(FormatReading(rad, unit));
  return x ? Num(*x) : Num(rad);
}

// Angle units, the phi wrap and the faces of SPEC 1, on the readings in
// radians (converted from data.angle_unit when read).
void CheckAngles(const std::string& file, const std::vector<RowView>& rows, AngleUnit unit,
                 bool gross_rows, ScreenFindings* out) {
  Offenders phi_range, theta_range, face2, face1;
  size_t face1_rows = 0, face2_rows = 0;
  std::vector<int> phi_wrapped;
  for (const RowView& r : rows) {
    if (!r.has_reading) continue;  // nothing to check (camera-only rows)
    const bool phi_ok = InAngleRange(r.phi), theta_ok = InAngleRange(r.theta);
    if (!phi_ok) phi_range.Add(r.line, AsWritten(r.phi, unit));
    if (!theta_ok) theta_range.Add(r.line, AsWritten(r.theta, unit));
    if (phi_ok && r.phi >= kTwoPi) phi_wrapped.push_back(r.line);
    if (!theta_ok) continue;
    ++(r.face == 1 ? face1_rows : face2_rows);
    if (r.face == 2 && FaceContradictsTheta(2, r.theta)) face2.Add(r.line, AsWritten(r.theta, unit));
    if (r.face == 1 && FaceContradictsTheta(1, r.theta)) face1.Add(r.line, AsWritten(r.theta, unit));
  }
  // A few rows against the face convention are gross errors, taken out and
  // listed by the gross-error screening (gross.h); most rows, a convention
  // mistake.
  if (gross_rows && FewEnoughToBeGross(face1.rows, face1_rows)) face1 = Offenders();
  if (gross_rows && FewEnoughToBeGross(face2.rows, face2_rows)) face2 = Offenders();
  const std::string cause =
      phi_range.Empty() && theta_range.Empty() ? std::string() : UnitCause(rows, unit);
  // "in radians" for files in radians; "(read in deg)" otherwise: the range
  // is checked on the converted values either way.
  const std::string as_read = unit == AngleUnit::kRad
                                  ? std::string(" in radians")
                                  : std::string(" (read in ") + AngleUnitName(unit) + ")";
  const std::string range = unit == AngleUnit::kRad ? "[-2 pi, 4 pi)" : "[-2 pi, 4 pi) rad";
  phi_range.Report(file, "phi", "a horizontal angle" + as_read + " within " + range + cause, out);
  theta_range.Report(file, "theta", "a zenith angle" + as_read + " within " + range + cause, out);
  face2.Report(file, "theta",
               "a face-2 zenith angle in [pi, 2 pi] (SPEC 1: face 2 of the face-1 pointing "
               "(phi, theta) is (phi - pi mod 2 pi, 2 pi - theta)); this face-2 row is written "
               "the face-1 way",
               out);
  face1.Report(file, "theta",
               "a face-1 zenith angle in [0, pi] (SPEC 1); this face-1 row holds a face-2 "
               "reading (face 2 has theta in [pi, 2 pi]): check its face",
               out);
  if (!phi_wrapped.empty()) {
    out->warnings.push_back(
        file + ": phi beyond 2 pi on " + std::to_string(phi_wrapped.size()) + " of " +
        std::to_string(rows.size()) + " rows (line" + (phi_wrapped.size() == 1 ? " " : "s ") +
        JoinInts(phi_wrapped, kListedLines) +
        "): readings of one turn are in [0, 2 pi) (SPEC 1); check that these angles are " +
        (unit == AngleUnit::kRad ? std::string("radians")
                                 : std::string(AngleUnitName(unit)) + " (data.angle_unit)"));
  }
}

// Whether all `values` lie in the image's extent `size` [px] give or take
// `margin` (pixel centres run from 0 to size - 1; their edges from -0.5).
bool AllFit(const std::vector<double>& values, int size, double margin) {
  return std::all_of(values.begin(), values.end(),
                     [&](double x) { return x >= -0.5 - margin && x <= size - 0.5 + margin; });
}

// Pixels against their zoom's image size (model.cameras): outside, or u and
// v swapped (SPEC 2: u = column to the right, v = row down).
void CheckPixels(const std::string& file, const std::vector<RowView>& rows,
                 const std::vector<CameraTool>& cameras, double margin, ScreenFindings* out) {
  for (size_t z = 0; z < cameras.size(); ++z) {
    const int w = cameras[z].width, h = cameras[z].height;
    std::vector<double> us, vs;
    for (const RowView& r : rows) {
      if (!r.has_pixel || r.zoom != static_cast<int>(z)) continue;
      us.push_back(r.u);
      vs.push_back(r.v);
    }
    if (us.empty()) continue;
    const std::string zoom = std::to_string(z);
    const std::string source =
        "(model.cameras[" + zoom + "]: " + std::to_string(w) + " x " + std::to_string(h) + " px)";
    Offenders u_out, v_out;
    for (const RowView& r : rows) {
      if (!r.has_pixel || r.zoom != static_cast<int>(z)) continue;
      if (!AllFit({r.u}, w, margin)) u_out.Add(r.line, Num(r.u));
      if (!AllFit({r.v}, h, margin)) v_out.Add(r.line, Num(r.v));
    }
    // Swapped pixels spread over the image leave it on many rows (a quarter
    // of a 4:3 image); one or two rows outside are mistakes of their own.
    const size_t outside = std::max(u_out.rows, v_out.rows);
    const bool swapped = outside >= kMinSwappedRows &&
                         outside * kSwappedFractionInverse >= us.size() && w != h &&
                         AllFit(us, h, margin) && AllFit(vs, w, margin);
    if (swapped) {
      const bool v_bad = !v_out.Empty();
      (v_bad ? v_out : u_out)
          .Report(
              file, v_bad ? "v" : "u",
              std::string("a pixel ") +
                  (v_bad ? "row v within the image height " : "column u within the image width ") +
                  std::to_string(v_bad ? h : w) + " px of zoom " + zoom + " " + source +
                  "; u and v look swapped: every u fits the height and every v the width "
                  "(SPEC 2: u = column to the right, v = row down)",
              out);
      continue;
    }
    const std::string margin_text =
        " give or take screen.pixel_margin_px = " + Num(margin) + " px " + source;
    u_out.Report(file, "u",
                 "a pixel column u within the image of zoom " + zoom + ", -0.5 .. " + Num(w - 0.5) +
                     margin_text,
                 out);
    v_out.Report(file, "v",
                 "a pixel row v within the image of zoom " + zoom + ", -0.5 .. " + Num(h - 0.5) +
                     margin_text,
                 out);
  }
}

std::string PointText(const Eigen::Vector3d& x) {
  return Num(x.x()) + ", " + Num(x.y()) + ", " + Num(x.z());
}

// Every record's point lies within d of the instrument (plus the tools'
// offsets, centimetres), so the coordinate-wise median m of the points lies
// within sqrt(3) d_max of it and |x - m| <= d + sqrt(3) d_max. The test
// allows twice that plus 1 m; it does not depend on where the reference
// frame's origin is.
void CheckRecordPoints(const std::string& file, const std::vector<Record>& records, bool gross_rows,
                       ScreenFindings* out) {
  if (records.size() < 3) return;
  Eigen::Vector3d median;
  double d_max = 0;
  for (int k = 0; k < 3; ++k) {
    std::vector<double> c;
    c.reserve(records.size());
    for (const Record& r : records) c.push_back(r.x[k]);
    std::nth_element(c.begin(), c.begin() + c.size() / 2, c.end());
    median[k] = c[c.size() / 2];
  }
  for (const Record& r : records) d_max = std::max(d_max, r.d);
  auto bound = [&](double d) { return 2.0 * (d + std::sqrt(3.0) * d_max) + 1.0; };
  Offenders far;
  bool millimetres = true;
  double first_distance = 0, first_d = 0;
  for (const Record& r : records) {
    const double distance = (r.x - median).norm();
    if (distance <= bound(r.d)) continue;
    if (far.Empty()) {
      first_distance = distance;
      first_d = r.d;
    }
    far.Add(r.line, PointText(r.x));
    // Millimetres: scaled back to metres (d stays), the point passes.
    millimetres = millimetres && distance / kMmPerM <= bound(r.d);
  }
  // A few such rows are gross errors (gross.h's sphere test lists them).
  if (far.Empty() || (gross_rows && FewEnoughToBeGross(far.rows, records.size()))) return;
  const std::string cause =
      millimetres && far.rows * 2 > records.size()
          ? "; the coordinates look like millimetres (SPEC 1: metres)"
          : "; x, y, z or d is wrong (a mistyped coordinate, another reference frame?)";
  far.Report(file, "x",
             "a point in metres about d = " + Num(first_d) +
                 " m from the instrument, so within 2 (d + sqrt(3) d_max) + 1 m = " +
                 Significant(bound(first_d)) + " m of the median of the points (SPEC 1; d_max = " +
                 Num(d_max) + " m); it is " + Significant(first_distance) + " m from it" + cause,
             out);
}

void CheckKnownPoints(const std::string& file, const std::vector<PixelObservation>& pixels,
                      double max_extent_m, ScreenFindings* out) {
  Offenders far;
  double first = 0;
  bool millimetres = true;
  for (const PixelObservation& p : pixels) {
    const double r = p.X.norm();
    if (r <= max_extent_m) continue;
    if (far.Empty()) first = r;
    far.Add(p.line, PointText(p.X));
    millimetres = millimetres && r / kMmPerM <= max_extent_m;
  }
  far.Report(file, "X",
             "a known point in metres within screen.max_extent_m = " + Num(max_extent_m) +
                 " m of the origin (SPEC 1); it is " + Significant(first) + " m away" +
                 (millimetres ? "; the coordinates look like millimetres" : ""),
             out);
}

// SPEC 2: zoom levels are 0..N-1. Memory and time of the later stages grow
// with the largest zoom, so it is bounded by the data's count of levels.
void CheckZooms(const Observations& obs, const std::vector<CameraTool>& cameras,
                int max_missing_zooms, ScreenFindings* out) {
  std::set<int> levels;
  for (const Record& r : obs.records) {
    if (r.tool == Tool::kCam) levels.insert(r.zoom);
  }
  for (const PixelObservation& p : obs.pixels) levels.insert(p.zoom);
  if (levels.empty()) return;
  const long long known = std::max<long long>(cameras.size(), levels.size());
  const long long limit = known + max_missing_zooms;
  const std::vector<int> level_list(levels.begin(), levels.end());
  const std::string expected =
      "a zoom level below " + std::to_string(limit) +
      " (SPEC 2: zoom levels are 0..N-1; the data hold " + std::to_string(levels.size()) +
      " zoom level" + (levels.size() == 1 ? "" : "s") + " (" + JoinInts(level_list, 8) +
      "), model.cameras lists " + std::to_string(cameras.size()) +
      ", and screen.max_missing_zooms = " + std::to_string(max_missing_zooms) +
      " more may lack data)";
  Offenders record_zooms, pixel_zooms;
  for (const Record& r : obs.records) {
    if (r.tool == Tool::kCam && r.zoom >= limit) record_zooms.Add(r.line, std::to_string(r.zoom));
  }
  for (const PixelObservation& p : obs.pixels) {
    if (p.zoom >= limit) pixel_zooms.Add(p.line, std::to_string(p.zoom));
  }
  record_zooms.Report(obs.records_source, "zoom", expected, out);
  pixel_zooms.Report(obs.pixels_source, "zoom", expected, out);
  if (!record_zooms.Empty() || !pixel_zooms.Empty()) return;
  std::vector<int> missing;
  for (int z = 0; z < *levels.rbegin(); ++z) {
    if (!levels.count(z)) missing.push_back(z);
  }
  if (!missing.empty()) {
    out->warnings.push_back("zoom level" + std::string(missing.size() == 1 ? " " : "s ") +
                            JoinInts(missing, 8) +
                            " have no camera rows and no pixels (the data use " +
                            JoinInts(level_list, 8) + "); their cameras are not calibrated");
  }
}

// Records that determine only one of the two tools.
void CheckTools(const Observations& obs, ScreenFindings* out) {
  if (obs.records.empty()) return;
  const auto edm = std::count_if(obs.records.begin(), obs.records.end(),
                                 [](const Record& r) { return r.tool == Tool::kEdm; });
  const size_t cam = obs.records.size() - static_cast<size_t>(edm);
  if (edm == 0) {
    out->warnings.push_back(obs.records_source + " has camera rows only (no edm rows): the EDM " +
                            "tool is not determined and keeps its starting pose");
  } else if (cam == 0 && obs.pixels.empty()) {
    out->warnings.push_back(obs.records_source + " has EDM rows only (no cam rows) and there " +
                            "are no pixels: the camera tools are not determined");
  }
}

}  // namespace

ScreenFindings FindDataMistakes(const Observations& obs, const std::vector<CameraTool>& cameras,
                                const ScreenOptions& options) {
  const std::string problem = options.Check();
  if (!problem.empty()) throw std::invalid_argument("screen options: " + problem);
  ScreenFindings out;
  const std::vector<RowView> record_rows = RowsOf(obs.records);
  const std::vector<RowView> pixel_rows = RowsOf(obs.pixels);
  CheckZooms(obs, cameras, options.max_missing_zooms, &out);
  // With the gross-error screening on (gross.h), a few offending rows are
  // its business; off, every offending row is an error here.
  const bool gross_rows = options.gross_errors.enabled;
  CheckAngles(obs.records_source, record_rows, obs.angle_unit, gross_rows, &out);
  CheckAngles(obs.pixels_source, pixel_rows, obs.angle_unit, gross_rows, &out);
  CheckPixels(obs.records_source, record_rows, cameras, options.pixel_margin_px, &out);
  CheckPixels(obs.pixels_source, pixel_rows, cameras, options.pixel_margin_px, &out);
  CheckRecordPoints(obs.records_source, obs.records, gross_rows, &out);
  CheckKnownPoints(obs.pixels_source, obs.pixels, options.max_extent_m, &out);
  CheckTools(obs, &out);
  for (std::string& notice : DuplicateRowNotices(obs)) out.warnings.push_back(std::move(notice));
  return out;
}

std::vector<std::string> ScreenObservations(const Observations& obs,
                                            const std::vector<CameraTool>& cameras,
                                            const ScreenOptions& options) {
  ScreenFindings findings = FindDataMistakes(obs, cameras, options);
  if (!findings.errors.empty()) throw InputError::Combine(findings.errors);
  for (std::string& w : findings.warnings) w = "screening: " + w;
  return findings.warnings;
}

}  // namespace rtscalib

#include "libcalib/diagnose/structure.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>
#include <tuple>

#include "libcalib/model/focus.h"
#include "libcalib/text/number_text.h"

namespace rtscalib {
namespace {

constexpr double kArcsecPerRad = 180.0 * 3600.0 / M_PI;
const double kNaN = std::numeric_limits<double>::quiet_NaN();

// A focus distance column differs from the target distance when some photo's
// two differ by more than this fraction: otherwise the two variables are one.
constexpr double kSameDistance = 1e-3;

// Distinct finite values of `values` at `rows` (stops counting at `enough`).
int Distinct(const std::vector<double>& values, const std::vector<int>& rows, int enough) {
  std::set<double> seen;
  for (int i : rows) {
    if (std::isfinite(values[i])) seen.insert(values[i]);
    if (static_cast<int>(seen.size()) >= enough) break;
  }
  return static_cast<int>(seen.size());
}

// Whether `a` is an affine function of `b` wherever both are finite (a
// covariate that only repeats the order of the rows, e.g. an index column).
bool SameOrder(const std::vector<double>& a, const std::vector<double>& b) {
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  int n = 0;
  for (size_t i = 0; i < a.size() && i < b.size(); ++i) {
    if (!std::isfinite(a[i]) || !std::isfinite(b[i])) continue;
    sa += a[i];
    sb += b[i];
    saa += a[i] * a[i];
    sbb += b[i] * b[i];
    sab += a[i] * b[i];
    ++n;
  }
  if (n < 3) return false;
  const double va = saa - sa * sa / n, vb = sbb - sb * sb / n, cab = sab - sa * sb / n;
  return va > 0 && vb > 0 && std::abs(cab) > (1.0 - 1e-9) * std::sqrt(va * vb);
}

bool IsOrder(const SessionVariable& v) {
  return v.name == "photo order" || v.name == "record order";
}
bool IsDistance(const SessionVariable& v) {
  return v.name == "target distance" || v.name == "focus distance";
}

}  // namespace

std::vector<SessionVariable> SessionVariables(const Observations& obs,
                                              const InstrumentModel& model) {
  std::vector<SessionVariable> out;
  const size_t nr = obs.records.size(), np = obs.pixels.size();
  auto make = [&](const std::string& name, const std::string& unit) {
    SessionVariable v;
    v.name = name;
    v.unit = unit;
    v.record.assign(nr, kNaN);
    v.pixel.assign(np, kNaN);
    return v;
  };

  // Target distance: a photo's centroid distance, a record's d.
  SessionVariable target = make("target distance", "m");
  const std::vector<double> centroid = PhotoFocusDistances(model, obs.pixels, &obs.targets, false);
  for (size_t i = 0; i < np; ++i) {
    if (centroid[i] > 0) target.pixel[i] = centroid[i];
  }
  for (size_t i = 0; i < nr; ++i) target.record[i] = obs.records[i].d;
  out.push_back(target);

  // Focus distance, when the photos report one that is not the target distance.
  SessionVariable focus = make("focus distance", "m");
  bool given = false, differs = false;
  for (size_t i = 0; i < np; ++i) {
    const double d = obs.pixels[i].focus_distance;
    if (!(d > 0)) continue;
    given = true;
    focus.pixel[i] = d;
    if (centroid[i] > 0 && std::abs(d / centroid[i] - 1.0) > kSameDistance) differs = true;
  }
  if (given && differs) out.push_back(focus);

  // The order the photos were taken in: the first appearance of each shot.
  SessionVariable photo_order = make("photo order", "");
  std::map<std::tuple<std::string, int, double, double>, int> photo_index;
  for (size_t i = 0; i < np; ++i) {
    const PixelObservation& p = obs.pixels[i];
    const auto key = std::make_tuple(p.shot, p.zoom, p.phi, p.theta);
    const auto it = photo_index.emplace(key, static_cast<int>(photo_index.size())).first;
    photo_order.pixel[i] = it->second;
  }
  if (photo_index.size() >= 3) out.push_back(photo_order);
  SessionVariable record_order = make("record order", "");
  for (size_t i = 0; i < nr; ++i) record_order.record[i] = static_cast<double>(i);
  if (nr >= 3) out.push_back(record_order);

  // Covariates, one variable per name over both files.
  std::vector<std::string> names = obs.record_covariates;
  for (const std::string& n : obs.pixel_covariates) {
    if (std::find(names.begin(), names.end(), n) == names.end()) names.push_back(n);
  }
  for (const std::string& name : names) {
    SessionVariable v = make(name, "");
    const auto r = std::find(obs.record_covariates.begin(), obs.record_covariates.end(), name);
    if (r != obs.record_covariates.end()) {
      const size_t k = r - obs.record_covariates.begin();
      for (size_t i = 0; i < nr; ++i) {
        if (k < obs.records[i].covariates.size()) v.record[i] = obs.records[i].covariates[k];
      }
    }
    const auto p = std::find(obs.pixel_covariates.begin(), obs.pixel_covariates.end(), name);
    if (p != obs.pixel_covariates.end()) {
      const size_t k = p - obs.pixel_covariates.begin();
      for (size_t i = 0; i < np; ++i) {
        if (k < obs.pixels[i].covariates.size()) v.pixel[i] = obs.pixels[i].covariates[k];
      }
    }
    // A covariate that repeats the order of the photos or rows adds nothing.
    bool repeats = false;
    for (const SessionVariable& o : out) {
      if (IsOrder(o) && (SameOrder(v.pixel, o.pixel) || SameOrder(v.record, o.record))) {
        repeats = true;
      }
    }
    if (!repeats) out.push_back(v);
  }

  // Categories: placements, and the boards the points lie on. Only where
  // every point's position is known: a board whose pose is estimated (per
  // placement, SPEC 7.1) moves its own image by scale, shift and rotation,
  // so an image motion per such category is the pose itself to first order
  // (nearly absorbed: its fitted size is meaningless, and as a nuisance it
  // would take the catalogue's effects with it, e.g. an eccentricity that
  // shifts each placement's photos by face).
  bool all_known = model.boards.empty();
  for (size_t i = 0; i < np; ++i) all_known = all_known && obs.pixels[i].X_known;
  if (!all_known) return out;
  SessionVariable placement = make("placement", "");
  placement.categorical = true;
  std::map<std::string, int> placement_index;
  for (size_t i = 0; i < np; ++i) {
    const auto it = placement_index
                        .emplace(obs.pixels[i].placement, static_cast<int>(placement_index.size()))
                        .first;
    placement.pixel[i] = it->second;
  }
  placement.categories.resize(placement_index.size());
  for (const auto& [name, index] : placement_index) {
    placement.categories[index] = name.empty() ? "(none)" : name;
  }
  if (placement.categories.size() >= 2 &&
      static_cast<int>(placement.categories.size()) <= kMaxTrendFunctions) {
    out.push_back(placement);
  }
  SessionVariable board = make("board", "");
  board.categorical = true;
  std::map<int, int> board_index;
  for (size_t i = 0; i < np; ++i) {
    for (size_t b = 0; b < obs.targets.boards.size(); ++b) {
      if (!obs.targets.boards[b].HasId(obs.pixels[i].target)) continue;
      const auto it = board_index.emplace(static_cast<int>(b), static_cast<int>(board_index.size()))
                          .first;
      board.pixel[i] = it->second;
      break;
    }
  }
  board.categories.resize(board_index.size());
  for (const auto& [b, index] : board_index) {
    board.categories[index] = "board " + std::to_string(obs.targets.boards[b].first_id);
  }
  if (board.categories.size() >= 2 &&
      static_cast<int>(board.categories.size()) <= kMaxTrendFunctions) {
    out.push_back(board);
  }
  return out;
}

std::vector<Probe> StructureProbes(const std::vector<SessionVariable>& variables,
                                   const Observations& obs, const InstrumentModel& model,
                                   bool readings) {
  std::vector<Probe> out;
  // Rows per kind: records, EDM records, and per zoom the pixels and camera records.
  std::vector<int> all_records, edm_records;
  std::map<int, std::vector<int>> zoom_pixels, zoom_cam;
  for (size_t i = 0; i < obs.records.size(); ++i) {
    all_records.push_back(static_cast<int>(i));
    if (obs.records[i].tool == Tool::kEdm) {
      edm_records.push_back(static_cast<int>(i));
    } else if (obs.records[i].zoom >= 0 && obs.records[i].zoom < model.NumZooms()) {
      zoom_cam[obs.records[i].zoom].push_back(static_cast<int>(i));
    }
  }
  std::vector<int> all_pixels;
  for (size_t i = 0; i < obs.pixels.size(); ++i) {
    all_pixels.push_back(static_cast<int>(i));
    if (obs.pixels[i].zoom >= 0 && obs.pixels[i].zoom < model.NumZooms()) {
      zoom_pixels[obs.pixels[i].zoom].push_back(static_cast<int>(i));
    }
  }
  // Enough distinct values for a trend on these rows.
  auto varies = [](const SessionVariable& v, const std::vector<int>& records,
                   const std::vector<int>& pixels) {
    const int need = v.categorical ? 2 : 3;
    return std::max(Distinct(v.record, records, need), 0) + Distinct(v.pixel, pixels, need) >=
           need;
  };

  if (readings) {
    for (size_t k = 0; k < variables.size(); ++k) {
      const SessionVariable& v = variables[k];
      if (v.categorical || IsDistance(v)) continue;
      Probe p;
      p.kind = ProbeKind::kReadingTrend;
      p.session_variable = static_cast<int>(k);
      p.form = IsOrder(v) ? TrendForm::kQuadratic : TrendForm::kLinear;
      if (varies(v, all_records, all_pixels)) {
        for (Reading r : {Reading::kPhi, Reading::kTheta}) {
          p.reading = r;
          out.push_back(p);
        }
      }
      if (varies(v, edm_records, {})) {
        p.reading = Reading::kDistance;
        p.per_metre = false;
        out.push_back(p);
        p.per_metre = true;
        out.push_back(p);
      }
    }
  }
  for (int z = 0; z < model.NumZooms(); ++z) {
    const std::vector<int>& pixels = zoom_pixels[z];
    const std::vector<int>& cams = zoom_cam[z];
    if (pixels.empty() && cams.empty()) continue;
    for (size_t k = 0; k < variables.size(); ++k) {
      const SessionVariable& v = variables[k];
      if (v.name == "record order") continue;  // camera records are not photos
      if (!varies(v, cams, pixels)) continue;
      Probe p;
      p.kind = ProbeKind::kImageMotion;
      p.zoom = z;
      p.session_variable = static_cast<int>(k);
      if (v.categorical) {
        p.form = TrendForm::kCategories;
        out.push_back(p);
      } else if (IsDistance(v)) {
        p.form = TrendForm::kInverse;
        out.push_back(p);
        if (v.name == "target distance") {
          p.form = TrendForm::kLinear;
          out.push_back(p);
        }
      } else {
        p.form = IsOrder(v) ? TrendForm::kQuadratic : TrendForm::kLinear;
        out.push_back(p);
      }
    }
    if (!pixels.empty()) {
      for (ImageField f : {ImageField::kPosition, ImageField::kRadius}) {
        Probe p;
        p.kind = ProbeKind::kImageField;
        p.zoom = z;
        p.field = f;
        out.push_back(p);
      }
    }
  }
  return out;
}

namespace {

// The probe's modelled error at x (reading trends: the reading's error in
// SI; image motions: the four motions), from the regression coefficients of
// the residual on its columns (which are minus the missing terms).
void TrendAt(const ColumnBlock& b, const Eigen::VectorXd& beta, double x, double* out, int n) {
  double f[kMaxTrendFunctions];
  b.basis.Evaluate(x, f);
  const int per = b.basis.size;
  for (int m = 0; m < n; ++m) {
    out[m] = 0;
    for (int j = 0; j < per; ++j) out[m] -= beta[m * per + j] * f[j];
  }
}

// The values of the variable to evaluate a trend at: the categories, or a
// grid over its range.
std::vector<double> Samples(const ColumnBlock& b) {
  std::vector<double> xs;
  if (b.basis.form == TrendForm::kCategories) {
    for (int c = 0; c < b.basis.size; ++c) xs.push_back(c);
    return xs;
  }
  constexpr int kGrid = 33;
  for (int i = 0; i < kGrid; ++i) xs.push_back(b.basis.lo + (b.basis.hi - b.basis.lo) * i / (kGrid - 1));
  return xs;
}

std::string ReadingWords(Reading r) {
  switch (r) {
    case Reading::kPhi:
      return "phi (horizontal angle) error";
    case Reading::kTheta:
      return "theta (vertical angle) error";
    case Reading::kDistance:
      return "distance error";
  }
  return "";
}

std::string FormWords(const ColumnBlock& b, const SessionVariable& v) {
  switch (b.basis.form) {
    case TrendForm::kLinear:
      return "changes in proportion to " + v.name;
    case TrendForm::kInverse:
      return "changes as 1/" + v.name;
    case TrendForm::kQuadratic:
      return IsOrder(v) ? "drifts slowly with the " + v.name : "changes smoothly with " + v.name;
    case TrendForm::kCategories:
      return "changes per " + v.name;
  }
  return "";
}

std::string Range(const ColumnBlock& b, const SessionVariable& v) {
  if (b.basis.form == TrendForm::kCategories) {
    return "over " + std::to_string(b.basis.size) + " " + v.name + "s";
  }
  if (IsOrder(v)) {
    return "from the first to the last " + std::string(v.name == "photo order" ? "photo" : "row");
  }
  return "over " + v.name + " " + Fmt("%.3g", b.basis.lo) + " to " + Fmt("%.3g", b.basis.hi) +
         (v.unit.empty() ? "" : " " + v.unit);
}

// What a finding suggests when no catalogue effect removes it.
std::string Hint(const ColumnBlock& b, const SessionVariable* v, const InstrumentModel& model) {
  const Probe& p = b.probe;
  if (p.kind == ProbeKind::kImageField) {
    return "lens distortion that the model's distortion groups do not hold (try the other "
           "groups of the catalogue, or a zoom whose field is too narrow for its coefficients)";
  }
  if (p.kind == ProbeKind::kImageMotion && v && IsDistance(*v)) {
    return model.effects.Has(Effect::kFocus)
               ? "a focus that is not first order in 1/D (the catalogue's focus is in the model)"
               : "the camera refocusing on each target: the catalogue effect focus "
                 "(model.effects: [..., focus])";
  }
  if (p.kind == ProbeKind::kImageMotion && v && v->categorical) {
    return "a " + v->name +
           " of its own: a surveyed pose or a print scale off, or a board that moved within its "
           "placement";
  }
  if (v && IsOrder(*v)) {
    return p.kind == ProbeKind::kImageMotion
               ? "the camera changing during the session (not in the catalogue)"
               : "a drift of the instrument during the session, e.g. with its temperature (not "
                 "in the catalogue)";
  }
  if (v) return "a dependence on " + v->name + " (not in the catalogue)";
  return "";
}

StructureFinding MakeFinding(const ColumnBlock& b, const ColumnTest& t, const Reduced& red,
                             const Linearization& lin, const InstrumentModel& model) {
  StructureFinding f;
  f.probe = b.probe;
  f.block = b.name;
  f.wald = t.wald;
  f.p_value = t.p_value;
  const Probe& p = b.probe;
  const SessionVariable* v =
      p.session_variable >= 0 ? &lin.variables.at(p.session_variable) : nullptr;
  if (v) {
    f.variable = v->name;
    f.form = FormWords(b, *v);
    f.lo = b.basis.lo;
    f.hi = b.basis.hi;
  }
  std::string size_text;
  if (p.kind == ProbeKind::kReadingTrend) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (double x : Samples(b)) {
      double e = 0;
      TrendAt(b, t.beta, x, &e, 1);
      lo = std::min(lo, e);
      hi = std::max(hi, e);
    }
    const bool distance = p.reading == Reading::kDistance;
    f.unit = distance ? (p.per_metre ? "ppm" : "mm") : "arcsec";
    f.size = (hi - lo) * (distance ? (p.per_metre ? 1e6 : 1e3) : kArcsecPerRad);
    f.quantity = p.per_metre ? "EDM scale" : ReadingWords(p.reading);
    size_text = Fmt("%.3g", f.size) + " " + f.unit;
  } else if (p.kind == ProbeKind::kImageMotion) {
    // Range of each motion, in pixels at the image corner (scale and
    // rotation times the half-diagonal) and in its own unit.
    const CameraTool& cam = model.cams.at(p.zoom);
    const double corner = std::hypot(0.5 * cam.width, 0.5 * cam.height);
    double lo[kNumImageMotions], hi[kNumImageMotions], first[kNumImageMotions],
        last[kNumImageMotions];
    std::fill(lo, lo + kNumImageMotions, std::numeric_limits<double>::infinity());
    std::fill(hi, hi + kNumImageMotions, -std::numeric_limits<double>::infinity());
    const std::vector<double> xs = Samples(b);
    for (size_t i = 0; i < xs.size(); ++i) {
      double m[kNumImageMotions];
      TrendAt(b, t.beta, xs[i], m, kNumImageMotions);
      for (int k = 0; k < kNumImageMotions; ++k) {
        lo[k] = std::min(lo[k], m[k]);
        hi[k] = std::max(hi[k], m[k]);
        if (i == 0) first[k] = m[k];
        last[k] = m[k];
      }
    }
    double px[kNumImageMotions];
    for (int k = 0; k < kNumImageMotions; ++k) {
      px[k] = (hi[k] - lo[k]) * (k == 0 || k == 3 ? corner : 1.0);
    }
    const int main = static_cast<int>(std::max_element(px, px + kNumImageMotions) - px);
    const char* kWhat[kNumImageMotions] = {"image scale", "principal point u", "principal point v",
                                           "image rotation"};
    f.quantity = std::string(kWhat[main]) + " of zoom " + std::to_string(p.zoom);
    f.unit = "px";
    f.size = px[main];
    std::string parts;
    for (int k = 0; k < kNumImageMotions; ++k) {
      if (px[k] < 0.3 * px[main]) continue;
      std::string part = std::string(kWhat[k]) + " ";
      if (k == 0) part += Fmt("%.3g", (hi[k] - lo[k]) * 1e6) + " ppm, ";
      if (k == 3) part += Fmt("%.3g", (hi[k] - lo[k]) * kArcsecPerRad) + " arcsec, ";
      part += Fmt("%.3g", px[k]) + " px" + (k == 0 || k == 3 ? " at the image corner" : "");
      if (b.basis.form != TrendForm::kCategories) {
        part += last[k] > first[k] ? " (growing with " : " (shrinking with ";
        part += v ? v->name + ")" : "x)";
      }
      parts += (parts.empty() ? "" : "; ") + part;
    }
    size_text = parts;
  } else {
    // Image fields: the largest displacement at the data (the field is a
    // polynomial: beyond the points it is extrapolation, not structure), of
    // the field's part that the model's own parameters cannot take up (the
    // columns projected out of them, red.extra): with boards of estimated
    // pose a degree-2 field is nearly a tilt of each board, and the raw
    // field's coefficients then grow without bound while what it changes in
    // the residuals stays small.
    f.quantity = "image displacement field of zoom " + std::to_string(p.zoom) + " (" +
                 (p.field == ImageField::kPosition ? "over the image position" : "along the radius") +
                 ")";
    f.form = p.field == ImageField::kPosition ? "degree 2 and 3 in the image position"
                                              : "odd powers of the radius";
    f.variable = p.field == ImageField::kPosition ? "image position" : "image radius";
    f.unit = "px";
    const double sigma = lin.sigma[static_cast<int>(ObsGroup::kPixel)];
    std::map<int, Eigen::Vector2d> at;  // per image observation: the fitted displacement
    for (int i = 0; i < lin.NumRows(); ++i) {
      const ResidualRow& row = lin.rows[i];
      if (row.group != ObsGroup::kPixel) continue;
      double value = 0;
      for (int j = 0; j < b.size; ++j) value -= red.extra(i, b.first + j) * t.beta[j];
      if (value == 0) continue;
      auto it = at.emplace(row.index, Eigen::Vector2d::Zero()).first;
      it->second[row.component] = value * sigma;
    }
    for (const auto& [index, d] : at) f.size = std::max(f.size, d.norm());
    size_text = "up to " + Fmt("%.3g", f.size) + " px";
  }
  f.description = f.quantity + " " + (v ? f.form : "has structure of " + f.form) + ": " +
                  size_text + (v ? " " + Range(b, *v) : "");
  f.points_to = Hint(b, v, model);
  return f;
}

// Below these a statistically significant trend is round-off of exact data,
// not structure: no instrument resolves 1e-3 arcsec, 1e-3 mm or 1e-3 ppm,
// and 1e-6 px is ranking.h's pixel floor. In the image, also a tenth of the
// pixel sigma: with 20,000 corners a field of a few thousandths of a pixel
// is significant, but it is the detector's own systematic error on the
// photos (docs/rendering.md measures ~0.003 px on rendered ones), nothing a
// model term would buy and nothing a user should chase.
bool AboveFloor(const StructureFinding& f, double pixel_sigma) {
  if (f.unit == "px") return f.size > std::max(1e-6, 0.1 * pixel_sigma);
  return f.size > 1e-3;  // arcsec, mm, ppm
}

}  // namespace

StructureAnalysis AnalyseStructure(const Linearization& lin, const Reduced& red,
                                   const ProbeAnalysis& probes, const InstrumentModel& model) {
  StructureAnalysis out;
  const double pixel_sigma = lin.sigma[static_cast<int>(ObsGroup::kPixel)];
  for (int s : probes.selected) {
    const ProbeResult& r = probes.probes[s];
    if (r.block->probe.kind == ProbeKind::kHarmonic) continue;
    StructureFinding f = MakeFinding(*r.block, r.joint, red, lin, model);
    f.unexplained = true;
    if (AboveFloor(f, pixel_sigma)) out.unexplained.push_back(f);
  }
  for (const ProbeResult& r : probes.probes) {
    if (r.block->probe.kind == ProbeKind::kHarmonic || !r.raw_significant || r.selected) continue;
    StructureFinding f = MakeFinding(*r.block, r.raw, red, lin, model);
    f.explained_by = r.explained_by;
    f.same_as = r.same_as;
    if (AboveFloor(f, pixel_sigma)) out.explained.push_back(f);
  }
  // Most significant first (by the test's statistic per degree of freedom
  // would favour small probes; the p-value saturates at 0, so the Wald).
  std::stable_sort(out.explained.begin(), out.explained.end(),
                   [](const StructureFinding& a, const StructureFinding& b) { return a.wald > b.wald; });
  return out;
}

}  // namespace rtscalib

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
    // Found on top of every distortion group of the catalogue: a lens
    // beyond them, or what a board's own shape (not flat, not printed to
    // scale) does to the corners it shows.
    return std::string("lens distortion beyond the catalogue's distortion groups") +
           (model.boards.empty() ? "" : ", or boards that are not flat") +
           " (a zoom whose photos cover little of the image cannot tell these apart)";
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

// The largest displacement the whitened rows `v` make at one observation,
// in its unit: px at image points, mm at camera or EDM records (image
// points first: a probe of a zoom with photos is said in pixels).
struct AtData {
  double size = 0;
  std::string unit = "px";
};
AtData LargestAtData(const Linearization& lin, const Eigen::VectorXd& v) {
  std::map<std::pair<int, int>, double> squares;  // (group, observation) -> |displacement|^2
  for (int i = 0; i < lin.NumRows(); ++i) {
    if (v[i] == 0) continue;
    const ResidualRow& row = lin.rows[i];
    const int g = static_cast<int>(row.group);
    const double x = v[i] * lin.sigma[g] * (row.group == ObsGroup::kPixel ? 1.0 : 1e3);
    squares[{g, row.index}] += x * x;
  }
  double px = 0, mm = 0;
  for (const auto& [key, sq] : squares) {
    (key.first == static_cast<int>(ObsGroup::kPixel) ? px : mm) =
        std::max(key.first == static_cast<int>(ObsGroup::kPixel) ? px : mm, sq);
  }
  AtData out;
  if (px > 0 || mm == 0) {
    out.size = std::sqrt(px);
  } else {
    out.size = std::sqrt(mm);
    out.unit = "mm";
  }
  return out;
}

// "; the points reach 83 % of the half-diagonal": where the data of a zoom end.
std::string ReachText(const Probe& p, const Materiality& scale) {
  if (p.zoom < 0 || p.zoom >= static_cast<int>(scale.reach.size()) || !(scale.reach[p.zoom] > 0))
    return "";
  return "; the observed points reach " + Fmt("%.0f", 100 * scale.reach[p.zoom]) +
         " % of the image's half-diagonal";
}

// `t` is the test of the probe's columns `columns` (after whatever was
// projected out of them): its fitted values are what the probe changes in
// the residuals beyond everything else fitted, which is what a size states.
// Regression coefficients of a probe nearly absorbed by the model or the
// catalogue are large while the columns left are small, so the coefficients
// alone (a motion evaluated at the image corner, a field where no photo
// reached) are never the size.
// `test` gives the finding's significance; `t` and `columns` its gain and
// sizes (for a selected probe, where the selection took it: what it adds).
StructureFinding MakeFinding(const ColumnBlock& b, const ColumnTest& test, const ColumnTest& t,
                             const Eigen::Ref<const Eigen::MatrixXd>& columns, const Reduced& red,
                             const Linearization& lin, const InstrumentModel& model,
                             const Materiality& scale) {
  StructureFinding f;
  f.probe = b.probe;
  f.block = b.name;
  f.wald = test.wald;
  f.p_value = test.p_value;
  f.gain = RelativeGain(scale.current, RmsLess(lin, scale.current, t.fitted));
  f.material = scale.Material(f.gain);
  const Probe& p = b.probe;
  const SessionVariable* v =
      p.session_variable >= 0 ? &lin.variables.at(p.session_variable) : nullptr;
  if (v) {
    f.variable = v->name;
    f.form = FormWords(b, *v);
    f.lo = b.basis.lo;
    f.hi = b.basis.hi;
  }
  if (p.zoom >= 0 && p.zoom < static_cast<int>(scale.reach.size())) f.reach = scale.reach[p.zoom];
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
    // Each motion's own displacement at the observed points, and beside it
    // its parameter (ppm, arcsec) and direction where the motion is its own:
    // the model's parameters leave at least half of its columns (a camera
    // on a bench turns every image scale into board distances), and what is
    // left of it beyond everything else fitted is at least half of that.
    const int per = b.basis.size;
    double first[kNumImageMotions], last[kNumImageMotions], lo[kNumImageMotions],
        hi[kNumImageMotions];
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
    AtData net[kNumImageMotions];
    bool own[kNumImageMotions];
    for (int k = 0; k < kNumImageMotions; ++k) {
      const Eigen::VectorXd beta = t.beta.segment(k * per, per);
      net[k] = LargestAtData(lin, columns.middleCols(k * per, per) * beta);
      const AtData alone = LargestAtData(lin, red.extra.middleCols(b.first + k * per, per) * beta);
      const double kept = red.kept_fraction.segment(b.first + k * per, per).maxCoeff();
      own[k] = kept >= 0.5 && net[k].size >= 0.5 * alone.size;
    }
    int main = 0;
    for (int k = 1; k < kNumImageMotions; ++k) {
      if (net[k].size > net[main].size) main = k;
    }
    const char* kWhat[kNumImageMotions] = {"image scale", "principal point u", "principal point v",
                                           "image rotation"};
    f.quantity = std::string(kWhat[main]) + " of zoom " + std::to_string(p.zoom);
    f.unit = net[main].unit;
    f.size = net[main].size;
    std::string parts;
    for (int k = 0; k < kNumImageMotions; ++k) {
      if (net[k].size < 0.3 * net[main].size || !(net[k].size > 0)) continue;
      std::string part = std::string(kWhat[k]) + " " + Fmt("%.3g", net[k].size) + " " + net[k].unit;
      if (own[k]) {
        if (k == 0) part += ", " + Fmt("%.3g", (hi[k] - lo[k]) * 1e6) + " ppm";
        if (k == 3) part += ", " + Fmt("%.3g", (hi[k] - lo[k]) * kArcsecPerRad) + " arcsec";
        if (b.basis.form != TrendForm::kCategories && v) {
          part += std::string(last[k] > first[k] ? ", growing with " : ", shrinking with ") +
                  v->name;
        }
      }
      parts += (parts.empty() ? "" : "; ") + part;
    }
    size_text = "up to " + Fmt("%.3g", f.size) + " " + f.unit + " at the observed points (" +
                parts + ")";
  } else {
    f.quantity = "image displacement field of zoom " + std::to_string(p.zoom) + " (" +
                 (p.field == ImageField::kPosition ? "over the image position" : "along the radius") +
                 ")";
    f.form = p.field == ImageField::kPosition ? "degree 2 and 3 in the image position"
                                              : "odd powers of the radius";
    f.variable = p.field == ImageField::kPosition ? "image position" : "image radius";
    const AtData at = LargestAtData(lin, t.fitted);
    f.unit = at.unit;
    f.size = at.size;
    size_text = "up to " + Fmt("%.3g", f.size) + " " + f.unit + " at the observed points";
  }
  f.description = f.quantity + " " + (v ? f.form : "has structure of " + f.form) + ": " +
                  size_text + (v ? " " + Range(b, *v) : "") + ReachText(p, scale);
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
                                   const ProbeAnalysis& probes, const InstrumentModel& model,
                                   const Materiality& scale) {
  StructureAnalysis out;
  const double pixel_sigma = lin.sigma[static_cast<int>(ObsGroup::kPixel)];
  for (int s : probes.selected) {
    const ProbeResult& r = probes.probes[s];
    if (r.block->probe.kind == ProbeKind::kHarmonic) continue;
    StructureFinding f = MakeFinding(*r.block, r.joint, r.at_selection, r.selection_columns, red,
                                     lin, model, scale);
    f.unexplained = true;
    if (!AboveFloor(f, pixel_sigma)) continue;
    (f.material ? out.unexplained : out.negligible).push_back(f);
  }
  for (const ProbeResult& r : probes.probes) {
    if (r.block->probe.kind == ProbeKind::kHarmonic || !r.raw_significant || r.selected) continue;
    StructureFinding f =
        MakeFinding(*r.block, r.raw, r.raw, red.extra.middleCols(r.block->first, r.block->size),
                    red, lin, model, scale);
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

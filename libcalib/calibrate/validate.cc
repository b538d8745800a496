#include "libcalib/calibrate/validate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

#include "libcalib/eval/error_measures.h"
#include "libcalib/text/number_text.h"

namespace rtscalib {
namespace {

// Medians of chi distributions (the length of a k-vector of unit normals):
// sqrt of the chi-squared medians 2.365974 (k = 3) and 2 ln 2 (k = 2).
constexpr double kChiMedian3 = 1.5381722;
constexpr double kChiMedian2 = 1.1774100;

std::string Sci(double x, int digits = 2) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*e", digits, x);
  return buf;
}

enum class Group { kEdm = 0, kCam = 1, kPixel = 2 };

// One row's residual: r [m or px] and r / sigma_a_priori.
struct RowResidual {
  Group group;
  std::string where;  // file:line
  double r = 0;
  double normalized = 0;
  bool finite = true;  // (r / sigma)^2 finite: what the fit's cost adds up
};

std::string WhereOf(const std::string& source, int line, int index) {
  return line > 0 ? source + ":" + std::to_string(line)
                  : source + " row " + std::to_string(index + 1);
}

// Residuals of every row the fit uses (outside the critical regions).
std::vector<RowResidual> Residuals(const Observations& obs, const InstrumentModel& model,
                                   const FitOptions& options) {
  std::vector<RowResidual> out;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<Record> records;
  std::vector<int> record_index;
  for (size_t i = 0; i < obs.records.size(); ++i) {
    const Record& r = obs.records[i];
    if (options.critical_region.Contains(r.theta)) continue;
    if (r.tool == Tool::kCam && r.zoom >= model.NumZooms()) continue;  // Refine rejects these
    records.push_back(r);
    record_index.push_back(static_cast<int>(i));
  }
  for (const RecordResidual& rr : RecordResiduals(model, records)) {
    const Record& rec = records[rr.index];
    RowResidual row;
    row.group = rec.tool == Tool::kEdm ? Group::kEdm : Group::kCam;
    row.where = WhereOf(obs.records_source, rec.line, record_index[rr.index]);
    row.r = rr.valid ? rr.distance : nan;
    row.normalized = row.r / (row.group == Group::kEdm ? options.sigma_edm_m : options.sigma_cam_m);
    row.finite = std::isfinite(row.normalized * row.normalized);
    out.push_back(row);
  }
  std::vector<PixelObservation> pixels;
  std::vector<int> pixel_index;
  for (size_t i = 0; i < obs.pixels.size(); ++i) {
    const PixelObservation& p = obs.pixels[i];
    if (options.critical_region.Contains(p.theta)) continue;
    if (p.zoom >= model.NumZooms()) continue;
    pixels.push_back(p);
    pixel_index.push_back(static_cast<int>(i));
  }
  for (const PixelResidual& pr : PixelResiduals(model, pixels)) {
    // A point behind the camera has no residual; the fit's cost function
    // rejects it the same way (it is not a non-finite cost).
    if (!pr.valid) continue;
    const PixelObservation& p = pixels[pr.index];
    RowResidual row;
    row.group = Group::kPixel;
    row.where = WhereOf(obs.pixels_source, p.line, pixel_index[pr.index]);
    row.r = pr.delta.norm();
    row.normalized = row.r / options.sigma_pixel_px;
    row.finite = std::isfinite(row.normalized * row.normalized);
    out.push_back(row);
  }
  return out;
}

const char* GroupName(Group g) {
  switch (g) {
    case Group::kEdm:
      return "EDM";
    case Group::kCam:
      return "camera";
    case Group::kPixel:
      return "pixel";
  }
  return "?";
}

// Non-finite rows first, then the largest r / sigma.
std::vector<std::string> WorstRows(std::vector<RowResidual> rows, int max_rows) {
  std::stable_sort(rows.begin(), rows.end(), [](const RowResidual& a, const RowResidual& b) {
    if (a.finite != b.finite) return !a.finite;
    return a.normalized > b.normalized;
  });
  std::vector<std::string> out;
  for (const RowResidual& r : rows) {
    if (static_cast<int>(out.size()) >= max_rows) break;
    const char* unit = r.group == Group::kPixel ? " px" : " m";
    out.push_back(r.where + ": " + GroupName(r.group) + " residual " + Sci(r.r) + unit + " (" +
                  Sci(r.normalized) + " sigma)" + (r.finite ? "" : ", cost not finite"));
  }
  return out;
}

// Parameter blocks that are not finite, by name.
std::vector<std::string> NonFiniteParameters(const InstrumentModel& m) {
  std::vector<std::string> out;
  auto all_finite = [](const auto& a) {
    return std::all_of(a.begin(), a.end(), [](double x) { return std::isfinite(x); });
  };
  auto pose = [&](const PoseBlock& p, const std::string& name) {
    if (!all_finite(p.q) || !all_finite(p.t)) out.push_back(name);
  };
  pose(m.base, "base");
  pose(m.edm, "edm");
  for (int k = 0; k < 2; ++k) {
    if (!all_finite(m.links[k].p)) out.push_back("link " + std::to_string(k + 1));
  }
  for (int z = 0; z < m.NumZooms(); ++z) {
    const std::string zoom = "zoom " + std::to_string(z);
    pose(m.cams[z].flange_from_cam, zoom + " camera tool");
    if (!all_finite(m.cams[z].intrinsics)) out.push_back(zoom + " intrinsics");
    if (!all_finite(m.cams[z].distortion)) out.push_back(zoom + " distortion");
    if (!all_finite(m.cams[z].focus)) out.push_back(zoom + " focus");
  }
  for (Effect e : m.effects.List()) {
    if (IsKinematic(e) && !all_finite(m.EffectValue(e))) out.push_back(Info(e).name);
  }
  return out;
}

Sigma0 Sigma0Of(const std::vector<RowResidual>& rows, RobustLoss loss) {
  std::vector<double> by_group[3];
  for (const RowResidual& r : rows) by_group[static_cast<int>(r.group)].push_back(r.normalized);
  double s0[3] = {0, 0, 0};
  for (int g = 0; g < 3; ++g) {
    std::vector<double>& v = by_group[g];
    if (v.empty()) continue;
    const double k = g == static_cast<int>(Group::kPixel) ? 2.0 : 3.0;
    if (loss == RobustLoss::kNone) {
      double sum2 = 0;
      for (double x : v) sum2 += x * x;
      s0[g] = std::sqrt(sum2 / (k * static_cast<double>(v.size())));
    } else {
      std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
      s0[g] = v[v.size() / 2] / (k == 2.0 ? kChiMedian2 : kChiMedian3);
    }
  }
  Sigma0 out;
  out.edm = s0[0];
  out.cam = s0[1];
  out.pixels = s0[2];
  out.n_edm = static_cast<int>(by_group[0].size());
  out.n_cam = static_cast<int>(by_group[1].size());
  out.n_pixels = static_cast<int>(by_group[2].size());
  return out;
}

void ThrowIfNonFinite(const std::string& stage, const char* what, const InstrumentModel& model,
                      const std::vector<RowResidual>& rows, double cost, const FitChecks& checks) {
  const std::vector<std::string> params = NonFiniteParameters(model);
  const auto bad_rows =
      std::count_if(rows.begin(), rows.end(), [](const RowResidual& r) { return !r.finite; });
  if (params.empty() && bad_rows == 0 && std::isfinite(cost)) return;
  std::string reason = std::string(what) + " is not finite:";
  if (!std::isfinite(cost)) reason += " cost " + Sci(cost) + ";";
  if (!params.empty()) reason += " parameters " + Join(params) + ";";
  if (bad_rows > 0) {
    reason +=
        " " + std::to_string(bad_rows) + " row(s) whose weighted squared residual is not finite;";
  }
  reason += " the rows below have the largest residuals";
  throw CalibrationFailure(CalibrationFailure::Kind::kNonFinite, stage, reason,
                           WorstRows(rows, checks.max_rows_named));
}

}  // namespace

CalibrationFailure::CalibrationFailure(Kind kind_, std::string stage_, std::string reason_,
                                       std::vector<std::string> rows_)
    : std::runtime_error([&] {
        std::string s = stage_ + ": " + reason_;
        for (const std::string& r : rows_) s += "\n  " + r;
        return s;
      }()),
      kind(kind_),
      stage(std::move(stage_)),
      reason(std::move(reason_)),
      rows(std::move(rows_)) {}

const char* FailureKindName(CalibrationFailure::Kind kind) {
  switch (kind) {
    case CalibrationFailure::Kind::kNonFinite:
      return "non-finite";
    case CalibrationFailure::Kind::kNotConverged:
      return "not converged";
    case CalibrationFailure::Kind::kAbsurdResiduals:
      return "residuals far beyond the sigmas";
  }
  return "?";
}

std::string FitChecks::Check() const {
  if (!(max_sigma0 > 1)) return "fit.max_sigma0 must be > 1";
  if (max_rows_named < 1) return "the number of rows named in a failure must be >= 1";
  return "";
}

Sigma0 ComputeSigma0(const Observations& obs, const InstrumentModel& model,
                     const FitOptions& options) {
  return Sigma0Of(Residuals(obs, model, options), options.loss);
}

void ValidateFit(const std::string& stage, const Observations& obs, const InstrumentModel& model,
                 const FitSummary& fit, const FitOptions& options, const FitChecks& checks) {
  const std::vector<RowResidual> rows = Residuals(obs, model, options);
  ThrowIfNonFinite(stage, "the fit", model, rows, fit.final_cost, checks);
  if (!fit.converged || fit.iterations == 0) {
    throw CalibrationFailure(CalibrationFailure::Kind::kNotConverged, stage,
                             "the refinement did not converge (" + std::to_string(fit.iterations) +
                                 " iterations; Ceres:" + fit.message +
                                 "); the rows below have the largest residuals",
                             WorstRows(rows, checks.max_rows_named));
  }
  const Sigma0 s = Sigma0Of(rows, options.loss);
  std::string beyond;
  auto check = [&](const char* group, double s0, int n, double sigma, const char* unit) {
    if (n == 0 || s0 <= checks.max_sigma0) return;
    beyond += std::string(beyond.empty() ? "" : "; ") + group + " sigma0 " + Sci(s0) + " (" +
              std::to_string(n) + " rows, a-priori sigma " + Sci(sigma) + unit + ")";
  };
  check("EDM", s.edm, s.n_edm, options.sigma_edm_m, " m");
  check("camera", s.cam, s.n_cam, options.sigma_cam_m, " m");
  check("pixel", s.pixels, s.n_pixels, options.sigma_pixel_px, " px");
  if (!beyond.empty()) {
    throw CalibrationFailure(CalibrationFailure::Kind::kAbsurdResiduals, stage,
                             "residuals far beyond the stated sigmas: " + beyond +
                                 ", limit fit.max_sigma0 = " + Sci(checks.max_sigma0, 1) +
                                 " (a gross error, a wrong unit or a wrong start); the rows "
                                 "below have the largest residuals",
                             WorstRows(rows, checks.max_rows_named));
  }
}

void ValidateStart(const std::string& stage, const Observations& obs, const InstrumentModel& start,
                   const FitOptions& options, const FitChecks& checks) {
  const std::vector<std::string> params = NonFiniteParameters(start);
  if (!params.empty()) {
    // Under a non-finite start every residual is non-finite: name the rows
    // whose coordinates are largest instead, since an overflow in the start's
    // sums (centroids, Kabsch) comes from them.
    std::vector<std::pair<double, std::string>> big;
    for (size_t i = 0; i < obs.records.size(); ++i) {
      const Record& r = obs.records[i];
      const double size = std::max(r.x.cwiseAbs().maxCoeff(), std::abs(r.d));
      big.push_back({std::isfinite(size) ? size : std::numeric_limits<double>::infinity(),
                     WhereOf(obs.records_source, r.line, static_cast<int>(i)) +
                         ": largest of |x|, |y|, |z|, |d| " + Sci(size)});
    }
    std::stable_sort(big.begin(), big.end(),
                     [](const auto& a, const auto& b) { return a.first > b.first; });
    std::vector<std::string> rows;
    for (size_t i = 0; i < big.size() && static_cast<int>(i) < checks.max_rows_named; ++i)
      rows.push_back(big[i].second);
    throw CalibrationFailure(CalibrationFailure::Kind::kNonFinite, stage,
                             "non-finite parameters " + Join(params) +
                                 " (an overflow while computing the start); the records below "
                                 "have the largest values",
                             rows);
  }
  ThrowIfNonFinite(stage, "the cost at the start", start, Residuals(obs, start, options), 0.0,
                   checks);
}

std::vector<std::string> MarkUndeterminedTools(const Observations& obs, const FitOptions& options,
                                               InstrumentModel* model) {
  bool edm = false;
  std::vector<bool> zoom(model->NumZooms(), false);
  for (const Record& r : obs.records) {
    if (options.critical_region.Contains(r.theta)) continue;
    if (r.tool == Tool::kEdm) edm = true;
    if (r.tool == Tool::kCam && r.zoom >= 0 && r.zoom < model->NumZooms()) zoom[r.zoom] = true;
  }
  for (const PixelObservation& p : obs.pixels) {
    if (options.critical_region.Contains(p.theta)) continue;
    if (p.zoom >= 0 && p.zoom < model->NumZooms()) zoom[p.zoom] = true;
  }
  std::vector<std::string> notes;
  model->edm_determined = edm;
  // A camera-only model has no EDM at all (nothing to note).
  if (!edm && model->kinematics != Kinematics::kNone) {
    notes.push_back(
        "EDM tool: not determined by the data (no EDM rows outside the critical regions); "
        "model.yaml holds its start value without uncertainty and predict refuses EDM rows");
  }
  for (int z = 0; z < model->NumZooms(); ++z) {
    model->cams[z].determined = zoom[z];
    if (!zoom[z]) {
      notes.push_back("zoom " + std::to_string(z) +
                      " camera: not determined by the data (no camera rows or pixels of this "
                      "zoom outside the critical regions); model.yaml holds its start value "
                      "without uncertainty and predict refuses rows of this zoom");
    }
  }
  return notes;
}

}  // namespace rtscalib

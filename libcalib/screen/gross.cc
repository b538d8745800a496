#include "libcalib/screen/gross.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <set>
#include <stdexcept>
#include <string>

#include "libcalib/screen/duplicates.h"

namespace rtscalib {
namespace {

// Least median of squares: random 5-row samples. With 5 % gross rows a
// sample is clean with probability 0.95^5 = 0.77; with 30 %, 0.17: 200
// samples miss a clean one with probability 0.83^200 < 1e-16.
constexpr int kSamples = 200;
constexpr double kMadToSigma = 1.4826;

double Median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

struct SphereRow {
  int index = 0;  // into records
  Eigen::Vector3d x;
  double d = 0;
};

// |x - c| - d for every row.
std::vector<double> Departures(const std::vector<SphereRow>& rows, const Eigen::Vector3d& c) {
  std::vector<double> r;
  r.reserve(rows.size());
  for (const SphereRow& row : rows) r.push_back((row.x - c).norm() - row.d);
  return r;
}

// Centre c of |x_i - c| = d_i + k0 from `use` rows: linear in (c, k0,
// k0^2 - |c|^2): 2 x_i.c + 2 d_i k0 + w = |x_i|^2 - d_i^2. With one
// distance only the k0 and w columns coincide; the rank-revealing solve
// keeps c. Returns false when the rows do not determine c.
bool SolveCentre(const std::vector<SphereRow>& rows, const std::vector<int>& use,
                 Eigen::Vector3d* c) {
  const int n = static_cast<int>(use.size());
  Eigen::MatrixXd a(n, 5);
  Eigen::VectorXd b(n);
  // Centred on the first row's point: keeps the squares small.
  const Eigen::Vector3d o = rows[use[0]].x;
  for (int i = 0; i < n; ++i) {
    const SphereRow& r = rows[use[i]];
    const Eigen::Vector3d x = r.x - o;
    a.row(i) << 2 * x.transpose(), 2 * r.d, 1.0;
    b[i] = x.squaredNorm() - r.d * r.d;
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(a);
  if (qr.rank() < 4) return false;
  const Eigen::VectorXd p = qr.solve(b);
  if (!p.allFinite()) return false;
  *c = p.head<3>() + o;
  return true;
}

// Robust scale of departures about their median.
void MedianAndSigma(const std::vector<double>& r, double* median, double* sigma) {
  *median = Median(r);
  std::vector<double> dev;
  dev.reserve(r.size());
  for (double x : r) dev.push_back(std::abs(x - *median));
  *sigma = kMadToSigma * Median(dev);
}

void ScreenSphere(const std::vector<SphereRow>& rows, const std::string& what,
                  const std::vector<Record>& records, const GrossScreenOptions& options,
                  std::vector<ExcludedRow>* out) {
  if (static_cast<int>(rows.size()) < options.min_rows) return;
  std::mt19937_64 rng(0x5eed + rows.size());
  std::uniform_int_distribution<int> pick(0, static_cast<int>(rows.size()) - 1);
  double best = std::numeric_limits<double>::infinity();
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (int s = 0; s < kSamples; ++s) {
    std::set<int> sample;
    while (sample.size() < 5) sample.insert(pick(rng));
    Eigen::Vector3d c;
    if (!SolveCentre(rows, std::vector<int>(sample.begin(), sample.end()), &c)) continue;
    double median = 0, sigma = 0;
    MedianAndSigma(Departures(rows, c), &median, &sigma);
    if (sigma < best) {
      best = sigma;
      centre = c;
    }
  }
  if (!std::isfinite(best)) return;
  // Least squares on the rows within 3 robust sigmas of the best sample.
  double median = 0, sigma = 0;
  std::vector<double> r = Departures(rows, centre);
  MedianAndSigma(r, &median, &sigma);
  std::vector<int> inliers;
  const double keep = std::max(3 * sigma, options.sphere_floor_m);
  for (int i = 0; i < static_cast<int>(rows.size()); ++i) {
    if (std::abs(r[i] - median) <= keep) inliers.push_back(i);
  }
  Eigen::Vector3d refined;
  if (static_cast<int>(inliers.size()) >= options.min_rows &&
      SolveCentre(rows, inliers, &refined)) {
    centre = refined;
    r = Departures(rows, centre);
    MedianAndSigma(r, &median, &sigma);
  }
  const double limit = std::max(options.sphere_threshold * sigma, options.sphere_floor_m);
  for (int i = 0; i < static_cast<int>(rows.size()); ++i) {
    const double dev = r[i] - median;
    if (std::abs(dev) <= limit) continue;
    char buf[320];
    std::snprintf(buf, sizeof buf,
                  "%s: the point is %.6g m %s the instrument than its distance d says (the "
                  "other rows agree to %.3g m; limit %.3g m): a wrong point or distance",
                  what.c_str(), std::abs(dev), dev > 0 ? "farther from" : "nearer to", sigma,
                  limit);
    out->push_back({false, rows[i].index, records[rows[i].index].line, buf});
  }
}

// Rows without a reading (camera-only pixels, SPEC 7.1) have no face to contradict.
bool HasReading(const Record&) { return true; }
bool HasReading(const PixelObservation& p) { return p.has_reading; }

// `skip`: rows already taken out (copies of earlier rows).
template <typename Row>
void ScreenFaces(const std::vector<Row>& rows, bool pixel, const std::set<int>& skip,
                 std::vector<ExcludedRow>* out) {
  for (int face : {1, 2}) {
    std::vector<int> bad;
    size_t of_face = 0;
    for (size_t i = 0; i < rows.size(); ++i) {
      if (rows[i].face != face || !HasReading(rows[i]) || skip.count(static_cast<int>(i))) continue;
      ++of_face;
      if (FaceContradictsTheta(face, rows[i].theta)) bad.push_back(static_cast<int>(i));
    }
    if (bad.empty() || !FewEnoughToBeGross(bad.size(), of_face)) continue;
    for (int i : bad) {
      char buf[256];
      std::snprintf(buf, sizeof buf,
                    "face %d with theta = %.6g: SPEC 1 puts face %d's zenith angles in %s; the "
                    "other %zu face-%d rows follow it (a wrong face label or reading)",
                    face, rows[i].theta, face, face == 1 ? "[0, pi]" : "[pi, 2 pi]",
                    of_face - bad.size(), face);
      out->push_back({pixel, i, rows[i].line, buf});
    }
  }
}

}  // namespace

bool FaceContradictsTheta(int face, double theta) {
  return (face == 1 && theta > M_PI) || (face == 2 && theta < M_PI);
}

bool FewEnoughToBeGross(size_t offending, size_t rows) {
  return offending < rows && 10 * offending <= rows;
}

std::vector<ExcludedRow> FindGrossRows(const Observations& obs, const GrossScreenOptions& options) {
  const std::string problem = options.Check();
  if (!problem.empty()) throw std::invalid_argument(problem);
  // Copies of earlier rows are taken out whether or not gross rows are
  // looked for (duplicates.h), and before: a gross row present twice must
  // not outvote the tests below.
  std::vector<ExcludedRow> out = FindDuplicateRows(obs);
  std::set<int> excluded, excluded_pixels;
  for (const ExcludedRow& e : out) (e.pixel ? excluded_pixels : excluded).insert(e.index);
  if (!options.enabled) return out;
  ScreenFaces(obs.records, false, excluded, &out);
  for (const ExcludedRow& e : out) {
    if (!e.pixel) excluded.insert(e.index);
  }
  std::vector<SphereRow> edm;
  std::map<int, std::vector<SphereRow>> cam;
  for (int i = 0; i < static_cast<int>(obs.records.size()); ++i) {
    const Record& r = obs.records[i];
    if (!r.point.empty() || excluded.count(i)) continue;  // unknown point: no x to check
    (r.tool == Tool::kEdm ? edm : cam[r.zoom]).push_back({i, r.x, r.d});
  }
  ScreenSphere(edm, "EDM row", obs.records, options, &out);
  for (const auto& [zoom, rows] : cam)
    ScreenSphere(rows, "camera row (zoom " + std::to_string(zoom) + ")", obs.records, options,
                 &out);
  ScreenFaces(obs.pixels, true, excluded_pixels, &out);
  std::sort(out.begin(), out.end());
  return out;
}

Observations WithoutRows(const Observations& obs, const std::vector<ExcludedRow>& rows,
                         std::vector<int>* record_from, std::vector<int>* pixel_from) {
  std::set<int> records, pixels;
  for (const ExcludedRow& e : rows) (e.pixel ? pixels : records).insert(e.index);
  Observations out = obs;
  out.records.clear();
  out.pixels.clear();
  if (record_from) record_from->clear();
  if (pixel_from) pixel_from->clear();
  for (int i = 0; i < static_cast<int>(obs.records.size()); ++i) {
    if (records.count(i)) continue;
    out.records.push_back(obs.records[i]);
    if (record_from) record_from->push_back(i);
  }
  for (int i = 0; i < static_cast<int>(obs.pixels.size()); ++i) {
    if (pixels.count(i)) continue;
    out.pixels.push_back(obs.pixels[i]);
    if (pixel_from) pixel_from->push_back(i);
  }
  return out;
}

}  // namespace rtscalib

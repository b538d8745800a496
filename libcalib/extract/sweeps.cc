#include "libcalib/extract/sweeps.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <tuple>

namespace rtscalib {
namespace {

double WrapTwoPi(double a) {
  a = std::fmod(a, 2.0 * M_PI);
  return a < 0.0 ? a + 2.0 * M_PI : a;
}

// Clusters of values closer than `tol` (single linkage on the sorted values).
// With `periodic`, values are compared modulo 2 pi and the first and last
// clusters merge when they meet across 2 pi. Returns the member indices of
// each cluster, each in increasing value order.
std::vector<std::vector<int>> Cluster(const std::vector<int>& idx, const std::vector<double>& value,
                                      double tol, bool periodic) {
  std::vector<std::pair<double, int>> v;
  v.reserve(idx.size());
  for (int i : idx) v.emplace_back(periodic ? WrapTwoPi(value[i]) : value[i], i);
  std::sort(v.begin(), v.end());
  std::vector<std::vector<int>> out;
  for (size_t k = 0; k < v.size(); ++k) {
    if (k == 0 || v[k].first - v[k - 1].first > tol) out.emplace_back();
    out.back().push_back(v[k].second);
  }
  if (periodic && out.size() > 1 && v.front().first + 2.0 * M_PI - v.back().first <= tol) {
    // The last cluster sits just below 2 pi: it is the first one's start.
    std::vector<int> merged = out.back();
    merged.insert(merged.end(), out.front().begin(), out.front().end());
    out.front() = merged;
    out.pop_back();
  }
  return out;
}

double Mean(const std::vector<int>& idx, const std::vector<double>& value, bool periodic) {
  if (!periodic) {
    double s = 0;
    for (int i : idx) s += value[i];
    return s / idx.size();
  }
  double c = 0, s = 0;
  for (int i : idx) {
    c += std::cos(value[i]);
    s += std::sin(value[i]);
  }
  return WrapTwoPi(std::atan2(s, c));
}

struct GroupKey {
  int tool;  // 0 edm, 1 cam
  int zoom;
  long long d_q;
  long long du_q, dv_q;
  bool operator<(const GroupKey& o) const {
    return std::tie(tool, zoom, d_q, du_q, dv_q) < std::tie(o.tool, o.zoom, o.d_q, o.du_q, o.dv_q);
  }
};

// The most frequent label (the first of equally frequent ones).
std::string MajoritySet(const std::vector<Record>& records, const std::vector<int>& rows) {
  std::map<std::string, int> count;
  std::string best;
  int best_n = 0;
  for (int i : rows) {
    const int n = ++count[records[i].set];
    if (n > best_n) {
      best = records[i].set;
      best_n = n;
    }
  }
  return best;
}

std::string FormatNumber(double v) {
  std::ostringstream s;
  s.precision(6);
  s << v;
  return s.str();
}

}  // namespace

bool IsUsableForExtraction(const Record& r, const ExtractOptions& options) {
  if (r.face != 1) return false;
  return !options.critical_region.Contains(r.theta);
}

double Sweep::Control(const std::vector<Record>& records, int i) const {
  const Record& r = records[rows[i]];
  return joint == 1 ? WrapTwoPi(r.phi) : r.theta;
}

std::string Sweep::Describe(const std::vector<Record>& records) const {
  std::ostringstream s;
  s << "joint-" << joint << " sweep (face " << face << ", ";
  if (tool == Tool::kEdm) {
    s << "edm, d = " << FormatNumber(d) << " m";
  } else {
    s << "cam zoom " << zoom << ", ray length " << FormatNumber(d) << " m, pixel offset ("
      << FormatNumber(pixel_offset.x()) << ", " << FormatNumber(pixel_offset.y())
      << ") px from the principal point";
  }
  s << ", " << (joint == 1 ? "theta" : "phi") << " = " << FormatNumber(constant_control)
    << " rad constant, " << rows.size() << " points";
  int lo = 0, hi = 0;
  for (int i : rows) {
    const int l = records[i].line;
    if (l <= 0) continue;
    lo = lo == 0 ? l : std::min(lo, l);
    hi = std::max(hi, l);
  }
  if (lo > 0) s << ", lines " << lo << "-" << hi;
  if (!set.empty()) s << ", set '" << set << "'";
  s << ")";
  return s.str();
}

std::vector<std::optional<PrincipalPoint>> FindPrincipalPoints(
    const std::vector<Record>& records, const std::vector<CameraTool>& cameras,
    const ExtractOptions& options) {
  // Camera rows by zoom, gathered once: the time grows with the data, not
  // with the largest zoom number.
  std::map<int, std::vector<const Record*>> rows_of_zoom;
  for (const Record& r : records) {
    if (r.tool == Tool::kCam) rows_of_zoom[r.zoom].push_back(&r);
  }
  // The result has an entry per level up to the largest (SPEC 2: levels are
  // 0..N-1), so a mistyped zoom would allocate without bound: the levels
  // are bounded by the data, one per camera row at most. In long long:
  // zoom + 1 overflows an int at INT_MAX.
  long long num_zooms = static_cast<long long>(cameras.size());
  if (!rows_of_zoom.empty()) {
    const auto& [largest, rows] = *rows_of_zoom.rbegin();
    num_zooms = std::max(num_zooms, largest + 1LL);
    const long long max_levels =
        static_cast<long long>(cameras.size()) + static_cast<long long>(records.size());
    if (num_zooms > max_levels) {
      throw ExtractionError("zoom " + std::to_string(largest) + " on line " +
                            std::to_string(rows.front()->line) + ", but the data hold " +
                            std::to_string(rows_of_zoom.size()) +
                            " zoom level(s); zoom levels are 0..N-1 (SPEC 2)");
    }
  }
  std::vector<std::optional<PrincipalPoint>> out(num_zooms);
  const double q = options.pixel_tolerance_px;
  for (int z = 0; z < num_zooms; ++z) {
    if (z < static_cast<int>(cameras.size())) {
      out[z] = PrincipalPoint{{cameras[z].intrinsics[2], cameras[z].intrinsics[3]}, false};
      continue;
    }
    const auto zoom_rows = rows_of_zoom.find(z);
    if (zoom_rows == rows_of_zoom.end()) continue;
    // Count the usable camera rows of this zoom per (quantised) pixel.
    std::map<std::pair<long long, long long>, int> count;
    std::map<std::pair<long long, long long>, Eigen::Vector2d> pixel;
    for (const Record* row : zoom_rows->second) {
      const Record& r = *row;
      if (!IsUsableForExtraction(r, options)) continue;
      const std::pair<long long, long long> key{std::llround(r.u / q), std::llround(r.v / q)};
      ++count[key];
      pixel.emplace(key, Eigen::Vector2d(r.u, r.v));
    }
    if (count.empty()) continue;
    const long long step = std::llround(1.0 / q);
    auto score = [&](const std::pair<long long, long long>& k) {
      auto at = [&](long long du, long long dv) {
        auto it = count.find({k.first + du, k.second + dv});
        return it == count.end() ? 0 : it->second;
      };
      // Triplet centres first (rows at +1 px in u and v exist), then the count.
      const int triplets = std::min(at(step, 0), at(0, step));
      return std::make_tuple(triplets > 0, count.at(k), triplets);
    };
    auto best = count.begin()->first;
    for (const auto& [k, n] : count) {
      if (score(k) > score(best)) best = k;
    }
    out[z] = PrincipalPoint{pixel.at(best), true};
  }
  return out;
}

SweepSearch FindSweeps(const std::vector<Record>& records,
                       const std::vector<std::optional<PrincipalPoint>>& principal_points,
                       const ExtractOptions& options) {
  SweepSearch out;
  for (int i = 0; i < static_cast<int>(records.size()); ++i) {
    const Record& r = records[i];
    if (r.face != 1) {
      ++out.excluded.face2;
    } else if (!IsUsableForExtraction(r, options)) {
      ++out.excluded.critical_zenith;
    } else {
      out.usable.push_back(i);
    }
  }

  // Group by (tool, zoom, d, pixel offset).
  std::map<GroupKey, std::vector<int>> groups;
  std::map<GroupKey, Eigen::Vector2d> offsets;
  for (int i : out.usable) {
    const Record& r = records[i];
    GroupKey key{r.tool == Tool::kEdm ? 0 : 1, 0, std::llround(r.d / options.distance_tolerance_m),
                 0, 0};
    Eigen::Vector2d offset = Eigen::Vector2d::Zero();
    if (r.tool == Tool::kCam) {
      key.zoom = r.zoom;
      offset = Eigen::Vector2d(r.u, r.v);
      if (r.zoom >= 0 && r.zoom < static_cast<int>(principal_points.size()) &&
          principal_points[r.zoom]) {
        offset -= principal_points[r.zoom]->pixel;
      }
      key.du_q = std::llround(offset.x() / options.pixel_tolerance_px);
      key.dv_q = std::llround(offset.y() / options.pixel_tolerance_px);
    }
    groups[key].push_back(i);
    offsets.emplace(key, offset);
  }

  std::vector<double> phi(records.size()), theta(records.size());
  for (int i : out.usable) {
    phi[i] = records[i].phi;
    theta[i] = records[i].theta;
  }
  for (const auto& [key, rows] : groups) {
    for (int joint : {1, 2}) {
      // Joint 1: constant theta, varying phi; joint 2: constant phi, varying theta.
      const std::vector<double>& fixed = joint == 1 ? theta : phi;
      const std::vector<double>& varying = joint == 1 ? phi : theta;
      const bool fixed_periodic = joint == 2;
      const bool varying_periodic = joint == 1;
      for (const auto& line : Cluster(rows, fixed, options.angle_tolerance_rad, fixed_periodic)) {
        // One row per control value: the first of each cluster of equal readings.
        std::vector<int> sweep_rows;
        for (const auto& same :
             Cluster(line, varying, options.angle_tolerance_rad, varying_periodic)) {
          sweep_rows.push_back(*std::min_element(same.begin(), same.end()));
        }
        if (static_cast<int>(sweep_rows.size()) < options.min_sweep_points) continue;
        std::sort(sweep_rows.begin(), sweep_rows.end(), [&](int a, int b) {
          const double va = varying_periodic ? WrapTwoPi(varying[a]) : varying[a];
          const double vb = varying_periodic ? WrapTwoPi(varying[b]) : varying[b];
          return va < vb;
        });
        Sweep s;
        s.joint = joint;
        s.face = 1;
        s.tool = key.tool == 0 ? Tool::kEdm : Tool::kCam;
        s.zoom = key.zoom;
        s.d = records[sweep_rows.front()].d;
        s.pixel_offset = offsets.at(key);
        s.constant_control = Mean(line, fixed, fixed_periodic);
        s.rows = sweep_rows;
        s.set = MajoritySet(records, sweep_rows);
        out.candidates.push_back(std::move(s));
      }
    }
  }

  // Choice (see the header).
  auto rank = [&](const Sweep& s) {
    const std::string& hint = s.joint == 1 ? options.joint1_set_hint : options.joint2_set_hint;
    const bool at_principal_point = s.pixel_offset.norm() <= options.pixel_tolerance_px;
    double quality = std::sqrt(static_cast<double>(s.NumPoints()));
    if (s.joint == 1) quality *= std::abs(std::sin(s.constant_control));
    const double span = s.Control(records, s.NumPoints() - 1) - s.Control(records, 0);
    // Compared lexicographically, smaller preferred (quality and span negated).
    return std::make_tuple(s.tool == Tool::kEdm ? 0 : 1, at_principal_point ? 0 : 1, s.zoom,
                           std::llround(s.d / options.distance_tolerance_m),
                           !hint.empty() && s.set == hint ? 0 : 1, -quality, -span);
  };
  for (const Sweep& s : out.candidates) {
    std::optional<Sweep>& chosen = s.joint == 1 ? out.joint1 : out.joint2;
    if (!chosen || rank(s) < rank(*chosen)) chosen = s;
  }
  return out;
}

}  // namespace rtscalib

#include "libcalib/screen/duplicates.h"

#include <cstdio>
#include <set>
#include <string>
#include <unordered_map>
#include <utility>

namespace rtscalib {
namespace {

// Line pairs named in a notice.
constexpr size_t kListedPairs = 5;

// Doubles as hexadecimal floating-point text: exact, and every NaN of an
// empty covariate cell reads the same.
void AppendExact(double x, std::string* key) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%a|", x);
  *key += buf;
}

void AppendText(const std::string& s, std::string* key) {
  *key += std::to_string(s.size()) + ":" + s + "|";
}

std::string KeyOf(const Record& r) {
  std::string key = std::to_string(r.face) + "|" + std::to_string(r.zoom) + "|" +
                    (r.tool == Tool::kCam ? "cam|" : "edm|");
  for (double x : {r.phi, r.theta, r.u, r.v, r.d, r.x.x(), r.x.y(), r.x.z()}) AppendExact(x, &key);
  AppendText(r.set, &key);
  AppendText(r.point, &key);
  for (double c : r.covariates) AppendExact(c, &key);
  return key;
}

std::string KeyOf(const PixelObservation& p) {
  std::string key = std::to_string(p.face) + "|" + std::to_string(p.zoom) + "|" +
                    std::to_string(p.has_reading) + std::to_string(p.X_known) + "|" +
                    std::to_string(p.target) + "|" + std::to_string(p.corner) + "|";
  for (double x : {p.phi, p.theta, p.focus_distance, p.X.x(), p.X.y(), p.X.z(), p.uv.x(), p.uv.y()})
    AppendExact(x, &key);
  AppendText(p.shot, &key);
  AppendText(p.placement, &key);
  for (double c : p.covariates) AppendExact(c, &key);
  return key;
}

// A later copy of a row: the row taken out and the line it repeats.
struct Copy {
  ExcludedRow row;
  int original_line = 0;
};

template <typename Row>
void FindCopies(const std::vector<Row>& rows, bool pixel, std::vector<Copy>* out) {
  std::unordered_map<std::string, int> first;  // key -> index of its first row
  first.reserve(rows.size());
  for (int i = 0; i < static_cast<int>(rows.size()); ++i) {
    const auto [it, inserted] = first.emplace(KeyOf(rows[i]), i);
    if (inserted) continue;
    const int original = rows[it->second].line;
    out->push_back({{pixel, i, rows[i].line,
                     "an exact copy of line " + std::to_string(original) +
                         " (every column equal): counted once, not a second measurement"},
                    original});
  }
}

std::vector<Copy> Copies(const Observations& obs) {
  std::vector<Copy> out;
  FindCopies(obs.records, false, &out);
  FindCopies(obs.pixels, true, &out);
  return out;
}

std::string Notice(const std::string& file, const std::vector<const Copy*>& copies, bool pixel) {
  // Distinct (copy, original) line pairs in file order: the corners of a
  // photo listed twice share one pair.
  std::vector<std::pair<int, int>> pairs;
  std::set<std::pair<int, int>> seen;
  for (const Copy* c : copies) {
    const std::pair<int, int> p(c->row.line, c->original_line);
    if (seen.insert(p).second) pairs.push_back(p);
  }
  const size_t n = copies.size();
  std::string out = file + ": " + std::to_string(n) + (n == 1 ? " row repeats" : " rows repeat") +
                    " an earlier row exactly (every column equal";
  if (pixel && pairs.size() < n) {
    out += "; the corners of " + std::to_string(pairs.size()) +
           (pairs.size() == 1 ? " line" : " lines");
  }
  out += "): ";
  for (size_t i = 0; i < pairs.size() && i < kListedPairs; ++i) {
    out += (i ? ", " : "") + std::string("line ") + std::to_string(pairs[i].first) +
           " repeats line " + std::to_string(pairs[i].second);
  }
  if (pairs.size() > kListedPairs) {
    out += " and " + std::to_string(pairs.size() - kListedPairs) + " more";
  }
  out +=
      ". Each copy is taken out before the fit and listed with the gross rows: counted twice, "
      "a copy would shrink every sigma by up to 1/sqrt(2). If the file was joined to itself, "
      "remove the copies";
  return out;
}

}  // namespace

std::vector<ExcludedRow> FindDuplicateRows(const Observations& obs) {
  std::vector<ExcludedRow> out;
  for (Copy& c : Copies(obs)) out.push_back(std::move(c.row));
  return out;
}

std::vector<std::string> DuplicateRowNotices(const Observations& obs) {
  const std::vector<Copy> copies = Copies(obs);
  std::vector<const Copy*> records, pixels;
  for (const Copy& c : copies) (c.row.pixel ? pixels : records).push_back(&c);
  std::vector<std::string> out;
  if (!records.empty()) out.push_back(Notice(obs.records_source, records, false));
  if (!pixels.empty()) out.push_back(Notice(obs.pixels_source, pixels, true));
  return out;
}

}  // namespace rtscalib

#include "app/plot/vega_svg.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "app/markup.h"

namespace rtscalib::app::vega {

using json = nlohmann::json;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
const double kNaN = std::numeric_limits<double>::quiet_NaN();

[[noreturn]] void Refuse(const std::string& what) {
  throw SubsetError("Vega spec: " + what +
                    " (outside the part of Vega that app/plot/vega_svg.h draws)");
}

// ---------------------------------------------------------------------------
// Vega's defaults (vega-parser's config): the guides' look and layout.
constexpr double kTickSize = 5, kLabelPadding = 2, kAxisTitlePadding = 4;
constexpr double kAxisLabelSize = 10, kAxisTitleSize = 11, kAxisLabelLimit = 180;
constexpr const char* kAxisColour = "#888";
constexpr const char* kGridColour = "#ddd";
constexpr double kLegendOffset = 18, kLegendMargin = 8, kLegendTitlePadding = 5;
constexpr double kLegendLabelOffset = 4, kLegendRowPadding = 2, kLegendColumnPadding = 10;
constexpr double kLegendSymbolSize = 100, kLegendSymbolStrokeWidth = 1.5;
constexpr double kLegendLabelLimit = 160, kLegendTitleLimit = 180;
constexpr double kGradientLength = 200, kGradientThickness = 16, kGradientLabelOffset = 2;
constexpr double kTitleOffset = 4, kSubtitlePadding = 3;
constexpr const char* kDefaultColour = "#4c78a8";

// ---------------------------------------------------------------------------
// Text: DejaVu Sans advance widths (units of 1/2048 em) of ASCII 32..126.
constexpr std::array<unsigned short, 95> kBook = {
    651,  821,  942,  1716, 1303, 1946, 1597, 563,  799,  799,  1024, 1716, 651,  739,  651,  690,
    1303, 1303, 1303, 1303, 1303, 1303, 1303, 1303, 1303, 1303, 690,  690,  1716, 1716, 1716, 1087,
    2048, 1401, 1405, 1430, 1577, 1294, 1178, 1587, 1540, 604,  604,  1343, 1141, 1767, 1532, 1612,
    1235, 1612, 1423, 1300, 1251, 1499, 1401, 2025, 1403, 1251, 1403, 799,  690,  799,  1716, 1024,
    1024, 1255, 1300, 1126, 1300, 1260, 721,  1300, 1298, 569,  569,  1186, 569,  1995, 1298, 1253,
    1300, 1300, 842,  1067, 803,  1298, 1212, 1675, 1212, 1212, 1075, 1303, 690,  1303, 1716};
constexpr std::array<unsigned short, 95> kBold = {
    713,  934,  1067, 1716, 1425, 2052, 1786, 627,  936,  936,  1071, 1716, 778,  850,  778,  748,
    1425, 1425, 1425, 1425, 1425, 1425, 1425, 1425, 1425, 1425, 819,  819,  1716, 1716, 1716, 1188,
    2048, 1585, 1561, 1503, 1700, 1399, 1399, 1681, 1714, 762,  762,  1587, 1305, 2038, 1714, 1741,
    1501, 1741, 1577, 1475, 1397, 1663, 1585, 2259, 1579, 1483, 1485, 936,  748,  936,  1716, 1024,
    1024, 1382, 1466, 1214, 1466, 1389, 891,  1466, 1458, 702,  702,  1362, 702,  2134, 1458, 1407,
    1466, 1466, 1010, 1219, 979,  1458, 1335, 1892, 1321, 1335, 1192, 1458, 748,  1458, 1716};

// ---------------------------------------------------------------------------
// Numbers and text in the SVG.

std::string Num(double v) {
  if (!std::isfinite(v)) return "0";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", v);
  std::string s = buf;
  while (!s.empty() && s.back() == '0') s.pop_back();
  if (!s.empty() && s.back() == '.') s.pop_back();
  return s == "-0" ? "0" : s;
}

// The text of a value as Vega shows it (String(value)).
std::string Text(const json& v) {
  if (v.is_string()) return v.get<std::string>();
  if (v.is_number()) return JsNumber(v.get<double>());
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_null()) return "";
  if (v.is_array()) {
    std::string s;
    for (size_t i = 0; i < v.size(); ++i) s += (i ? "," : "") + Text(v[i]);
    return s;
  }
  return v.dump();
}

double Number(const json& v, double fallback = kNaN) {
  if (v.is_number()) return v.get<double>();
  if (v.is_boolean()) return v.get<bool>() ? 1 : 0;
  return fallback;
}

// ---------------------------------------------------------------------------
// Colours: CSS colours as given, interpolated in RGB as d3's interpolateRgb.

struct Rgb {
  double r = 0, g = 0, b = 0;
};

bool ParseHex(const std::string& c, Rgb* out) {
  if (c.empty() || c[0] != '#') return false;
  auto hex = [](char h) {
    return h >= '0' && h <= '9'   ? h - '0'
           : h >= 'a' && h <= 'f' ? h - 'a' + 10
           : h >= 'A' && h <= 'F' ? h - 'A' + 10
                                  : -1;
  };
  int v[6];
  if (c.size() == 7) {
    for (int i = 0; i < 6; ++i) v[i] = hex(c[i + 1]);
  } else if (c.size() == 4) {
    for (int i = 0; i < 3; ++i) v[2 * i] = v[2 * i + 1] = hex(c[i + 1]);
  } else {
    return false;
  }
  for (int x : v) {
    if (x < 0) return false;
  }
  *out = {v[0] * 16.0 + v[1], v[2] * 16.0 + v[3], v[4] * 16.0 + v[5]};
  return true;
}

Rgb ColourOf(const std::string& c) {
  Rgb rgb;
  if (ParseHex(c, &rgb)) return rgb;
  if (c == "white") return {255, 255, 255};
  if (c == "black") return {0, 0, 0};
  Refuse("the colour '" + c + "' in an interpolated range (give it as #rrggbb)");
}

std::string Hex(const Rgb& c) {
  char buf[8];
  auto byte = [](double v) { return static_cast<int>(std::lround(std::clamp(v, 0.0, 255.0))); };
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", byte(c.r), byte(c.g), byte(c.b));
  return buf;
}

// d3's piecewise(interpolateRgb, colours)(t).
std::string Piecewise(const std::vector<Rgb>& colours, double t) {
  // No colour for no position (a log scale's domain reaching 0): not drawn.
  if (!std::isfinite(t)) return "";
  const size_t n = colours.size() - 1;
  if (n == 0) return Hex(colours[0]);
  const double s = t * n;
  const size_t i = static_cast<size_t>(std::clamp(std::floor(s), 0.0, double(n - 1)));
  const double f = s - i;
  const Rgb& a = colours[i];
  const Rgb& b = colours[i + 1];
  return Hex({a.r + (b.r - a.r) * f, a.g + (b.g - a.g) * f, a.b + (b.b - a.b) * f});
}

// Vega's schemes (vega-scale): continuous ones as their colour stops,
// discrete ones as their colours.
std::vector<Rgb> SchemeStops(const std::string& packed) {
  std::vector<Rgb> out;
  for (size_t i = 0; i + 6 <= packed.size(); i += 6)
    out.push_back(ColourOf("#" + packed.substr(i, 6)));
  return out;
}

const char* ContinuousScheme(const std::string& name) {
  if (name == "viridis") {
    return "440154470e61481a6c482575472f7d443a834144873d4e8a39568c35608d31688e2d708e2a788e27818e238"
           "8"
           "8e21918d1f988b1fa08822a8842ab07f35b77943bf7154c56866cc5d7ad1518fd744a5db36bcdf27d2e21be"
           "9"
           "e51afde725";
  }
  return nullptr;
}

const char* DiscreteScheme(const std::string& name) {
  if (name == "category10") return "1f77b4ff7f0e2ca02cd627289467bd8c564be377c27f7f7fbcbd2217becf";
  if (name == "category20") {
    return "1f77b4aec7e8ff7f0effbb782ca02c98df8ad62728ff98969467bdc5b0d58c564bc49c94e377c2f7b6d27f"
           "7f7fc7c7c7bcbd22dbdb8d17becf9edae5";
  }
  if (name == "tableau10") return "4c78a8f58518e4575672b7b254a24beeca3bb279a2ff9da69d755dbab0ac";
  return nullptr;
}

// ---------------------------------------------------------------------------
// Ticks and nice domains: d3-array's ticks and d3-scale's nice.

const double kE10 = std::sqrt(50.0), kE5 = std::sqrt(10.0), kE2 = std::sqrt(2.0);

double TickIncrement(double start, double stop, double count) {
  const double step = (stop - start) / std::max(0.0, count);
  const double power = std::floor(std::log(step) / std::log(10.0));
  const double error = step / std::pow(10.0, power);
  const double f = error >= kE10 ? 10 : error >= kE5 ? 5 : error >= kE2 ? 2 : 1;
  return power >= 0 ? f * std::pow(10.0, power) : -std::pow(10.0, -power) / f;
}

double TickStep(double start, double stop, double count) {
  const double step0 = std::abs(stop - start) / std::max(0.0, count);
  double step1 = std::pow(10.0, std::floor(std::log(step0) / std::log(10.0)));
  const double error = step0 / step1;
  if (error >= kE10) {
    step1 *= 10;
  } else if (error >= kE5) {
    step1 *= 5;
  } else if (error >= kE2) {
    step1 *= 2;
  }
  return stop < start ? -step1 : step1;
}

std::vector<double> Ticks(double start, double stop, double count) {
  if (start == stop && count > 0) return {start};
  const bool reverse = stop < start;
  if (reverse) std::swap(start, stop);
  const double step = TickIncrement(start, stop, count);
  std::vector<double> ticks;
  if (step == 0 || !std::isfinite(step)) return ticks;
  // d3 counts the ticks, then places tick i at (r0 + i) * step: counted here
  // too, so that a domain far from 0 for its width (where r0 + 1 == r0 in
  // floating point) still ends; a count beyond any axis's draws none.
  constexpr double kMaxTicks = 10000;
  if (step > 0) {
    double r0 = std::round(start / step), r1 = std::round(stop / step);
    if (r0 * step < start) ++r0;
    if (r1 * step > stop) --r1;
    if (!(r1 - r0 < kMaxTicks)) return ticks;
    for (int i = 0; i <= static_cast<int>(r1 - r0); ++i) ticks.push_back((r0 + i) * step);
  } else {
    const double s = -step;
    double r0 = std::round(start * s), r1 = std::round(stop * s);
    if (r0 / s < start) ++r0;
    if (r1 / s > stop) --r1;
    if (!(r1 - r0 < kMaxTicks)) return ticks;
    for (int i = 0; i <= static_cast<int>(r1 - r0); ++i) ticks.push_back((r0 + i) / s);
  }
  if (reverse) std::reverse(ticks.begin(), ticks.end());
  return ticks;
}

// d3-scale 3's linearish nice(count), the one Debian's Vega bundles: two
// passes of the tick step (the floating point of its second pass decides,
// as in the browser: [0, 0.139] becomes [0, 0.15]). A domain of zero width
// keeps its ends.
void NiceLinear(double* d0, double* d1, double count) {
  double start = *d0, stop = *d1;
  const bool reverse = stop < start;
  if (reverse) std::swap(start, stop);
  double step = TickIncrement(start, stop, count);
  if (step > 0) {
    start = std::floor(start / step) * step;
    stop = std::ceil(stop / step) * step;
    step = TickIncrement(start, stop, count);
  } else if (step < 0) {
    start = std::ceil(start * step) / step;
    stop = std::floor(stop * step) / step;
    step = TickIncrement(start, stop, count);
  }
  if (step > 0) {
    start = std::floor(start / step) * step;
    stop = std::ceil(stop / step) * step;
  } else if (step < 0) {
    start = std::ceil(start * step) / step;
    stop = std::floor(stop * step) / step;
  } else {
    return;
  }
  if (!std::isfinite(start) || !std::isfinite(stop)) return;
  *d0 = reverse ? stop : start;
  *d1 = reverse ? start : stop;
}

// ---------------------------------------------------------------------------
// Scales.

bool SameValue(const json& a, const json& b) {
  if (a.is_number() && b.is_number()) return a.get<double>() == b.get<double>();
  return a == b;
}

class Scale {
 public:
  Scale(const json& spec, const std::function<std::vector<const json*>(const json&)>& values,
        double width, double height);

  bool discrete() const { return type_ == "ordinal" || type_ == "point"; }
  const std::string& type() const { return type_; }
  json Map(const json& v) const;
  // Position of a value (the numeric output of a positional scale).
  double Position(const json& v) const { return Number(Map(v), kNaN); }
  // The range's ends (positional scales).
  std::pair<double, double> RangeEnds() const;
  // Tick values for about `count` ticks (d3's ticks; the domain of a
  // discrete scale).
  std::vector<json> TickValues(double count) const;
  // Labels of tick values (Vega's tickFormat): `skip` filters the log
  // scale's labels as d3's log format does.
  std::vector<std::string> Labels(const std::vector<json>& ticks, double count,
                                  const std::string& specifier) const;
  // The domain's values (discrete) or ends (continuous).
  const std::vector<json>& domain() const { return domain_; }
  double d0() const { return d0_; }
  double d1() const { return d1_; }
  // Fraction along the range of a continuous value (0 at d0, 1 at d1).
  double Fraction(double v) const;
  // The colour at fraction t of a colour range.
  std::string ColourAt(double t) const;
  bool colours() const { return !stops_.empty(); }

 private:
  double Transform(double v) const;

  std::string name_, type_;
  double d0_ = 0, d1_ = 1;
  mutable std::vector<json> domain_;  // discrete; d3's ordinal scale adds unknown values
  std::vector<json> range_;           // ordinal output values
  double r0_ = 0, r1_ = 1;            // numeric range
  std::vector<Rgb> stops_;            // colour range of a continuous scale
  bool clamp_ = false;
  double exponent_ = 1, padding_ = 0;
};

double Scale::Transform(double v) const {
  if (type_ == "log") return std::log10(v);
  if (type_ == "sqrt" || type_ == "pow") {
    return v < 0 ? -std::pow(-v, exponent_) : std::pow(v, exponent_);
  }
  return v;
}

double Scale::Fraction(double v) const {
  const double a = Transform(d0_), b = Transform(d1_);
  double t = b - a != 0 ? (Transform(v) - a) / (b - a) : 0.5;
  if (clamp_) t = std::clamp(t, 0.0, 1.0);
  return t;
}

std::string Scale::ColourAt(double t) const { return Piecewise(stops_, t); }

Scale::Scale(const json& spec, const std::function<std::vector<const json*>(const json&)>& values,
             double width, double height) {
  static const std::set<std::string> kKeys = {"name",   "type",    "domain",   "range",
                                              "nice",   "zero",    "clamp",    "reverse",
                                              "scheme", "padding", "exponent", "round"};
  for (const auto& [k, v] : spec.items()) {
    if (!kKeys.count(k)) Refuse("scale property '" + k + "'");
  }
  name_ = spec.value("name", "");
  type_ = spec.value("type", "linear");
  if (type_ != "linear" && type_ != "log" && type_ != "sqrt" && type_ != "pow" &&
      type_ != "ordinal" && type_ != "point") {
    Refuse("scale type '" + type_ + "' (scale '" + name_ + "')");
  }
  if (spec.value("round", false)) Refuse("scale round (scale '" + name_ + "')");
  if (type_ == "sqrt") exponent_ = 0.5;
  if (spec.contains("exponent")) exponent_ = spec["exponent"].get<double>();
  clamp_ = spec.value("clamp", false);
  padding_ = spec.value("padding", 0.0);

  // Domain: literal values, or the values of data fields.
  std::vector<const json*> dv;
  const json& d = spec.contains("domain") ? spec["domain"] : json();
  if (d.is_array()) {
    for (const json& v : d) dv.push_back(&v);
  } else if (d.is_object()) {
    dv = values(d);
  } else {
    Refuse("scale '" + name_ + "' without a domain");
  }
  if (discrete()) {
    for (const json* v : dv) {
      if (v->is_null()) continue;
      if (std::none_of(domain_.begin(), domain_.end(),
                       [&](const json& e) { return SameValue(e, *v); })) {
        domain_.push_back(*v);
      }
    }
  } else {
    double lo = kInf, hi = -kInf;
    for (const json* v : dv) {
      const double x = Number(*v);
      if (!std::isfinite(x) || (type_ == "log" && x <= 0)) continue;
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
    // A literal domain of two values keeps their order: a reversed axis
    // (the zenith angle of face 2 runs from 360 down to 180).
    if (d.is_array() && d.size() == 2) {
      lo = Number(d[0]);
      hi = Number(d[1]);
    }
    if (!(lo <= hi) && !(d.is_array())) lo = hi = type_ == "log" ? 1 : 0;
    const bool zero = spec.contains("zero") ? spec["zero"].get<bool>() : type_ != "log";
    if (zero) {
      lo = std::min(lo, 0.0);
      hi = std::max(hi, 0.0);
    }
    d0_ = lo;
    d1_ = hi;
    const json& nice = spec.contains("nice") ? spec["nice"] : json(false);
    if (nice.is_number() || (nice.is_boolean() && nice.get<bool>())) {
      if (type_ == "log") {
        d0_ = std::pow(10.0, std::floor(std::log10(d0_)));
        d1_ = std::pow(10.0, std::ceil(std::log10(d1_)));
      } else if (type_ == "linear") {
        NiceLinear(&d0_, &d1_, nice.is_number() ? nice.get<double>() : 10);
      } else {
        // d3's pow scale nices its domain as a linear one.
        NiceLinear(&d0_, &d1_, nice.is_number() ? nice.get<double>() : 10);
      }
    } else if (!nice.is_boolean()) {
      Refuse("scale nice '" + nice.dump() + "' (scale '" + name_ + "')");
    }
  }

  // Range: numbers, colours, "width"/"height", or a scheme.
  json r = spec.contains("range") ? spec["range"] : json();
  std::string scheme;
  if (spec.contains("scheme")) scheme = spec["scheme"].get<std::string>();
  if (r.is_object() && r.contains("scheme")) scheme = r["scheme"].get<std::string>();
  if (r.is_string()) {
    const std::string s = r.get<std::string>();
    if (s == "width") {
      r = {0, width};
    } else if (s == "height") {
      r = {height, 0};
    } else if (s == "category") {
      scheme = "tableau10";
    } else if (s == "symbol") {
      r = {"circle",  "square",         "triangle-up",   "cross",
           "diamond", "triangle-right", "triangle-down", "triangle-left"};
    } else {
      Refuse("scale range '" + s + "' (scale '" + name_ + "')");
    }
  }
  if (!scheme.empty()) {
    if (const char* c = ContinuousScheme(scheme); c != nullptr && !discrete()) {
      stops_ = SchemeStops(c);
    } else if (const char* q = DiscreteScheme(scheme); q != nullptr && discrete()) {
      for (const Rgb& c : SchemeStops(q)) range_.push_back(Hex(c));
    } else {
      Refuse("scheme '" + scheme + "' for a " + type_ + " scale (scale '" + name_ + "')");
    }
  } else if (r.is_array() && !r.empty()) {
    if (discrete() && type_ == "ordinal") {
      range_.assign(r.begin(), r.end());
    } else if (r[0].is_string()) {
      if (discrete()) Refuse("a colour range of a point scale (scale '" + name_ + "')");
      for (const json& c : r) stops_.push_back(ColourOf(c.get<std::string>()));
    } else if (r.size() == 2) {
      r0_ = r[0].get<double>();
      r1_ = r[1].get<double>();
    } else {
      Refuse("a range of " + std::to_string(r.size()) + " numbers (scale '" + name_ + "')");
    }
  } else {
    Refuse("scale '" + name_ + "' without a range");
  }
  if (spec.value("reverse", false)) {
    if (!stops_.empty()) {
      std::reverse(stops_.begin(), stops_.end());
    } else if (!range_.empty()) {
      std::reverse(range_.begin(), range_.end());
    } else {
      std::swap(r0_, r1_);
    }
  }
}

json Scale::Map(const json& v) const {
  if (type_ == "ordinal") {
    size_t i = 0;
    while (i < domain_.size() && !SameValue(domain_[i], v)) ++i;
    if (i == domain_.size()) domain_.push_back(v);  // d3's implicit domain
    return range_.empty() ? json() : range_[i % range_.size()];
  }
  if (type_ == "point") {
    size_t i = 0;
    while (i < domain_.size() && !SameValue(domain_[i], v)) ++i;
    if (i == domain_.size()) return json();
    const double n = static_cast<double>(domain_.size());
    const double step = (r1_ - r0_) / std::max(1.0, n - 1 + 2 * padding_);
    const double start = r0_ + (r1_ - r0_ - step * (n - 1)) * 0.5;
    return start + step * static_cast<double>(i);
  }
  const double x = Number(v);
  if (!std::isfinite(x) || (type_ == "log" && x <= 0)) return json();
  const double t = Fraction(x);
  if (!stops_.empty()) return ColourAt(t);
  return r0_ + t * (r1_ - r0_);
}

std::pair<double, double> Scale::RangeEnds() const { return {r0_, r1_}; }

std::vector<json> Scale::TickValues(double count) const {
  std::vector<json> out;
  if (discrete()) return domain_;
  std::vector<double> t;
  if (type_ == "log") {
    // d3's log ticks, base 10.
    double u = d0_, v = d1_;
    const bool r = v < u;
    if (r) std::swap(u, v);
    double i = std::log10(u), j = std::log10(v);
    if (j - i < count) {
      i = std::round(i) - 1;
      j = std::round(j) + 1;
      for (; i < j; ++i) {
        const double p = std::pow(10.0, i);
        for (int k = 1; k < 10; ++k) {
          const double x = p * k;
          if (x < u) continue;
          if (x > v) break;
          t.push_back(x);
        }
      }
    } else {
      for (double e : Ticks(i, j, std::min(j - i, count))) t.push_back(std::pow(10.0, e));
    }
    if (r) std::reverse(t.begin(), t.end());
  } else {
    t = Ticks(d0_, d1_, count);
  }
  for (double x : t) out.push_back(x);
  return out;
}

std::vector<std::string> Scale::Labels(const std::vector<json>& ticks, double count,
                                       const std::string& specifier) const {
  std::vector<std::string> out;
  if (discrete()) {
    for (const json& v : ticks)
      out.push_back(specifier.empty() || !v.is_number() ? Text(v)
                                                        : Format(v.get<double>(), specifier));
    return out;
  }
  if (type_ == "log") {
    // Vega: formatFloat (',' with 12 significant digits, zeros trimmed) and
    // d3's log-label filter, which keeps 1, 2, 5-like labels as the ticks
    // thicken.
    const double k = std::max(1.0, 10 * count / std::max<double>(1, TickValues(count).size()));
    for (const json& v : ticks) {
      const double d = v.get<double>();
      double i = d / std::pow(10.0, std::round(std::log10(d)));
      if (i * 10 < 10 - 0.5) i *= 10;
      out.push_back(i <= k ? Format(d, specifier.empty() ? ",.12~" : specifier) : "");
    }
    return out;
  }
  // Vega's formatSpan: ",f" with the precision of the tick step.
  std::string spec = specifier;
  if (spec.empty()) {
    const double step = TickStep(d0_, d1_, count);
    const double e = std::floor(std::log10(std::abs(step)) + 1e-12);
    const int precision = std::isfinite(e) ? std::max(0, -static_cast<int>(e)) : 0;
    spec = ",." + std::to_string(precision) + "f";
  }
  for (const json& v : ticks) out.push_back(Format(v.get<double>(), spec));
  return out;
}

// ---------------------------------------------------------------------------
// Bounds and SVG fragments.

struct Box {
  double x1 = kInf, y1 = kInf, x2 = -kInf, y2 = -kInf;
  bool empty() const { return x1 > x2; }
  void Add(double x, double y) {
    if (!std::isfinite(x) || !std::isfinite(y)) return;
    x1 = std::min(x1, x);
    y1 = std::min(y1, y);
    x2 = std::max(x2, x);
    y2 = std::max(y2, y);
  }
  void Add(const Box& b, double dx = 0, double dy = 0) {
    if (b.empty()) return;
    Add(b.x1 + dx, b.y1 + dy);
    Add(b.x2 + dx, b.y2 + dy);
  }
};

// A drawing in its own frame and the box it covers.
struct Layer {
  std::string svg;
  Box box;
  void Append(const Layer& l, double dx, double dy) {
    if (l.svg.empty()) return;
    if (dx == 0 && dy == 0) {
      svg += l.svg;
    } else {
      svg += "<g transform=\"translate(" + Num(dx) + "," + Num(dy) + ")\">" + l.svg + "</g>";
    }
    box.Add(l.box, dx, dy);
  }
};

struct TextStyle {
  double size = 11;
  bool bold = false;
  std::string fill = "#000";
  std::string align = "left";           // left, center, right
  std::string baseline = "alphabetic";  // top, middle, bottom, alphabetic
  double angle = 0;                     // degrees, about the anchor
  double opacity = 1;
  double limit = 0;  // px; longer text is cut with an ellipsis
};

// Vega's vertical offset of a baseline (vega-scenegraph's textOffset).
double BaselineOffset(const std::string& baseline, double size) {
  return std::round(baseline == "top"      ? 0.79 * size
                    : baseline == "middle" ? 0.30 * size
                    : baseline == "bottom" ? -0.21 * size
                                           : 0.0);
}

std::string Truncate(const std::string& text, const TextStyle& s) {
  if (s.limit <= 0 || TextWidth(text, s.size, s.bold) <= s.limit) return text;
  const std::string ellipsis = "\xE2\x80\xA6";
  std::string t = text;
  while (!t.empty() && TextWidth(t + ellipsis, s.size, s.bold) > s.limit) {
    t.pop_back();
    while (!t.empty() && (static_cast<unsigned char>(t.back()) & 0xC0) == 0x80) t.pop_back();
  }
  return t + ellipsis;
}

void DrawText(Layer* l, double x, double y, const std::string& raw, const TextStyle& s) {
  if (raw.empty()) return;
  const std::string text = Truncate(raw, s);
  const double w = TextWidth(text, s.size, s.bold);
  const double dy = BaselineOffset(s.baseline, s.size);
  const char* anchor = s.align == "center" ? "middle" : s.align == "right" ? "end" : "start";
  l->svg += "<text x=\"0\" y=\"" + Num(dy) + "\" transform=\"translate(" + Num(x) + "," + Num(y) +
            ")" + (s.angle != 0 ? " rotate(" + Num(s.angle) + ")" : std::string()) +
            "\" text-anchor=\"" + anchor + "\" font-family=\"sans-serif\" font-size=\"" +
            Num(s.size) + "px\"" + (s.bold ? " font-weight=\"bold\"" : "") + " fill=\"" +
            EscapeMarkup(s.fill) + "\"" +
            (s.opacity != 1 ? " opacity=\"" + Num(s.opacity) + "\"" : std::string()) + ">" +
            EscapeMarkup(text) + "</text>";
  // The box: the text's rectangle about its anchor, rotated.
  const double left = s.align == "center" ? -w / 2 : s.align == "right" ? -w : 0;
  // Vega's text bounds: from round(0.8 size) above the alphabetic baseline.
  const double top = dy - std::round(0.8 * s.size);
  const double a = s.angle * M_PI / 180, c = std::cos(a), sn = std::sin(a);
  for (double px : {left, left + w}) {
    for (double py : {top, top + s.size}) l->box.Add(x + c * px - sn * py, y + sn * px + c * py);
  }
}

std::string Paint(const char* attr, const std::string& colour, double opacity) {
  if (colour.empty() || colour == "none" || colour == "transparent") {
    return std::string(" ") + attr + "=\"none\"";
  }
  std::string s = std::string(" ") + attr + "=\"" + EscapeMarkup(colour) + "\"";
  if (opacity != 1) s += std::string(" ") + attr + "-opacity=\"" + Num(opacity) + "\"";
  return s;
}

// The path of a Vega symbol shape of `size` (area in px^2) about (0, 0).
std::string SymbolPath(const std::string& shape, double size, double* radius) {
  const double r = std::sqrt(size) / 2;
  *radius = r;
  const double h = std::sqrt(3.0) / 2 * r;
  const double tan30 = 0.5773502691896257;
  auto poly = [](std::initializer_list<std::pair<double, double>> pts) {
    std::string d;
    bool first = true;
    for (const auto& [x, y] : pts) {
      d += (first ? "M" : "L") + Num(x) + "," + Num(y);
      first = false;
    }
    return d + "Z";
  };
  if (shape == "square") return poly({{-r, -r}, {r, -r}, {r, r}, {-r, r}});
  if (shape == "diamond") return poly({{-r, 0}, {0, -r}, {r, 0}, {0, r}});
  if (shape == "triangle-up") return poly({{0, -h}, {-r, h}, {r, h}});
  if (shape == "triangle-down") return poly({{0, h}, {-r, -h}, {r, -h}});
  if (shape == "triangle-right") return poly({{h, 0}, {-h, -r}, {-h, r}});
  if (shape == "triangle-left") return poly({{-h, 0}, {h, -r}, {h, r}});
  if (shape == "triangle") {
    const double o = h - r * tan30;
    return poly({{0, -h - o}, {-r, h - o}, {r, h - o}});
  }
  if (shape == "wedge") {
    const double o = h - r * tan30, b = r / 4;
    return poly({{0, -h - o}, {-b, h - o}, {b, h - o}});
  }
  if (shape == "cross") {
    const double s = r / 2.5;
    return poly({{-r, -s},
                 {-r, s},
                 {-s, s},
                 {-s, r},
                 {s, r},
                 {s, s},
                 {r, s},
                 {r, -s},
                 {s, -s},
                 {s, -r},
                 {-s, -r},
                 {-s, -s}});
  }
  if (shape == "stroke") return "M" + Num(-r) + ",0L" + Num(r) + ",0";
  if (shape == "circle") return "";
  Refuse("symbol shape '" + shape + "'");
}

struct SymbolStyle {
  std::string shape = "circle";
  double size = 64, angle = 0;
  std::string fill, stroke;
  double stroke_width = 1, opacity = 1, fill_opacity = 1, stroke_opacity = 1;
};

void DrawSymbol(Layer* l, double x, double y, const SymbolStyle& s) {
  double r = 0;
  const std::string d = SymbolPath(s.shape, s.size, &r);
  std::string paint = Paint("fill", s.fill, s.fill_opacity);
  if (!s.stroke.empty() && s.stroke != "none") {
    paint += Paint("stroke", s.stroke, s.stroke_opacity);
    if (s.stroke_width != 1) paint += " stroke-width=\"" + Num(s.stroke_width) + "\"";
  }
  if (s.opacity != 1) paint += " opacity=\"" + Num(s.opacity) + "\"";
  if (d.empty()) {
    l->svg +=
        "<circle cx=\"" + Num(x) + "\" cy=\"" + Num(y) + "\" r=\"" + Num(r) + "\"" + paint + "/>";
  } else {
    l->svg += "<path transform=\"translate(" + Num(x) + "," + Num(y) + ")" +
              (s.angle != 0 ? " rotate(" + Num(s.angle) + ")" : std::string()) + "\" d=\"" + d +
              "\"" + paint + "/>";
  }
  const double e = r * 1.2 + s.stroke_width / 2;  // wedges reach a little beyond r
  l->box.Add(x - e, y - e);
  l->box.Add(x + e, y + e);
}

void DrawLine(Layer* l, double x1, double y1, double x2, double y2, const std::string& stroke,
              double width, const std::string& extra = "") {
  l->svg += "<line x1=\"" + Num(x1) + "\" y1=\"" + Num(y1) + "\" x2=\"" + Num(x2) + "\" y2=\"" +
            Num(y2) + "\" stroke=\"" + EscapeMarkup(stroke) + "\"" +
            (width != 1 ? " stroke-width=\"" + Num(width) + "\"" : std::string()) + extra + "/>";
  l->box.Add(x1, y1);
  l->box.Add(x2, y2);
}

// ---------------------------------------------------------------------------
// Scopes: the data, scales and size of the spec or of a group mark.

using Rows = std::vector<const json*>;

class Scope {
 public:
  Scope(const Scope* parent, double width, double height)
      : parent_(parent), width_(width), height_(height) {}

  double width() const { return width_; }
  double height() const { return height_; }
  const Scope* parent() const { return parent_; }

  void AddData(const std::string& name, Rows rows) { data_[name] = std::move(rows); }
  const Rows& Data(const std::string& name) const {
    for (const Scope* s = this; s != nullptr; s = s->parent_) {
      auto it = s->data_.find(name);
      if (it != s->data_.end()) return it->second;
    }
    Refuse("data '" + name + "' that no scope defines");
  }
  void AddScale(const std::string& name, std::unique_ptr<Scale> s) { scales_[name] = std::move(s); }
  const Scale& ScaleNamed(const std::string& name) const {
    for (const Scope* s = this; s != nullptr; s = s->parent_) {
      auto it = s->scales_.find(name);
      if (it != s->scales_.end()) return *it->second;
    }
    Refuse("scale '" + name + "' that no scope defines");
  }
  // `l` clipped to this scope's rectangle (a clip path made once): what
  // lies outside is neither drawn nor part of the bounds.
  void Clip(Layer* l, std::string* defs, int* counter) const {
    l->svg = "<g clip-path=\"url(#" + ClipId(defs, counter) + ")\">" + l->svg + "</g>";
    l->box.x1 = std::max(l->box.x1, 0.0);
    l->box.y1 = std::max(l->box.y1, 0.0);
    l->box.x2 = std::min(l->box.x2, width_);
    l->box.y2 = std::min(l->box.y2, height_);
  }
  // A clip path of this scope's rectangle, made once.
  std::string ClipId(std::string* defs, int* counter) const {
    if (clip_id_.empty()) {
      clip_id_ = "clip" + std::to_string(++*counter);
      *defs += "<clipPath id=\"" + clip_id_ + "\"><rect x=\"0\" y=\"0\" width=\"" + Num(width_) +
               "\" height=\"" + Num(height_) + "\"/></clipPath>";
    }
    return clip_id_;
  }

 private:
  const Scope* parent_;
  double width_, height_;
  std::map<std::string, Rows> data_;
  std::map<std::string, std::unique_ptr<Scale>> scales_;
  mutable std::string clip_id_;
};

const json& Member(const json& datum, const std::string& field) {
  static const json kNull;
  if (!datum.is_object()) return kNull;
  auto it = datum.find(field);
  return it == datum.end() ? kNull : *it;
}

// ---------------------------------------------------------------------------
// Encodings: one mark property's rule (or rules with tests), compiled once.

class Channel {
 public:
  Channel(const json& spec, const Scope& scope) {
    if (spec.is_array()) {
      for (const json& r : spec) rules_.push_back(Compile(r, scope));
    } else {
      rules_.push_back(Compile(spec, scope));
    }
  }

  json Eval(const json& datum) const {
    for (const Rule& r : rules_) {
      if (r.test && !Truthy(r.test->Eval(datum, scale_fn_))) continue;
      return Value(r, datum);
    }
    return json();
  }

 private:
  struct Rule {
    std::shared_ptr<Expression> test, signal;
    json value;
    std::string field;
    double group = kNaN;  // {field: {group: width|height}}
    const Scale* scale = nullptr;
    double offset = 0, mult = 1;
    bool has_value = false;
  };

  Rule Compile(const json& r, const Scope& scope) {
    if (!r.is_object()) Refuse("encoding " + r.dump());
    Rule rule;
    for (const auto& [k, v] : r.items()) {
      if (k == "test") {
        rule.test = std::make_shared<Expression>(v.get<std::string>());
      } else if (k == "signal") {
        rule.signal = std::make_shared<Expression>(v.get<std::string>());
      } else if (k == "value") {
        rule.value = v;
        rule.has_value = true;
      } else if (k == "field") {
        if (v.is_string()) {
          rule.field = v.get<std::string>();
        } else if (v.is_object() && v.contains("group") && v.size() == 1) {
          const std::string g = v["group"].get<std::string>();
          // The group that holds the mark: the scope it is drawn in.
          const Scope* p = &scope;
          if (g == "width") {
            rule.group = p->width();
          } else if (g == "height") {
            rule.group = p->height();
          } else {
            Refuse("group field '" + g + "'");
          }
        } else {
          Refuse("field reference " + v.dump());
        }
      } else if (k == "scale") {
        rule.scale = &scope.ScaleNamed(v.get<std::string>());
      } else if (k == "offset" && v.is_number()) {
        rule.offset = v.get<double>();
      } else if (k == "mult" && v.is_number()) {
        rule.mult = v.get<double>();
      } else {
        Refuse("encoding property '" + k + "' in " + r.dump());
      }
    }
    if (!scale_fn_) {
      const Scope* s = &scope;
      scale_fn_ = [s](const std::string& name, const json& v) {
        return s->ScaleNamed(name).Map(v);
      };
    }
    return rule;
  }

  json Value(const Rule& r, const json& datum) const {
    json v;
    if (r.signal) {
      v = r.signal->Eval(datum, scale_fn_);
    } else if (!r.field.empty()) {
      v = Member(datum, r.field);
    } else if (std::isfinite(r.group)) {
      v = r.group;
    } else if (r.has_value) {
      v = r.value;
    } else if (!r.scale) {
      return json();
    }
    if (r.scale) v = r.scale->Map(v);
    if ((r.offset != 0 || r.mult != 1) && v.is_number()) v = v.get<double>() * r.mult + r.offset;
    return v;
  }

  std::vector<Rule> rules_;
  Expression::ScaleFn scale_fn_;
};

// A mark's encoding: its channels by property.
class Encoding {
 public:
  Encoding(const json& mark, const Scope& scope) {
    static const std::set<std::string> kDrawn = {"x",           "y",
                                                 "x2",          "y2",
                                                 "width",       "height",
                                                 "xc",          "yc",
                                                 "fill",        "stroke",
                                                 "strokeWidth", "opacity",
                                                 "fillOpacity", "strokeOpacity",
                                                 "strokeDash",  "size",
                                                 "shape",       "angle",
                                                 "text",        "align",
                                                 "baseline",    "fontSize",
                                                 "fontWeight",  "font",
                                                 "dx",          "dy",
                                                 "url",         "aspect",
                                                 "limit",       "interpolate"};
    static const std::set<std::string> kInteractive = {
        "tooltip", "description", "aria", "cursor", "href", "ariaRole", "ariaRoleDescription"};
    if (!mark.contains("encode")) return;
    for (const auto& [set, enc] : mark["encode"].items()) {
      if (set != "enter" && set != "update") Refuse("encode set '" + set + "'");
      for (const auto& [k, v] : enc.items()) {
        if (kInteractive.count(k)) continue;
        if (!kDrawn.count(k)) Refuse("mark property '" + k + "'");
        channels_.erase(k);
        channels_.emplace(k, Channel(v, scope));
      }
    }
  }
  bool Has(const std::string& k) const { return channels_.count(k) > 0; }
  json Get(const std::string& k, const json& datum) const {
    auto it = channels_.find(k);
    return it == channels_.end() ? json() : it->second.Eval(datum);
  }
  double Num(const std::string& k, const json& datum, double fallback) const {
    auto it = channels_.find(k);
    if (it == channels_.end()) return fallback;
    const json v = it->second.Eval(datum);
    return v.is_null() ? fallback : Number(v, kNaN);
  }
  std::string Str(const std::string& k, const json& datum, const std::string& fallback) const {
    auto it = channels_.find(k);
    if (it == channels_.end()) return fallback;
    const json v = it->second.Eval(datum);
    return v.is_null() ? std::string() : Text(v);
  }

 private:
  std::map<std::string, Channel> channels_;
};

// ---------------------------------------------------------------------------
// The drawing of a spec.

class Drawer {
 public:
  Layer DrawSpec(const json& spec) {
    Scope scope(nullptr, spec.value("width", 0.0), spec.value("height", 0.0));
    Layer l = DrawScope(spec, &scope, /*top=*/true);
    return l;
  }
  const std::string& defs() const { return defs_; }

 private:
  void ReadData(const json& spec, Scope* scope);
  void ReadScales(const json& spec, Scope* scope);
  Layer DrawScope(const json& spec, Scope* scope, bool top);
  void DrawMark(const json& mark, const Scope& scope, Layer* l);
  // A group mark (not a facet): its drawing in its own frame, its place
  // and size.
  Layer DrawGroup(const json& mark, const Scope& scope, double* x, double* y, double* w, double* h);
  void DrawAxis(const json& axis, const Scope& scope, Layer* l);
  Layer DrawLegend(const json& legend, const Scope& scope);
  void DrawTitle(const json& title, Layer* l);

  std::string defs_;
  int clips_ = 0;
};

void Drawer::ReadData(const json& spec, Scope* scope) {
  if (!spec.contains("data")) return;
  for (const json& d : spec["data"]) {
    for (const auto& [k, v] : d.items()) {
      if (k != "name" && k != "values" && k != "source" && k != "transform") {
        Refuse("data property '" + k + "'");
      }
    }
    const std::string name = d.at("name").get<std::string>();
    Rows rows;
    if (d.contains("values")) {
      const json& values = d["values"];
      if (!values.is_array()) Refuse("data '" + name + "' whose values are not an array");
      for (const json& v : values) rows.push_back(&v);
    } else if (d.contains("source")) {
      rows = scope->Data(d["source"].get<std::string>());
    }
    if (d.contains("transform")) {
      for (const json& t : d["transform"]) {
        if (t.value("type", "") != "filter" || !t.contains("expr") || t.size() != 2) {
          Refuse("data transform " + t.dump());
        }
        const Expression e(t["expr"].get<std::string>());
        Rows kept;
        for (const json* r : rows) {
          if (Truthy(e.Eval(*r))) kept.push_back(r);
        }
        rows = std::move(kept);
      }
    }
    scope->AddData(name, std::move(rows));
  }
}

void Drawer::ReadScales(const json& spec, Scope* scope) {
  if (!spec.contains("scales")) return;
  // A range "width" or "height" is the spec's own size (Vega's width and
  // height signals), in a group too.
  const Scope* root = scope;
  while (root->parent() != nullptr) root = root->parent();
  for (const json& s : spec["scales"]) {
    auto values = [scope](const json& d) {
      std::vector<const json*> out;
      auto add = [&](const std::string& data, const std::string& field) {
        for (const json* r : scope->Data(data)) out.push_back(&Member(*r, field));
      };
      for (const auto& [k, v] : d.items()) {
        if (k != "data" && k != "field" && k != "fields")
          Refuse("scale domain property '" + k + "'");
      }
      if (d.contains("field")) {
        add(d.at("data").get<std::string>(), d["field"].get<std::string>());
      } else if (d.contains("fields")) {
        for (const json& f : d["fields"]) {
          if (f.is_string()) {
            add(d.at("data").get<std::string>(), f.get<std::string>());
          } else {
            add(f.at("data").get<std::string>(), f.at("field").get<std::string>());
          }
        }
      } else {
        Refuse("scale domain " + d.dump());
      }
      return out;
    };
    scope->AddScale(s.at("name").get<std::string>(),
                    std::make_unique<Scale>(s, values, root->width(), root->height()));
  }
}

Layer Drawer::DrawScope(const json& spec, Scope* scope, bool top) {
  static const std::set<std::string> kKeys = {
      "$schema", "autosize", "background", "padding", "width", "height",     "data",
      "scales",  "axes",     "legends",    "marks",   "title", "layout",     "type",
      "encode",  "from",     "name",       "clip",    "style", "description"};
  for (const auto& [k, v] : spec.items()) {
    if (!kKeys.count(k)) Refuse("property '" + k + "'");
  }
  if (top && spec.contains("autosize") && spec["autosize"] != "pad") {
    Refuse("autosize " + spec["autosize"].dump());
  }
  ReadData(spec, scope);
  ReadScales(spec, scope);
  Layer l;
  if (spec.contains("axes")) {
    for (const json& a : spec["axes"]) DrawAxis(a, *scope, &l);
  }
  const bool grid = spec.contains("layout");
  std::vector<Layer> cells;
  std::vector<std::pair<double, double>> sizes;
  if (spec.contains("marks")) {
    for (const json& m : spec["marks"]) {
      if (grid && m.value("type", "") == "group" && !m.contains("from")) {
        double x = 0, y = 0, w = 0, h = 0;  // the grid places the panel: x, y unused
        cells.push_back(DrawGroup(m, *scope, &x, &y, &w, &h));
        sizes.emplace_back(w, h);
      } else {
        DrawMark(m, *scope, &l);
      }
    }
  }
  if (grid) {
    const json& g = spec["layout"];
    for (const auto& [k, v] : g.items()) {
      if (k != "columns" && k != "align" && k != "bounds" && k != "padding") {
        Refuse("layout property '" + k + "'");
      }
    }
    if (g.value("bounds", "flush") != "flush" || g.value("align", "all") != "all") {
      Refuse("layout " + g.dump());
    }
    const size_t columns = std::max<size_t>(1, g.value("columns", size_t{1}));
    double pad_row = 0, pad_col = 0;
    if (g.contains("padding") && g["padding"].is_number()) {
      pad_row = pad_col = g["padding"].get<double>();
    } else if (g.contains("padding")) {
      pad_row = g["padding"].value("row", 0.0);
      pad_col = g["padding"].value("column", 0.0);
    }
    double cw = 0, ch = 0;
    for (const auto& [w, h] : sizes) {
      cw = std::max(cw, w);
      ch = std::max(ch, h);
    }
    for (size_t i = 0; i < cells.size(); ++i) {
      const double x = static_cast<double>(i % columns) * (cw + pad_col);
      const double y = static_cast<double>(i / columns) * (ch + pad_row);
      l.Append(cells[i], x, y);
    }
  }
  if (top) {
    l.box.Add(0, 0);
    l.box.Add(scope->width(), scope->height());
  }
  if (spec.contains("legends")) {
    // Vega stacks the legends of one orient, each `kLegendMargin` apart,
    // `kLegendOffset` beyond the content.
    const Box content = l.box;
    double right_y = 0, top_x = 0;
    std::vector<Layer> tops;
    for (const json& lg : spec["legends"]) {
      const std::string orient = lg.value("orient", "right");
      Layer legend = DrawLegend(lg, *scope);
      if (orient == "right") {
        l.Append(legend,
                 (content.empty() ? scope->width() : content.x2) + kLegendOffset - legend.box.x1,
                 right_y - legend.box.y1);
        right_y += legend.box.y2 - legend.box.y1 + kLegendMargin;
      } else if (orient == "top") {
        tops.push_back(std::move(legend));
      } else {
        Refuse("legend orient '" + orient + "'");
      }
    }
    double height = 0;
    for (const Layer& t : tops) height = std::max(height, t.box.y2 - t.box.y1);
    for (const Layer& t : tops) {
      l.Append(t, top_x - t.box.x1,
               (content.empty() ? 0 : content.y1) - kLegendOffset - height - t.box.y1);
      top_x += t.box.x2 - t.box.x1 + kLegendMargin * 2;
    }
  }
  if (spec.contains("title")) DrawTitle(spec["title"], &l);
  return l;
}

Layer Drawer::DrawGroup(const json& mark, const Scope& scope, double* x, double* y, double* w,
                        double* h) {
  const Encoding e(mark, scope);
  const json datum = json::object();
  *x = e.Num("x", datum, 0);
  *y = e.Num("y", datum, 0);
  *w = e.Num("width", datum, 0);
  *h = e.Num("height", datum, 0);
  Scope child(&scope, *w, *h);
  Layer inner = DrawScope(mark, &child, false);
  // The group's own rectangle (its frame), under its content.
  const std::string fill = e.Str("fill", datum, ""), stroke = e.Str("stroke", datum, "");
  if (!fill.empty() || !stroke.empty()) {
    inner.svg = "<rect x=\"0\" y=\"0\" width=\"" + Num(*w) + "\" height=\"" + Num(*h) + "\"" +
                Paint("fill", fill, e.Num("fillOpacity", datum, 1)) +
                (stroke.empty() ? std::string() : Paint("stroke", stroke, 1)) + "/>" + inner.svg;
    inner.box.Add(0, 0);
    inner.box.Add(*w, *h);
  }
  if (mark.value("clip", false)) child.Clip(&inner, &defs_, &clips_);
  return inner;
}

void Drawer::DrawMark(const json& mark, const Scope& scope, Layer* out) {
  static const std::set<std::string> kKeys = {"type",  "from", "encode",  "marks",      "scales",
                                              "axes",  "data", "title",   "clip",       "name",
                                              "style", "role", "legends", "interactive"};
  for (const auto& [k, v] : mark.items()) {
    if (!kKeys.count(k)) Refuse("mark property '" + k + "'");
  }
  const std::string type = mark.value("type", "");
  if (type == "group") {
    if (mark.contains("from")) {
      const json& from = mark["from"];
      if (!from.contains("facet")) Refuse("group mark from " + from.dump());
      const json& f = from["facet"];
      const std::string by = f.at("groupby").get<std::string>();
      const Rows& rows = scope.Data(f.at("data").get<std::string>());
      std::vector<json> keys;
      std::vector<Rows> groups;
      for (const json* r : rows) {
        const json& k = Member(*r, by);
        size_t i = 0;
        while (i < keys.size() && !SameValue(keys[i], k)) ++i;
        if (i == keys.size()) {
          keys.push_back(k);
          groups.emplace_back();
        }
        groups[i].push_back(r);
      }
      const Encoding e(mark, scope);
      // Each facet draws the group's content: the mark without its facet
      // and its own encoding (the group's place and size, evaluated here).
      json inner = mark;
      inner.erase("from");
      inner.erase("encode");
      for (size_t i = 0; i < keys.size(); ++i) {
        const json datum = {{by, keys[i]}};
        Scope child(&scope, e.Num("width", datum, 0), e.Num("height", datum, 0));
        child.AddData(f.at("name").get<std::string>(), groups[i]);
        Layer l = DrawScope(inner, &child, false);
        if (mark.value("clip", false)) {
          l.svg = "<g clip-path=\"url(#" + child.ClipId(&defs_, &clips_) + ")\">" + l.svg + "</g>";
        }
        out->Append(l, e.Num("x", datum, 0), e.Num("y", datum, 0));
      }
      return;
    }
    double x = 0, y = 0, w = 0, h = 0;
    Layer l = DrawGroup(mark, scope, &x, &y, &w, &h);
    out->Append(l, x, y);
    return;
  }

  Rows rows;
  static const json kEmpty = json::object();
  if (mark.contains("from")) {
    if (!mark["from"].contains("data") || mark["from"].size() != 1) {
      Refuse("mark from " + mark["from"].dump());
    }
    rows = scope.Data(mark["from"]["data"].get<std::string>());
  } else {
    rows.push_back(&kEmpty);
  }
  const Encoding e(mark, scope);
  const bool painted = e.Has("fill") || e.Has("stroke");
  Layer l;
  auto opacity = [&](const json& d, const char* k) { return e.Num(k, d, 1.0); };
  auto dash = [&](const json& d) {
    const json v = e.Get("strokeDash", d);
    if (!v.is_array() || v.empty()) return std::string();
    std::string s = " stroke-dasharray=\"";
    for (size_t i = 0; i < v.size(); ++i) s += (i ? "," : "") + Num(Number(v[i], 0));
    return s + "\"";
  };
  // A rect's or image's extent along one axis: from x to x2, from x over
  // its width, or its width about the centre xc.
  auto xy_span = [&](const json& d, const char* a, const char* a2, const char* size,
                     const char* centre, double* lo, double* hi) {
    double v = e.Num(a, d, kNaN), v2 = e.Num(a2, d, kNaN);
    const double s = e.Num(size, d, kNaN);
    if (e.Has(centre)) {
      const double c = e.Num(centre, d, kNaN);
      v = c - s / 2;
      v2 = c + s / 2;
    }
    if (!std::isfinite(v2) && std::isfinite(s)) v2 = v + s;
    *lo = std::min(v, v2);
    *hi = std::max(v, v2);
  };
  if (type == "rect") {
    for (const json* d : rows) {
      double x0, x1, y0, y1;
      xy_span(*d, "x", "x2", "width", "xc", &x0, &x1);
      xy_span(*d, "y", "y2", "height", "yc", &y0, &y1);
      if (!std::isfinite(x0 + x1 + y0 + y1)) continue;
      const std::string fill = painted ? e.Str("fill", *d, "") : kDefaultColour;
      const std::string stroke = e.Str("stroke", *d, "");
      std::string s = "<rect x=\"" + Num(x0) + "\" y=\"" + Num(y0) + "\" width=\"" + Num(x1 - x0) +
                      "\" height=\"" + Num(y1 - y0) + "\"" +
                      Paint("fill", fill, opacity(*d, "fillOpacity"));
      if (!stroke.empty()) {
        s += Paint("stroke", stroke, opacity(*d, "strokeOpacity"));
        const double w = e.Num("strokeWidth", *d, 1);
        if (w != 1) s += " stroke-width=\"" + Num(w) + "\"";
        s += dash(*d);
      }
      const double o = opacity(*d, "opacity");
      if (o != 1) s += " opacity=\"" + Num(o) + "\"";
      l.svg += s + "/>";
      l.box.Add(x0, y0);
      l.box.Add(x1, y1);
    }
  } else if (type == "rule") {
    for (const json* d : rows) {
      const double x = e.Num("x", *d, 0), y = e.Num("y", *d, 0);
      const double x2 = e.Num("x2", *d, x), y2 = e.Num("y2", *d, y);
      if (!std::isfinite(x + y + x2 + y2)) continue;
      const std::string stroke = painted ? e.Str("stroke", *d, "") : "#000";
      if (stroke.empty()) continue;
      std::string extra = dash(*d);
      const double so = opacity(*d, "strokeOpacity"), o = opacity(*d, "opacity");
      if (so != 1) extra += " stroke-opacity=\"" + Num(so) + "\"";
      if (o != 1) extra += " opacity=\"" + Num(o) + "\"";
      DrawLine(&l, x, y, x2, y2, stroke, e.Num("strokeWidth", *d, 1), extra);
    }
  } else if (type == "symbol") {
    for (const json* d : rows) {
      const double x = e.Num("x", *d, 0), y = e.Num("y", *d, 0);
      if (!std::isfinite(x) || !std::isfinite(y)) continue;
      SymbolStyle s;
      s.shape = e.Str("shape", *d, "circle");
      s.size = e.Num("size", *d, 64);
      s.angle = e.Num("angle", *d, 0);
      s.fill = painted ? e.Str("fill", *d, "") : kDefaultColour;
      s.stroke = e.Str("stroke", *d, "");
      s.stroke_width = e.Num("strokeWidth", *d, 1);
      s.opacity = opacity(*d, "opacity");
      s.fill_opacity = opacity(*d, "fillOpacity");
      s.stroke_opacity = opacity(*d, "strokeOpacity");
      if (s.fill.empty() && s.stroke.empty()) continue;
      DrawSymbol(&l, x, y, s);
    }
  } else if (type == "line" || type == "area") {
    if (rows.empty()) return;
    const json& d0 = *rows.front();
    if (e.Has("interpolate") && e.Str("interpolate", d0, "linear") != "linear") {
      Refuse("line interpolate '" + e.Str("interpolate", d0, "") + "'");
    }
    // One path through the items in data order, broken where an item has
    // no position; an area closes along y2 back to its start.
    std::string d;
    std::vector<std::pair<double, double>> top, base;
    auto flush = [&] {
      if (top.empty()) return;
      for (size_t i = 0; i < top.size(); ++i) {
        d += (i ? "L" : "M") + Num(top[i].first) + "," + Num(top[i].second);
      }
      if (type == "area") {
        for (size_t i = base.size(); i-- > 0;)
          d += "L" + Num(base[i].first) + "," + Num(base[i].second);
        d += "Z";
      }
      top.clear();
      base.clear();
    };
    for (const json* r : rows) {
      const double x = e.Num("x", *r, kNaN), y = e.Num("y", *r, kNaN);
      const double y2 = type == "area" ? e.Num("y2", *r, 0) : 0;
      if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(y2)) {
        flush();
        continue;
      }
      top.emplace_back(x, y);
      l.box.Add(x, y);
      if (type == "area") {
        base.emplace_back(x, y2);
        l.box.Add(x, y2);
      }
    }
    flush();
    if (d.empty()) return;
    std::string paint;
    if (type == "line") {
      const std::string stroke = painted ? e.Str("stroke", d0, "") : kDefaultColour;
      paint = " fill=\"none\"" + Paint("stroke", stroke, opacity(d0, "strokeOpacity"));
      const double w = e.Num("strokeWidth", d0, painted ? 1 : 2);
      if (w != 1) paint += " stroke-width=\"" + Num(w) + "\"";
      paint += dash(d0);
    } else {
      paint = Paint("fill", painted ? e.Str("fill", d0, "") : kDefaultColour,
                    opacity(d0, "fillOpacity"));
      const std::string stroke = e.Str("stroke", d0, "");
      if (!stroke.empty()) paint += Paint("stroke", stroke, opacity(d0, "strokeOpacity"));
    }
    const double o = opacity(d0, "opacity");
    if (o != 1) paint += " opacity=\"" + Num(o) + "\"";
    l.svg += "<path d=\"" + d + "\"" + paint + "/>";
  } else if (type == "text") {
    for (const json* d : rows) {
      const double x = e.Num("x", *d, 0) + e.Num("dx", *d, 0);
      const double y = e.Num("y", *d, 0) + e.Num("dy", *d, 0);
      if (!std::isfinite(x) || !std::isfinite(y)) continue;
      TextStyle s;
      s.size = e.Num("fontSize", *d, 11);
      s.bold = e.Str("fontWeight", *d, "normal") == "bold";
      s.fill = e.Has("fill") ? e.Str("fill", *d, "") : "#000";
      s.align = e.Str("align", *d, "left");
      s.baseline = e.Str("baseline", *d, "alphabetic");
      s.angle = e.Num("angle", *d, 0);
      s.opacity = opacity(*d, "opacity");
      s.limit = e.Num("limit", *d, 0);
      if (s.fill.empty()) continue;
      DrawText(&l, x, y, e.Str("text", *d, ""), s);
    }
  } else if (type == "image") {
    for (const json* d : rows) {
      double x0, x1, y0, y1;
      xy_span(*d, "x", "x2", "width", "xc", &x0, &x1);
      xy_span(*d, "y", "y2", "height", "yc", &y0, &y1);
      const std::string url = e.Str("url", *d, "");
      if (!std::isfinite(x0 + x1 + y0 + y1) || url.empty()) continue;
      const json aspect = e.Get("aspect", *d);
      const double o = opacity(*d, "opacity");
      l.svg += "<image x=\"" + Num(x0) + "\" y=\"" + Num(y0) + "\" width=\"" + Num(x1 - x0) +
               "\" height=\"" + Num(y1 - y0) + "\" preserveAspectRatio=\"" +
               (aspect.is_boolean() && !aspect.get<bool>() ? "none" : "xMidYMid") + "\"" +
               (o != 1 ? " opacity=\"" + Num(o) + "\"" : std::string()) + " xlink:href=\"" +
               EscapeMarkup(url) + "\"/>";
      l.box.Add(x0, y0);
      l.box.Add(x1, y1);
    }
  } else {
    Refuse("mark type '" + type + "'");
  }
  if (mark.value("clip", false) && !l.svg.empty()) scope.Clip(&l, &defs_, &clips_);
  out->Append(l, 0, 0);
}

void Drawer::DrawAxis(const json& axis, const Scope& scope, Layer* out) {
  static const std::set<std::string> kKeys = {
      "orient", "scale",      "title",      "tickCount",     "labelFontSize", "titleFontSize",
      "grid",   "labelAngle", "labelAlign", "labelLimit",    "format",        "domain",
      "ticks",  "labels",     "zindex",     "labelBaseline", "titlePadding",  "labelPadding",
      "offset", "tickSize",   "values"};
  for (const auto& [k, v] : axis.items()) {
    if (!kKeys.count(k)) Refuse("axis property '" + k + "'");
  }
  const std::string orient = axis.at("orient").get<std::string>();
  const Scale& s = scope.ScaleNamed(axis.at("scale").get<std::string>());
  const bool vertical = orient == "left" || orient == "right";
  if (!vertical && orient != "bottom" && orient != "top") Refuse("axis orient '" + orient + "'");
  const double count = axis.value("tickCount", 10.0);
  const double sign = orient == "left" || orient == "top" ? -1 : 1;
  const double tick_size = axis.value("tickSize", kTickSize);
  const double label_padding = axis.value("labelPadding", kLabelPadding);
  const double offset = axis.value("offset", 0.0);
  std::vector<json> ticks;
  if (axis.contains("values")) {
    ticks.assign(axis["values"].begin(), axis["values"].end());
  } else {
    ticks = s.TickValues(count);
  }
  const std::vector<std::string> labels = s.Labels(ticks, count, axis.value("format", ""));
  // Where the axis lies: along the bottom or right edge of the scope, or at 0.
  const double along = orient == "bottom" ? scope.height() : orient == "right" ? scope.width() : 0;
  Layer l;
  const auto [r0, r1] = s.RangeEnds();
  // Grid lines first, under the rest (and under the marks drawn later).
  if (axis.value("grid", false)) {
    for (const json& t : ticks) {
      const double p = std::round(s.Position(t));
      if (!std::isfinite(p)) continue;
      if (vertical) {
        DrawLine(&l, 0, p + 0.5, scope.width(), p + 0.5, kGridColour, 1);
      } else {
        DrawLine(&l, p + 0.5, 0, p + 0.5, scope.height(), kGridColour, 1);
      }
    }
    // The grid does not reach beyond the scope: no part of the bounds.
    l.box = Box();
  }
  Layer g;  // in the axis's frame: 0 on the axis line, `sign` outwards
  auto put = [vertical](double p, double d) {
    return vertical ? std::make_pair(d, p) : std::make_pair(p, d);
  };
  if (axis.value("domain", true)) {
    const auto [ax, ay] = put(r0, 0);
    const auto [bx, by] = put(r1, 0);
    DrawLine(&g, ax + 0.5, ay + 0.5, bx + 0.5, by + 0.5, kAxisColour, 1);
  }
  if (axis.value("ticks", true)) {
    for (const json& t : ticks) {
      const double p = std::round(s.Position(t));
      if (!std::isfinite(p)) continue;
      const auto [ax, ay] = put(p, 0);
      const auto [bx, by] = put(p, sign * tick_size);
      DrawLine(&g, ax + 0.5, ay + 0.5, bx + 0.5, by + 0.5, kAxisColour, 1);
    }
  }
  // Labels, and how far they reach from the axis line.
  double extent = tick_size + label_padding;
  if (axis.value("labels", true)) {
    TextStyle ts;
    ts.size = axis.value("labelFontSize", kAxisLabelSize);
    ts.limit = axis.value("labelLimit", kAxisLabelLimit);
    ts.angle = axis.value("labelAngle", 0.0);
    ts.align = axis.value("labelAlign",
                          vertical ? (orient == "left" ? "right" : "left") : std::string("center"));
    ts.baseline = axis.value("labelBaseline", vertical             ? std::string("middle")
                                              : orient == "bottom" ? "top"
                                                                   : "bottom");
    Layer labels_layer;
    for (size_t i = 0; i < ticks.size(); ++i) {
      const double p = s.Position(ticks[i]);
      if (!std::isfinite(p)) continue;
      const auto [x, y] = put(p, sign * (tick_size + label_padding));
      DrawText(&labels_layer, x, y, labels[i], ts);
    }
    if (!labels_layer.box.empty()) {
      extent = vertical ? (orient == "left" ? -labels_layer.box.x1 : labels_layer.box.x2)
                        : (orient == "top" ? -labels_layer.box.y1 : labels_layer.box.y2);
    }
    g.Append(labels_layer, 0, 0);
  }
  const std::string title = axis.value("title", "");
  if (!title.empty()) {
    TextStyle ts;
    ts.size = axis.value("titleFontSize", kAxisTitleSize);
    ts.bold = true;
    ts.align = "center";
    const double d = sign * (extent + axis.value("titlePadding", kAxisTitlePadding));
    const double mid = (r0 + r1) / 2;
    if (vertical) {
      ts.angle = orient == "left" ? -90 : 90;
      ts.baseline = "bottom";
      DrawText(&g, d, mid, title, ts);
    } else {
      ts.baseline = orient == "bottom" ? "top" : "bottom";
      DrawText(&g, mid, d, title, ts);
    }
  }
  const auto [gx, gy] = put(0, along + sign * offset);
  l.Append(g, gx, gy);
  out->Append(l, 0, 0);
}

Layer Drawer::DrawLegend(const json& legend, const Scope& scope) {
  static const std::set<std::string> kKeys = {"fill",   "stroke",     "shape",   "size",
                                              "title",  "type",       "orient",  "direction",
                                              "format", "symbolType", "columns", "opacity"};
  for (const auto& [k, v] : legend.items()) {
    if (!kKeys.count(k)) Refuse("legend property '" + k + "'");
  }
  Layer l;
  double y = 0;
  const std::string title = legend.value("title", "");
  if (!title.empty()) {
    TextStyle ts;
    ts.size = kAxisTitleSize;
    ts.bold = true;
    ts.baseline = "top";
    ts.limit = kLegendTitleLimit;
    DrawText(&l, 0, 0, title, ts);
    y = kAxisTitleSize + kLegendTitlePadding;
  }
  const Scale* fill = legend.contains("fill") ? &scope.ScaleNamed(legend["fill"]) : nullptr;
  const Scale* stroke = legend.contains("stroke") ? &scope.ScaleNamed(legend["stroke"]) : nullptr;
  const Scale* shape = legend.contains("shape") ? &scope.ScaleNamed(legend["shape"]) : nullptr;
  const Scale* size = legend.contains("size") ? &scope.ScaleNamed(legend["size"]) : nullptr;
  const Scale* main = fill ? fill : stroke ? stroke : shape ? shape : size;
  if (main == nullptr) Refuse("legend without a scale: " + legend.dump());
  const std::string format = legend.value("format", "");
  TextStyle label;
  label.size = kAxisLabelSize;
  label.baseline = "middle";
  label.limit = kLegendLabelLimit;

  const bool gradient =
      legend.value("type", main->discrete() ? "symbol" : "gradient") == "gradient";
  if (gradient) {
    if (main->discrete() || !main->colours()) Refuse("gradient legend of a non-colour scale");
    const std::string id = "gradient" + std::to_string(++clips_);
    // Vertical: the domain's start at the bottom.
    std::string stops;
    constexpr int kStops = 16;
    for (int i = 0; i <= kStops; ++i) {
      const double t = static_cast<double>(i) / kStops;
      stops += "<stop offset=\"" + Num(t) + "\" stop-color=\"" + main->ColourAt(t) + "\"/>";
    }
    defs_ += "<linearGradient id=\"" + id + "\" x1=\"0\" y1=\"1\" x2=\"0\" y2=\"0\">" + stops +
             "</linearGradient>";
    l.svg += "<rect x=\"0\" y=\"" + Num(y) + "\" width=\"" + Num(kGradientThickness) +
             "\" height=\"" + Num(kGradientLength) + "\" fill=\"url(#" + id + ")\"/>";
    l.box.Add(0, y);
    l.box.Add(kGradientThickness, y + kGradientLength);
    // Vega's gradient labels: about 2 per 100 px of the gradient's length,
    // a log scale's thinned by d3's label filter, overlapping ones dropped.
    const double count = std::max(2.0, 2 * std::floor(kGradientLength / 100));
    std::vector<json> ticks = main->TickValues(count);
    std::vector<std::string> text = main->Labels(ticks, count, format);
    double last = kInf;
    for (size_t i = 0; i < ticks.size(); ++i) {
      if (text[i].empty()) continue;
      const double v = Number(ticks[i]);
      const double f = main->Fraction(v);
      if (f < -1e-9 || f > 1 + 1e-9) continue;
      const double ly = y + (1 - f) * kGradientLength;
      if (last - ly < label.size + 1) continue;
      last = ly;
      // Vega keeps the end labels within the gradient's length.
      TextStyle end = label;
      if (f < 1e-9) end.baseline = "bottom";
      if (f > 1 - 1e-9) end.baseline = "top";
      DrawText(&l, kGradientThickness + kGradientLabelOffset, ly, text[i], end);
    }
    return l;
  }
  // A symbol legend: one entry per value of the scale's domain.
  const std::vector<json> values = main->domain();
  const std::vector<std::string> text = main->Labels(values, 10, format);
  const bool horizontal = legend.value("direction", legend.value("orient", "right") == "top"
                                                        ? "horizontal"
                                                        : "vertical") == "horizontal";
  double x = 0;
  for (size_t i = 0; i < values.size(); ++i) {
    SymbolStyle s;
    s.size = size ? Number(size->Map(values[i]), kLegendSymbolSize) : kLegendSymbolSize;
    s.shape = shape ? Text(shape->Map(values[i])) : legend.value("symbolType", "circle");
    s.fill = fill ? Text(fill->Map(values[i])) : "";
    s.stroke = stroke ? Text(stroke->Map(values[i])) : fill ? "" : kAxisColour;
    s.stroke_width = kLegendSymbolStrokeWidth;
    // Vega's entry: the symbol's box (its stroke included) then the label,
    // an entry as tall as the larger of the two.
    const double d = std::sqrt(s.size) + 2;
    const double h = std::max(d, label.size + 4);
    DrawSymbol(&l, x + d / 2, y + d / 2, s);
    DrawText(&l, x + d + kLegendLabelOffset, y + d / 2, text[i], label);
    if (horizontal) {
      x += d + kLegendLabelOffset + TextWidth(text[i], label.size, false) + kLegendColumnPadding;
    } else {
      y += h + kLegendRowPadding;
    }
  }
  return l;
}

void Drawer::DrawTitle(const json& title, Layer* l) {
  std::string text;
  std::vector<std::string> subtitle;
  double size = 13, sub_size = 12, offset = kTitleOffset;
  std::string anchor = "middle";
  if (title.is_string()) {
    text = title.get<std::string>();
  } else {
    static const std::set<std::string> kKeys = {
        "text", "subtitle", "fontSize", "anchor", "subtitleFontSize", "offset", "orient", "frame"};
    for (const auto& [k, v] : title.items()) {
      if (!kKeys.count(k)) Refuse("title property '" + k + "'");
    }
    if (title.value("orient", "top") != "top") Refuse("title orient " + title["orient"].dump());
    text = title.value("text", "");
    if (title.contains("subtitle")) {
      const json& s = title["subtitle"];
      if (s.is_array()) {
        for (const json& line : s) subtitle.push_back(line.get<std::string>());
      } else {
        subtitle.push_back(s.get<std::string>());
      }
    }
    size = title.value("fontSize", size);
    sub_size = title.value("subtitleFontSize", sub_size);
    offset = title.value("offset", offset);
    anchor = title.value("anchor", anchor);
  }
  const Box b = l->box.empty() ? Box{0, 0, 0, 0} : l->box;
  // Vega's line height of text of several lines: its font size + 2.
  const double line = sub_size + 2;
  const double height = size + (subtitle.empty() ? 0 : kSubtitlePadding + line * subtitle.size());
  const double y = b.y1 - offset - height;
  const double x = anchor == "start" ? b.x1 : anchor == "end" ? b.x2 : (b.x1 + b.x2) / 2;
  TextStyle ts;
  ts.size = size;
  ts.bold = true;
  ts.baseline = "top";
  ts.align = anchor == "start" ? "left" : anchor == "end" ? "right" : "center";
  Layer t;
  DrawText(&t, x, y, text, ts);
  ts.size = sub_size;
  ts.bold = false;
  for (size_t i = 0; i < subtitle.size(); ++i) {
    DrawText(&t, x, y + size + kSubtitlePadding + line * i, subtitle[i], ts);
  }
  l->Append(t, 0, 0);
}

}  // namespace

double TextWidth(const std::string& text, double size, bool bold) {
  const auto& table = bold ? kBold : kBook;
  double units = 0;
  for (size_t i = 0; i < text.size();) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c < 0x80) {
      units += c >= 32 && c < 127 ? table[c - 32] : 0;
      ++i;
      continue;
    }
    // A character beyond ASCII: the width of a digit (Greek letters,
    // degree and minus signs are about as wide).
    units += table['0' - 32];
    ++i;
    while (i < text.size() && (static_cast<unsigned char>(text[i]) & 0xC0) == 0x80) ++i;
  }
  return units * size / 2048.0;
}

std::string DrawSvg(const json& spec) {
  if (!spec.is_object()) Refuse("a spec that is not a JSON object");
  Drawer drawer;
  Layer l = drawer.DrawSpec(spec);
  const double pad = spec.contains("padding") ? Number(spec["padding"], 0) : 0;
  if (spec.contains("padding") && !spec["padding"].is_number())
    Refuse("padding " + spec["padding"].dump());
  Box b = l.box;
  if (b.empty()) b = {0, 0, 0, 0};
  // Vega's "pad": the spec's size, grown by what the content reaches beyond
  // it on each side (each rounded up), and the padding.
  const double sw = spec.value("width", 0.0), sh = spec.value("height", 0.0);
  const double left = std::ceil(std::max(0.0, -b.x1)), top = std::ceil(std::max(0.0, -b.y1));
  const double w = left + sw + std::ceil(std::max(0.0, b.x2 - sw)) + 2 * pad;
  const double h = top + sh + std::ceil(std::max(0.0, b.y2 - sh)) + 2 * pad;
  const std::string background = spec.value("background", "");
  std::string svg =
      "<svg xmlns=\"http://www.w3.org/2000/svg\" xmlns:xlink=\"http://www.w3.org/1999/xlink\" "
      "version=\"1.1\" width=\"" +
      Num(w) + "\" height=\"" + Num(h) + "\" viewBox=\"0 0 " + Num(w) + " " + Num(h) + "\">";
  if (!drawer.defs().empty()) svg += "<defs>" + drawer.defs() + "</defs>";
  if (!background.empty()) {
    svg += "<rect width=\"" + Num(w) + "\" height=\"" + Num(h) + "\" fill=\"" + EscapeMarkup(background) +
           "\"/>";
  }
  svg += "<g transform=\"translate(" + Num(pad + left) + "," + Num(pad + top) + ")\">" + l.svg +
         "</g></svg>\n";
  return svg;
}

}  // namespace rtscalib::app::vega

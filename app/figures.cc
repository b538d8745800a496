#include "app/figures.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>
#include <stdexcept>
#include <tuple>
#include "app/coverage.h"

#include "libcalib/eval/error_measures.h"
#include "libcalib/model/kinematics.h"

namespace rtscalib::app {
namespace {

using nlohmann::json;

const cv::Scalar kInk(40, 40, 40);
const cv::Scalar kGrid(225, 225, 225);
const cv::Scalar kWhite(255, 255, 255);
const cv::Scalar kHatch(190, 190, 190);
// Series colours (BGR): blue, orange, green, red.
const cv::Scalar kSeries[4] = {cv::Scalar(180, 119, 31), cv::Scalar(14, 127, 255),
                               cv::Scalar(44, 160, 44), cv::Scalar(40, 39, 214)};
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;

std::string Fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), f, v);
  return buf;
}

// Text with alignment: h = 0 left, 1 centre, 2 right; v = 0 baseline, 1 centre, 2 top.
void Put(cv::Mat& img, const std::string& s, cv::Point p, double scale = 0.45, int h = 0, int v = 0,
         const cv::Scalar& color = kInk, int thickness = 1) {
  int base = 0;
  const cv::Size sz = cv::getTextSize(s, kFont, scale, thickness, &base);
  const int x = p.x - (h == 1 ? sz.width / 2 : h == 2 ? sz.width : 0);
  const int y = p.y + (v == 1 ? sz.height / 2 : v == 2 ? sz.height : 0);
  cv::putText(img, s, cv::Point(x, y), kFont, scale, color, thickness, cv::LINE_AA);
}

// Text turned by 90 degrees (reads bottom to top), centred at p.
void PutVertical(cv::Mat& img, const std::string& s, cv::Point p, double scale = 0.45) {
  int base = 0;
  const cv::Size sz = cv::getTextSize(s, kFont, scale, 1, &base);
  cv::Mat strip(sz.height + base + 4, sz.width + 4, CV_8UC3, kWhite);
  cv::putText(strip, s, cv::Point(2, sz.height + 1), kFont, scale, kInk, 1, cv::LINE_AA);
  cv::Mat turned;
  cv::rotate(strip, turned, cv::ROTATE_90_COUNTERCLOCKWISE);
  const cv::Rect roi(p.x - turned.cols / 2, p.y - turned.rows / 2, turned.cols, turned.rows);
  const cv::Rect inside = roi & cv::Rect(0, 0, img.cols, img.rows);
  if (inside.area() == 0) return;
  turned(cv::Rect(inside.x - roi.x, inside.y - roi.y, inside.width, inside.height))
      .copyTo(img(inside));
}

// 1, 2, 5 x 10^k steps covering [lo, hi] with about n ticks.
std::vector<double> NiceTicks(double lo, double hi, int n) {
  if (!(hi > lo)) return {lo};
  const double raw = (hi - lo) / std::max(n, 1);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0}) {
    if (m * mag >= raw) {
      step = m * mag;
      break;
    }
  }
  std::vector<double> t;
  for (double x = std::ceil(lo / step - 1e-9) * step; x <= hi + 1e-9 * step; x += step)
    t.push_back(std::abs(x) < 1e-12 * step ? 0.0 : x);
  return t;
}

double NiceNumber(double x) {
  if (!(x > 0)) return 1.0;
  const double mag = std::pow(10.0, std::floor(std::log10(x)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * mag >= x * 0.999) return m * mag;
  }
  return 10 * mag;
}

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t i = std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1) + 0.5));
  return v[i];
}

// A plotting area: data coordinates -> image pixels.
struct Panel {
  cv::Rect r;
  double x0 = 0, x1 = 1, y0 = 0, y1 = 1;  // y0 maps to the top when y_down, else to the bottom
  bool y_down = false;
  bool log_y = false;
  cv::Point Map(double x, double y) const {
    const double tx = (x - x0) / (x1 - x0);
    double ty =
        log_y ? (std::log(y) - std::log(y0)) / (std::log(y1) - std::log(y0)) : (y - y0) / (y1 - y0);
    if (!y_down) ty = 1.0 - ty;
    return cv::Point(static_cast<int>(std::lround(r.x + tx * r.width)),
                     static_cast<int>(std::lround(r.y + ty * r.height)));
  }
};

void Axes(cv::Mat& img, const Panel& p, const std::vector<double>& xt,
          const std::vector<double>& yt, const std::string& xlabel, const std::string& ylabel,
          const char* xfmt = "%g", const char* yfmt = "%g", bool grid = true) {
  for (double x : xt) {
    const cv::Point a = p.Map(x, p.y0);
    if (grid) cv::line(img, cv::Point(a.x, p.r.y), cv::Point(a.x, p.r.y + p.r.height), kGrid, 1);
    cv::line(img, cv::Point(a.x, p.r.y + p.r.height), cv::Point(a.x, p.r.y + p.r.height + 5), kInk,
             1);
    Put(img, Fmt(xfmt, x), cv::Point(a.x, p.r.y + p.r.height + 8), 0.42, 1, 2);
  }
  for (double y : yt) {
    const cv::Point a = p.Map(p.x0, y);
    if (grid) cv::line(img, cv::Point(p.r.x, a.y), cv::Point(p.r.x + p.r.width, a.y), kGrid, 1);
    cv::line(img, cv::Point(p.r.x - 5, a.y), cv::Point(p.r.x, a.y), kInk, 1);
    Put(img, Fmt(yfmt, y), cv::Point(p.r.x - 8, a.y), 0.42, 2, 1);
  }
  cv::rectangle(img, p.r, kInk, 1);
  Put(img, xlabel, cv::Point(p.r.x + p.r.width / 2, p.r.y + p.r.height + 30), 0.48, 1, 2);
  if (!ylabel.empty())
    PutVertical(img, ylabel, cv::Point(p.r.x - 52, p.r.y + p.r.height / 2), 0.48);
}

cv::Mat ViridisLut() {
  cv::Mat ramp(256, 1, CV_8UC1);
  for (int i = 0; i < 256; ++i) ramp.at<uchar>(i) = static_cast<uchar>(i);
  cv::Mat lut;
  cv::applyColorMap(ramp, lut, cv::COLORMAP_VIRIDIS);
  return lut;
}

cv::Scalar ColourOf(const cv::Mat& lut, double t) {
  const int i = std::clamp(static_cast<int>(std::lround(255 * t)), 0, 255);
  const cv::Vec3b c = lut.at<cv::Vec3b>(i);
  return cv::Scalar(c[0], c[1], c[2]);
}

void ColourBar(cv::Mat& img, const cv::Mat& lut, cv::Rect r, double vmax,
               const std::string& label) {
  for (int y = 0; y < r.height; ++y) {
    const double t = 1.0 - static_cast<double>(y) / std::max(r.height - 1, 1);
    cv::line(img, cv::Point(r.x, r.y + y), cv::Point(r.x + r.width, r.y + y), ColourOf(lut, t), 1);
  }
  cv::rectangle(img, r, kInk, 1);
  for (double v : NiceTicks(0, vmax, 5)) {
    const int y = r.y + r.height - static_cast<int>(std::lround(v / vmax * r.height));
    cv::line(img, cv::Point(r.x + r.width, y), cv::Point(r.x + r.width + 4, y), kInk, 1);
    Put(img, Fmt("%g", v), cv::Point(r.x + r.width + 7, y), 0.4, 0, 1);
  }
  PutVertical(img, label, cv::Point(r.x + r.width + 58, r.y + r.height / 2), 0.45);
}

void Hatch(cv::Mat& img, cv::Rect r) {
  r &= cv::Rect(0, 0, img.cols, img.rows);
  if (r.area() <= 0) return;
  cv::Mat roi = img(r);
  roi = cv::Scalar(240, 240, 240);
  for (int k = -r.height; k < r.width; k += 8) {
    cv::line(roi, cv::Point(k, r.height), cv::Point(k + r.height, 0), kHatch, 1, cv::LINE_AA);
  }
}

// ---------------------------------------------------------------------------
// Error maps.

struct MapSource {
  std::string key, title, unit;
  double scale = 1;  // to the unit shown
  ObsGroup group = ObsGroup::kEdm;
  int zoom = 0;
};

Figure ErrorMap(const MapSource& src, const std::vector<ObservationResidual>& res,
                const std::set<int>& faces, const FitOptions& fit, const std::string& model) {
  // rms of |residual| per pointing and face.
  std::map<std::tuple<int, double, double>, std::pair<double, int>> cells;
  std::set<double> phis, thetas;
  for (const ObservationResidual& o : res) {
    if (!o.valid || o.group != src.group || (src.group != ObsGroup::kEdm && o.zoom != src.zoom))
      continue;
    auto& c = cells[{o.face, o.phi, o.theta}];
    c.first += o.size * o.size;
    ++c.second;
    phis.insert(std::round(o.phi * 1e4));
    thetas.insert(std::round(ZenithOf(o.theta) * 1e4));
  }
  std::vector<double> values;
  for (const auto& [k, c] : cells) values.push_back(std::sqrt(c.first / c.second) * src.scale);
  const double vmax = NiceNumber(std::max(Percentile(values, 0.98), 1e-12));

  const int panel_w = 430, panel_h = 300, left = 80, top = 84, gap = 90;
  const int n = static_cast<int>(faces.size());
  cv::Mat img(top + panel_h + 70, left + n * panel_w + (n - 1) * gap + 140, CV_8UC3, kWhite);
  Put(img, src.title + ": rms error per pointing [" + src.unit + "]", cv::Point(left, 26), 0.6, 0,
      0, kInk, 1);
  Put(img,
      "model " + model +
          "; hatched: critical regions (not fitted); same colour scale for both faces",
      cv::Point(left, 48), 0.42);
  const cv::Mat lut = ViridisLut();
  const int cell_w = std::clamp(panel_w / std::max<int>(phis.size(), 8), 6, 28);
  const int cell_h = std::clamp(panel_h / std::max<int>(thetas.size(), 6), 6, 28);
  int i = 0;
  for (int face : faces) {
    Panel p;
    p.r = cv::Rect(left + i * (panel_w + gap), top, panel_w, panel_h);
    p.x0 = 0;
    p.x1 = 360;
    p.y_down = true;
    if (face == 1) {
      p.y0 = 0;
      p.y1 = 180;
    } else {
      p.y0 = 360;
      p.y1 = 180;
    }
    // Critical regions: zenith below min or above max (SPEC 1), in readings of this face.
    const double zmin = fit.min_zenith_rad * 180 / M_PI, zmax = fit.max_zenith_rad * 180 / M_PI;
    auto band = [&](double t_a, double t_b) {
      const cv::Point a = p.Map(0, t_a), b = p.Map(360, t_b);
      Hatch(img, cv::Rect(cv::Point(a.x, std::min(a.y, b.y)), cv::Point(b.x, std::max(a.y, b.y))));
    };
    if (face == 1) {
      band(0, zmin);
      band(zmax, 180);
    } else {
      band(360 - zmin, 360);
      band(180, 360 - zmax);
    }
    Axes(img, p, NiceTicks(0, 360, 8),
         face == 1 ? NiceTicks(0, 180, 6) : std::vector<double>{180, 210, 240, 270, 300, 330, 360},
         "phi [deg]", "theta [deg] (zenith at the top)", "%g", "%g", false);
    for (const auto& [k, c] : cells) {
      if (std::get<0>(k) != face) continue;
      const double v = std::sqrt(c.first / c.second) * src.scale;
      const cv::Point m = p.Map(std::get<1>(k) * 180 / M_PI, std::get<2>(k) * 180 / M_PI);
      const cv::Rect box(m.x - cell_w / 2, m.y - cell_h / 2, cell_w, cell_h);
      cv::rectangle(img, box, ColourOf(lut, std::min(v / vmax, 1.0)), cv::FILLED);
      if (v > vmax) cv::rectangle(img, box, cv::Scalar(0, 0, 200), 1);
    }
    cv::rectangle(img, p.r, kInk, 1);
    Put(img, "face " + std::to_string(face), cv::Point(p.r.x + p.r.width / 2, p.r.y - 6), 0.5, 1,
        0);
    ++i;
  }
  ColourBar(img, lut, cv::Rect(img.cols - 120, top, 18, panel_h), vmax,
            "rms error [" + src.unit + "]");
  Figure f;
  f.name = "error_map_" + src.key + ".png";
  f.section = "maps";
  f.title = src.title;
  f.caption = "Root mean square of the observed-minus-model point error at each pointing (" +
              src.unit +
              "), for every observation including the critical regions. Cells outlined in red "
              "exceed the scale.";
  f.image = img;
  return f;
}

// ---------------------------------------------------------------------------
// Image-space residual arrows.

Figure ImageArrows(int zoom, const PipelineResult& r) {
  const CameraTool& cam = r.calibration.model.cams[zoom];
  struct Arrow {
    double u, v, du, dv;
    int n;
  };
  std::vector<Arrow> raw;
  const double zmin = r.calibration.fit_options.min_zenith_rad,
               zmax = r.calibration.fit_options.max_zenith_rad;
  for (const PixelObservation& p : r.obs.pixels) {
    if (p.zoom != zoom || InCriticalRegion(p.theta, zmin, zmax)) continue;
    Eigen::Vector2d pred;
    if (!PredictPixel(r.calibration.model, zoom, p.phi, p.theta, p.X, &pred)) continue;
    raw.push_back({p.uv.x(), p.uv.y(), p.uv.x() - pred.x(), p.uv.y() - pred.y(), 1});
  }
  for (const Record& rec : r.obs.records) {
    if (rec.tool != Tool::kCam || rec.zoom != zoom || InCriticalRegion(rec.theta, zmin, zmax))
      continue;
    Eigen::Vector2d pred;
    if (!PredictPixel(r.calibration.model, zoom, rec.phi, rec.theta, rec.x, &pred)) continue;
    raw.push_back({rec.u, rec.v, rec.u - pred.x(), rec.v - pred.y(), 1});
  }
  // Mean per image cell (16 x 12): the systematic part a person can read.
  const int nx = 16, ny = 12;
  std::map<std::pair<int, int>, Arrow> cells;
  for (const Arrow& a : raw) {
    const int cx = std::clamp(static_cast<int>(a.u / cam.width * nx), 0, nx - 1);
    const int cy = std::clamp(static_cast<int>(a.v / cam.height * ny), 0, ny - 1);
    Arrow& c = cells[{cx, cy}];
    c.u += a.u;
    c.v += a.v;
    c.du += a.du;
    c.dv += a.dv;
    ++c.n;
  }
  std::vector<Arrow> arrows;
  std::vector<double> lengths;
  for (auto& [k, c] : cells) {
    arrows.push_back({c.u / c.n, c.v / c.n, c.du / c.n, c.dv / c.n, c.n});
    lengths.push_back(std::hypot(c.du / c.n, c.dv / c.n));
  }
  const int left = 70, top = 64;
  const double fit_scale = std::min(640.0 / cam.width, 480.0 / cam.height);
  const int w = static_cast<int>(cam.width * fit_scale),
            h = static_cast<int>(cam.height * fit_scale);
  cv::Mat img(top + h + 90, left + w + 40, CV_8UC3, kWhite);
  Put(img,
      "Image residuals, zoom " + std::to_string(zoom) +
          ": observed - predicted pixel, mean per cell",
      cv::Point(left, 26), 0.6);
  Put(img,
      std::to_string(raw.size()) +
          " observations outside the critical regions (image points and camera records), " +
          std::to_string(arrows.size()) + " cells",
      cv::Point(left, 48), 0.42);
  Panel p;
  p.r = cv::Rect(left, top, w, h);
  p.x0 = 0;
  p.x1 = cam.width;
  p.y0 = 0;
  p.y1 = cam.height;
  p.y_down = true;
  Axes(img, p, NiceTicks(0, cam.width, 6), NiceTicks(0, cam.height, 5), "u [px]", "v [px]");
  const double p95 = Percentile(lengths, 0.95);
  const double bar = NiceNumber(std::max(p95, 1e-6));
  const double px_per_unit =
      0.08 * w / bar;  // a bar-sized residual is drawn 8% of the image width long
  for (const Arrow& a : arrows) {
    const cv::Point from = p.Map(a.u, a.v);
    const cv::Point to(static_cast<int>(from.x + a.du * px_per_unit),
                       static_cast<int>(from.y + a.dv * px_per_unit));
    cv::circle(img, from, 2, kSeries[0], cv::FILLED, cv::LINE_AA);
    if (from != to) cv::arrowedLine(img, from, to, kSeries[3], 2, cv::LINE_AA, 0, 0.25);
  }
  // Scale bar below the image.
  const cv::Point a(left, top + h + 62),
      b(left + static_cast<int>(bar * px_per_unit), top + h + 62);
  cv::arrowedLine(img, a, b, kSeries[3], 2, cv::LINE_AA, 0, 0.25);
  Put(img, Fmt("%g px", bar), cv::Point(b.x + 10, b.y), 0.48, 0, 1);
  Figure f;
  f.name = "image_residuals_zoom" + std::to_string(zoom) + ".png";
  f.section = "image";
  f.title = "Image residuals, zoom " + std::to_string(zoom);
  f.caption =
      "Observed minus predicted pixel of every image point and camera record of this zoom, "
      "averaged per "
      "image cell; the scale bar gives the arrow length of " +
      Fmt("%g", bar) + " px. A radial or swirling pattern is a missing distortion term.";
  f.image = img;
  return f;
}

// ---------------------------------------------------------------------------
// Histograms against the fitted Gaussian.

struct Series {
  std::string title, unit;
  std::vector<double> values;  // in `unit`
  double sigma = 0;            // fitted, in `unit`
};

void HistogramPanel(cv::Mat& img, cv::Rect area, const Series& s) {
  const int bins = 36;
  const double range = 4.5 * s.sigma;
  std::vector<int> counts(bins, 0);
  int outside = 0;
  for (double v : s.values) {
    if (std::abs(v) >= range) {
      ++outside;
      continue;
    }
    counts[std::clamp(static_cast<int>((v + range) / (2 * range) * bins), 0, bins - 1)]++;
  }
  const double width = 2 * range / bins;
  double peak = 1;
  for (int c : counts) peak = std::max(peak, static_cast<double>(c));
  const double gauss_peak = s.values.size() * width / (std::sqrt(2 * M_PI) * s.sigma);
  peak = std::max(peak, gauss_peak) * 1.1;
  Panel p;
  p.r = area;
  p.x0 = -range;
  p.x1 = range;
  p.y0 = 0;
  p.y1 = peak;
  Axes(img, p, NiceTicks(-range, range, 6), NiceTicks(0, peak, 4), "residual [" + s.unit + "]",
       "count", "%g", "%g");
  for (int i = 0; i < bins; ++i) {
    const cv::Point a = p.Map(-range + i * width, counts[i]),
                    b = p.Map(-range + (i + 1) * width, 0);
    cv::rectangle(img, cv::Rect(a, b), cv::Scalar(215, 180, 140), cv::FILLED);
    cv::rectangle(img, cv::Rect(a, b), cv::Scalar(160, 120, 80), 1);
  }
  cv::Point last;
  for (int k = 0; k <= 200; ++k) {
    const double x = -range + 2 * range * k / 200;
    const double y = s.values.size() * width * std::exp(-0.5 * x * x / (s.sigma * s.sigma)) /
                     (std::sqrt(2 * M_PI) * s.sigma);
    const cv::Point q = p.Map(x, y);
    if (k > 0) cv::line(img, last, q, kSeries[3], 2, cv::LINE_AA);
    last = q;
  }
  cv::rectangle(img, p.r, kInk, 1);
  double ss = 0;
  for (double v : s.values) ss += v * v;
  const double rms = s.values.empty() ? 0 : std::sqrt(ss / s.values.size());
  Put(img, s.title, cv::Point(area.x + area.width / 2, area.y - 24), 0.5, 1, 0);
  Put(img,
      "fitted sigma " + Fmt("%.3g", s.sigma) + ", rms " + Fmt("%.3g", rms) + " " + s.unit + ", n " +
          std::to_string(s.values.size()) + ", beyond 4.5 sigma: " + std::to_string(outside),
      cv::Point(area.x + area.width / 2, area.y - 7), 0.38, 1, 0);
}

Figure Histograms(const PipelineResult& r) {
  const Diagnosis& d = *r.calibration.diagnosis;
  Series edm{"EDM points (x, y, z)", "mm", {}, d.sigma[0] * 1e3};
  Series cam{"camera points (x, y, z)", "mm", {}, d.sigma[1] * 1e3};
  Series px{"image points (u, v)", "px", {}, d.sigma[2]};
  for (const ObservationResidual& o : d.residuals) {
    if (!o.valid || o.critical) continue;
    if (o.group == ObsGroup::kPixel) {
      px.values.push_back(o.delta.x());
      px.values.push_back(o.delta.y());
    } else {
      Series& s = o.group == ObsGroup::kEdm ? edm : cam;
      for (int k = 0; k < 3; ++k) s.values.push_back(o.delta[k] * 1e3);
    }
  }
  std::vector<const Series*> shown;
  for (const Series* s : {&edm, &cam, &px}) {
    if (!s->values.empty() && s->sigma > 0) shown.push_back(s);
  }
  const int pw = 380, ph = 260, left = 80, gap = 110, top = 100;
  cv::Mat img(top + ph + 60, left + static_cast<int>(shown.size()) * (pw + gap), CV_8UC3, kWhite);
  Put(img, "Residuals against the Gaussian of the fitted sigma (fitted rows)", cv::Point(left, 28),
      0.6);
  for (size_t i = 0; i < shown.size(); ++i) {
    HistogramPanel(img, cv::Rect(left + static_cast<int>(i) * (pw + gap), top, pw, ph), *shown[i]);
  }
  Figure f;
  f.name = "residual_histograms.png";
  f.section = "histograms";
  f.title = "Residual histograms";
  f.caption =
      "Coordinates of observed minus model for the rows the fit uses; the red curve is the normal "
      "density with the fitted (a-posteriori) sigma of the group. Heavy tails point at outliers, a "
      "curve narrower than the bars at a missing effect or an optimistic sigma.";
  f.image = img;
  return f;
}

// ---------------------------------------------------------------------------
// Ladders.

struct Rung {
  std::string label, added;
  double edm_mm = NAN, cam_mm = NAN, px = NAN;
};

Figure LadderFigure(const std::vector<Rung>& rungs, const std::string& name,
                    const std::string& title, const std::string& caption) {
  const int left = 90, top = 70, step = 150;
  const bool has_px =
      std::any_of(rungs.begin(), rungs.end(), [](const Rung& g) { return std::isfinite(g.px); });
  const bool has_mm = std::any_of(rungs.begin(), rungs.end(), [](const Rung& g) {
    return std::isfinite(g.edm_mm) || std::isfinite(g.cam_mm);
  });
  const int pw = std::max(520, static_cast<int>(rungs.size()) * step), ph = 260;
  const int panels = (has_mm ? 1 : 0) + (has_px ? 1 : 0);
  cv::Mat img(top + panels * (ph + 110), left + pw + 60, CV_8UC3, kWhite);
  Put(img, title, cv::Point(left, 28), 0.6);
  int row = 0;
  auto panel = [&](const std::vector<std::pair<std::string, double Rung::*>>& series,
                   const std::string& unit) {
    std::vector<double> all;
    for (const Rung& g : rungs) {
      for (const auto& s : series) {
        if (std::isfinite(g.*(s.second)) && g.*(s.second) > 0) all.push_back(g.*(s.second));
      }
    }
    if (all.empty()) return;
    const double lo = *std::min_element(all.begin(), all.end()),
                 hi = *std::max_element(all.begin(), all.end());
    Panel p;
    p.r = cv::Rect(left, top + row * (ph + 110), pw, ph);
    p.x0 = -0.5;
    p.x1 = rungs.size() - 0.5;
    p.log_y = true;
    p.y0 = std::pow(10.0, std::floor(std::log10(lo)));
    p.y1 = std::pow(10.0, std::ceil(std::log10(hi * 1.0001)));
    if (p.y1 / p.y0 < 10) p.y1 = p.y0 * 10;
    std::vector<double> yt;
    for (double d = p.y0; d <= p.y1 * 1.0001; d *= 10) {
      for (double m : {1.0, 2.0, 5.0}) {
        if (m * d <= p.y1 * 1.0001) yt.push_back(m * d);
      }
    }
    Axes(img, p, {}, yt, "", "rms error [" + unit + "] (log)", "%g", "%g");
    for (size_t i = 0; i < rungs.size(); ++i) {
      const cv::Point a = p.Map(static_cast<double>(i), p.y0);
      cv::line(img, cv::Point(a.x, p.r.y + p.r.height), cv::Point(a.x, p.r.y + p.r.height + 5),
               kInk, 1);
      Put(img, rungs[i].label, cv::Point(a.x, p.r.y + p.r.height + 10), 0.42, 1, 2);
      // One effect per line under the tick.
      std::istringstream words(rungs[i].added);
      std::string word;
      for (int line = 0; words >> word; ++line) {
        Put(img, word, cv::Point(a.x, p.r.y + p.r.height + 30 + 17 * line), 0.4, 1, 2, kSeries[3]);
      }
    }
    int k = 0;
    for (const auto& [label, member] : series) {
      cv::Point last(-1, -1);
      bool any = false;
      for (size_t i = 0; i < rungs.size(); ++i) {
        const double v = rungs[i].*member;
        if (!(std::isfinite(v) && v > 0)) continue;
        const cv::Point q = p.Map(static_cast<double>(i), v);
        if (last.x >= 0) cv::line(img, last, q, kSeries[k], 2, cv::LINE_AA);
        cv::circle(img, q, 4, kSeries[k], cv::FILLED, cv::LINE_AA);
        last = q;
        any = true;
      }
      if (any) {
        const cv::Point legend(p.r.x + p.r.width - 170, p.r.y + 18 + 18 * k);
        cv::line(img, legend, legend + cv::Point(20, 0), kSeries[k], 2, cv::LINE_AA);
        Put(img, label, legend + cv::Point(26, 0), 0.42, 0, 1);
      }
      ++k;
    }
    ++row;
  };
  if (has_mm) panel({{"EDM points", &Rung::edm_mm}, {"camera points", &Rung::cam_mm}}, "mm");
  if (has_px) panel({{"image points", &Rung::px}}, "px");
  Figure f;
  f.name = name;
  f.section = "ladder";
  f.title = title;
  f.caption = caption;
  f.image = img;
  return f;
}

double JsonRms(const json& j, const char* a, const char* b, const char* key) {
  if (!j.contains(a)) return NAN;
  const json& x = b ? j[a] : j;
  if (b && !x.contains(b)) return NAN;
  const json& y = b ? x[b] : x[a];
  if (!y.is_object() || !y.contains(key) || !y.contains("n") || y["n"].get<int>() == 0) return NAN;
  return y[key].get<double>();
}

std::string Added(const std::vector<std::string>& before, const std::vector<std::string>& after) {
  std::string out;
  for (const std::string& e : after) {
    if (std::find(before.begin(), before.end(), e) == before.end())
      out += (out.empty() ? "+" : " +") + e;
  }
  for (const std::string& e : before) {
    if (std::find(after.begin(), after.end(), e) == after.end())
      out += (out.empty() ? "-" : " -") + e;
  }
  return out;
}

// A heat map of cols x rows cells over a width x height image, 480 px wide:
// cells coloured by value / vmax (viridis; vmax a nice number above `max`),
// grey where not finite, white diagonal strokes where `inside` is false
// (extrapolated). The figure's text goes around the panel.
struct HeatMapPanel {
  static constexpr int left = 30, top = 40;
  int width = 480, height = 1;
  cv::Mat image, lut;
  double vmax = 1;
  HeatMapPanel(int image_w, int image_h, int cols, int rows, double max,
               const std::function<double(int, int)>& value,
               const std::function<bool(int, int)>& inside) {
    height =
        std::max(1, static_cast<int>(std::lround(width * double(image_h) / std::max(1, image_w))));
    image = cv::Mat(height + top + 70, width + 2 * left + 110, CV_8UC3, kWhite);
    lut = ViridisLut();
    vmax = std::isfinite(max) && max > 0 ? NiceNumber(max) : 1.0;
    for (int j = 0; j < rows; ++j) {
      for (int i = 0; i < cols; ++i) {
        const cv::Rect r(left + i * width / cols, top + j * height / rows,
                         (i + 1) * width / cols - i * width / cols,
                         (j + 1) * height / rows - j * height / rows);
        const double v = value(i, j);
        if (!std::isfinite(v)) {
          cv::rectangle(image, r, kHatch, cv::FILLED);
          continue;
        }
        cv::rectangle(image, r, ColourOf(lut, std::min(v / vmax, 1.0)), cv::FILLED);
        if (!inside(i, j)) {
          cv::Mat roi = image(r & cv::Rect(0, 0, image.cols, image.rows));
          for (int k = -roi.rows; k < roi.cols; k += 6) {
            cv::line(roi, cv::Point(k, roi.rows), cv::Point(k + roi.rows, 0), kWhite, 1,
                     cv::LINE_AA);
          }
        }
      }
    }
  }
};

}  // namespace

Figure DifferenceFigure(const ZoomDifference& d) {
  const HeatMapPanel p(
      d.width, d.height, d.cols, d.rows, d.max_px,
      [&](int i, int j) { return d.diff_px[j * d.cols + i]; },
      [&](int i, int j) { return bool(d.inside[j * d.cols + i]); });
  cv::Mat img = p.image;
  const int left = p.left, top = p.top, panel_w = p.width, panel_h = p.height;
  const cv::Mat& lut = p.lut;
  const double vmax = p.vmax;
  cv::rectangle(img, cv::Rect(left, top, panel_w, panel_h), kInk, 1);
  ColourBar(img, lut, cv::Rect(left + panel_w + 20, top, 18, panel_h), vmax, "difference [px]");
  Put(img,
      "zoom " + std::to_string(d.zoom) + ": RMS " + Fmt("%.3g", d.rms_px) + ", max " +
          Fmt("%.3g", d.max_px) + " px; rotation removed " +
          Fmt("%.3g", d.rotation_rad * 180 / M_PI * 3600) + "\"",
      cv::Point(left, 25), 0.45);
  Put(img, std::to_string(d.width) + " x " + std::to_string(d.height) + " px (first model's image)",
      cv::Point(left, top + panel_h + 25), 0.42);
  Put(img, "hatched: outside either model's valid region; grey: not predictable",
      cv::Point(left, top + panel_h + 48), 0.42);
  Figure f;
  f.name = "compare_zoom" + std::to_string(d.zoom) + ".png";
  f.section = "compare";
  f.title = "Projection difference, zoom " + std::to_string(d.zoom);
  f.caption =
      "How far apart the two models project one ray, after the best rotation between "
      "their camera frames is removed (docs/compare.md).";
  f.image = img;
  return f;
}

std::vector<unsigned char> EncodePng(const cv::Mat& image) {
  std::vector<unsigned char> out;
  if (image.empty() || !cv::imencode(".png", image, out) || out.empty()) {
    throw std::runtime_error("PNG encoding failed for a " + std::to_string(image.cols) + "x" +
                             std::to_string(image.rows) + " figure");
  }
  return out;
}

// ---------------------------------------------------------------------------
// Image coverage per zoom (app/coverage.h): points per cell of the image and
// every observed point, with the 3x3 ninths whose corners the distortion
// needs.

Figure CoverageFigure(const ZoomCoverage& c, const Observations& obs) {
  const int panel_w = 480;
  const int panel_h =
      std::max(1, static_cast<int>(std::lround(panel_w * double(c.height) / std::max(1, c.width))));
  const int left = 30, top = 40;
  cv::Mat img(panel_h + top + 60, panel_w + 2 * left, CV_8UC3, kWhite);
  const cv::Mat lut = ViridisLut();
  const int vmax = std::max(1, *std::max_element(c.counts.begin(), c.counts.end()));
  for (int j = 0; j < kCoverageCells; ++j) {
    for (int i = 0; i < kCoverageCells; ++i) {
      const int n = c.counts[j * kCoverageCells + i];
      const cv::Rect r(left + i * panel_w / kCoverageCells, top + j * panel_h / kCoverageCells,
                       panel_w / kCoverageCells, panel_h / kCoverageCells);
      if (n == 0) {
        Hatch(img, r);
      } else {
        cv::rectangle(img, r, ColourOf(lut, 0.25 + 0.75 * std::log1p(n) / std::log1p(vmax)),
                      cv::FILLED);
      }
    }
  }
  const double sx = double(panel_w) / std::max(1, c.width),
               sy = double(panel_h) / std::max(1, c.height);
  for (const PixelObservation& p : obs.pixels) {
    if (p.zoom != c.zoom) continue;
    cv::circle(img, cv::Point(left + int(p.uv.x() * sx), top + int(p.uv.y() * sy)), 1, kWhite,
               cv::FILLED);
  }
  for (int k = 1; k < 3; ++k) {
    cv::line(img, cv::Point(left + k * panel_w / 3, top),
             cv::Point(left + k * panel_w / 3, top + panel_h), kInk, 1);
    cv::line(img, cv::Point(left, top + k * panel_h / 3),
             cv::Point(left + panel_w, top + k * panel_h / 3), kInk, 1);
  }
  cv::rectangle(img, cv::Rect(left, top, panel_w, panel_h), kInk, 1);
  Put(img,
      "zoom " + std::to_string(c.zoom) + ": " + std::to_string(c.points) + " points, " +
          Fmt("%.0f", 100 * c.covered_fraction) + "% of cells, radius " +
          Fmt("%.0f", 100 * c.radius_fraction) + "% of corner",
      cv::Point(left, 25), 0.45);
  Put(img, std::to_string(c.width) + " x " + std::to_string(c.height) + " px",
      cv::Point(left, top + panel_h + 25), 0.45);
  Figure f;
  f.name = "coverage_zoom" + std::to_string(c.zoom) + ".png";
  f.section = "image";
  f.title = "Image coverage, zoom " + std::to_string(c.zoom);
  f.caption =
      "Where the observed points fell in the image: points per cell (colour, log scale; hatched "
      "= none) and each point (white). The distortion polynomial is only determined where "
      "points are: empty corner ninths mean it is extrapolated there.";
  f.image = img;
  return f;
}

// Projection uncertainty of one zoom (libcalib/api/uncertainty_map.h): the
// 1-sigma semi-major axis per cell, hatched where the cell centre is outside
// the valid region (the convex hull of the calibration's points, drawn as a
// white polygon), grey where the model cannot predict.
Figure UncertaintyFigure(const UncertaintyMap& m, const UncertaintyMapOptions& o,
                         const CameraTool& cam, bool full) {
  const HeatMapPanel p(
      m.width, m.height, m.cols, m.rows, m.max_px, [&](int i, int j) { return m.Cell(i, j); },
      [&](int i, int j) { return bool(m.inside[j * m.cols + i]); });
  cv::Mat img = p.image;
  const int left = p.left, top = p.top, panel_w = p.width, panel_h = p.height;
  const cv::Mat& lut = p.lut;
  const double vmax = p.vmax;
  const double sx = double(panel_w) / std::max(1, m.width),
               sy = double(panel_h) / std::max(1, m.height);
  if (cam.valid_region.size() >= 3) {
    std::vector<cv::Point> hull;
    for (const Eigen::Vector2d& p : cam.valid_region) {
      hull.emplace_back(left + int(std::lround((p.x() + 0.5) * sx)),
                        top + int(std::lround((p.y() + 0.5) * sy)));
    }
    cv::polylines(img, hull, true, kWhite, 2, cv::LINE_AA);
  }
  cv::rectangle(img, cv::Rect(left, top, panel_w, panel_h), kInk, 1);
  ColourBar(img, lut, cv::Rect(left + panel_w + 20, top, 18, panel_h), vmax, "1-sigma [px]");
  Put(img,
      "zoom " + std::to_string(m.zoom) + ": point at " + Fmt("%g", o.range_m) + " m, min " +
          Fmt("%.3g", m.min_px) + ", median " + Fmt("%.3g", m.median_px) + ", max " +
          Fmt("%.3g", m.max_px) + " px",
      cv::Point(left, 25), 0.45);
  Put(img,
      std::to_string(m.width) + " x " + std::to_string(m.height) + " px; pointing phi " +
          Fmt("%.4g", o.phi) + ", theta " + Fmt("%.4g", o.theta) + " rad; " +
          (full ? "full covariance" : "diagonal approximation (no full covariance)"),
      cv::Point(left, top + panel_h + 25), 0.42);
  Put(img, "hatched: outside the calibration points' hull (white); grey: not predictable",
      cv::Point(left, top + panel_h + 48), 0.42);
  Figure f;
  f.name = "uncertainty_zoom" + std::to_string(m.zoom) + ".png";
  f.section = "uncertainty";
  f.title = "Projection uncertainty, zoom " + std::to_string(m.zoom) + ", point at " +
            Fmt("%g", o.range_m) + " m";
  f.caption =
      "How far (1 sigma, worst direction, pixels) the pixel where a point at " +
      Fmt("%g", o.range_m) +
      " m is seen may lie from the model's prediction, from the uncertainty of this zoom's "
      "intrinsics, distortion and camera tool and of the kinematic chain (first order, J P J^T "
      "with the fit's full covariance). Hatched cells lie outside the convex hull of the "
      "calibration's image points (white outline): there the distortion is extrapolated and "
      "the number is a lower bound at best.";
  f.image = img;
  return f;
}

// ---------------------------------------------------------------------------
std::vector<Figure> MakeFigures(const PipelineResult& r, const json& history) {
  std::vector<Figure> figs;
  for (const ZoomCoverage& c : ComputeCoverage(r.obs, r.calibration.model).zooms) {
    figs.push_back(CoverageFigure(c, r.obs));
  }
  for (const UncertaintyMap& m : r.uncertainty_maps) {
    if (m.determined) {
      figs.push_back(UncertaintyFigure(m, r.uncertainty_options, r.calibration.model.cams[m.zoom],
                                       r.full_covariance));
    }
  }
  if (!r.calibration.diagnosis) return figs;
  const Diagnosis& d = *r.calibration.diagnosis;
  const std::string model = d.model_description;
  // Faces and zooms present.
  std::set<int> faces;
  std::set<int> cam_zooms, pixel_zooms;
  bool edm = false;
  for (const ObservationResidual& o : d.residuals) {
    if (!o.valid) continue;
    faces.insert(o.face);
    if (o.group == ObsGroup::kEdm) edm = true;
    if (o.group == ObsGroup::kCam) cam_zooms.insert(o.zoom);
    if (o.group == ObsGroup::kPixel) pixel_zooms.insert(o.zoom);
  }
  if (edm)
    figs.push_back(ErrorMap({"edm", "EDM points", "mm", 1e3, ObsGroup::kEdm, 0}, d.residuals, faces,
                            r.calibration.fit_options, model));
  for (int z : cam_zooms) {
    figs.push_back(
        ErrorMap({"cam_zoom" + std::to_string(z), "Camera points, zoom " + std::to_string(z), "mm",
                  1e3, ObsGroup::kCam, z},
                 d.residuals, faces, r.calibration.fit_options, model));
  }
  for (int z : pixel_zooms) {
    figs.push_back(
        ErrorMap({"pixels_zoom" + std::to_string(z), "Image points, zoom " + std::to_string(z),
                  "px", 1.0, ObsGroup::kPixel, z},
                 d.residuals, faces, r.calibration.fit_options, model));
  }

  // This run's stepwise ladder.
  if (r.calibration.ladder.size() > 1) {
    std::vector<Rung> rungs;
    for (size_t i = 0; i < r.calibration.ladder.size(); ++i) {
      const LadderStep& s = r.calibration.ladder[i];
      rungs.push_back({"step " + std::to_string(i), s.added.empty() ? "(start)" : "+" + s.added,
                       s.rms.edm_n ? s.rms.edm_m * 1e3 : NAN, s.rms.cam_n ? s.rms.cam_m * 1e3 : NAN,
                       s.rms.pixels_n ? s.rms.pixels_px : NAN});
    }
    figs.push_back(
        LadderFigure(rungs, "ladder_stepwise.png", "The ladder of this run (forward stepwise)",
                     "Error of the fitted rows after each effect the stepwise search added."));
  }
  // Across runs: earlier runs of this output folder, then this one.
  if (history.is_array() && !history.empty()) {
    std::vector<Rung> rungs;
    std::vector<std::string> prev;
    bool first = true;
    auto add = [&](const std::string& label, const std::vector<std::string>& effects,
                   const json& final) {
      Rung g;
      g.label = label;
      g.added = first ? "" : Added(prev, effects);
      g.edm_mm = JsonRms(final, "records", "edm", "rms_m") * 1e3;
      g.cam_mm = JsonRms(final, "records", "cam", "rms_m") * 1e3;
      if (final.contains("pixels") && final["pixels"].value("n", 0) > 0)
        g.px = final["pixels"]["rms_px"].get<double>();
      rungs.push_back(g);
      prev = effects;
      first = false;
    };
    for (const json& h : history) {
      if (!h.contains("final")) continue;
      std::vector<std::string> effects;
      if (h.contains("effects")) effects = h["effects"].get<std::vector<std::string>>();
      add("run " + h.value("run", std::string("?")).substr(0, 3), effects, h["final"]);
    }
    json final = {{"records",
                   {{"edm",
                     {{"rms_m", r.calibration.final_errors.edm.rms_m},
                      {"n", r.calibration.final_errors.edm.n}}},
                    {"cam",
                     {{"rms_m", r.calibration.final_errors.cam.rms_m},
                      {"n", r.calibration.final_errors.cam.n}}}}},
                  {"pixels",
                   {{"rms_px", r.calibration.final_errors.pixels.rms_px},
                    {"n", r.calibration.final_errors.pixels.n}}}};
    add("this run", r.calibration.model.effects.Names(), final);
    figs.push_back(LadderFigure(
        rungs, "ladder_runs.png", "The ladder across runs (this output folder's history)",
        "Final error of every run kept in the output folder (all rows, SPEC 6 `final`); "
        "red: the effects added (+) or removed (-) relative to the run before."));
  }
  for (int z : cam_zooms) {
    if (z < r.calibration.model.NumZooms()) figs.push_back(ImageArrows(z, r));
  }
  for (int z : pixel_zooms) {
    if (z < r.calibration.model.NumZooms() && !cam_zooms.count(z))
      figs.push_back(ImageArrows(z, r));
  }
  figs.push_back(Histograms(r));
  return figs;
}

}  // namespace rtscalib::app

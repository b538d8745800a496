#include "libcalib/camera/opencv_model.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace rtscalib {
namespace {

// Polynomials in s = r^2, coefficients in ascending order.
using Poly = std::vector<double>;

void Trim(Poly* p) {
  while (!p->empty() && p->back() == 0.0) p->pop_back();
}

double Eval(const Poly& p, double s) {
  double v = 0.0;
  for (auto it = p.rbegin(); it != p.rend(); ++it) v = v * s + *it;
  return v;
}

Poly Derivative(const Poly& p) {
  Poly d;
  for (size_t i = 1; i < p.size(); ++i) d.push_back(static_cast<double>(i) * p[i]);
  Trim(&d);
  return d;
}

Poly Multiply(const Poly& a, const Poly& b) {
  if (a.empty() || b.empty()) return {};
  Poly c(a.size() + b.size() - 1, 0.0);
  for (size_t i = 0; i < a.size(); ++i) {
    for (size_t j = 0; j < b.size(); ++j) c[i + j] += a[i] * b[j];
  }
  return c;
}

Poly Add(const Poly& a, const Poly& b, double b_scale) {
  Poly c(std::max(a.size(), b.size()), 0.0);
  for (size_t i = 0; i < a.size(); ++i) c[i] += a[i];
  for (size_t i = 0; i < b.size(); ++i) c[i] += b_scale * b[i];
  Trim(&c);
  return c;
}

// Cauchy's bound: every real root lies in [-B, B].
double RootBound(const Poly& p) {
  double m = 0.0;
  for (size_t i = 0; i + 1 < p.size(); ++i) m = std::max(m, std::abs(p[i] / p.back()));
  return 1.0 + m;
}

int Sign(double v) { return v > 0.0 ? 1 : (v < 0.0 ? -1 : 0); }

// Points in (lo, hi) where p changes sign or touches zero, ascending. The real
// roots of p' split [lo, hi] into pieces on which p is monotone, so each piece
// holds at most one root, found by bisection (exact isolation; no sampling
// step that could miss a pair of close roots).
std::vector<double> RootsIn(Poly p, double lo, double hi) {
  Trim(&p);
  std::vector<double> roots;
  if (p.size() <= 1) return roots;  // constant: no isolated roots
  if (p.size() == 2) {
    const double r = -p[0] / p[1];
    if (r > lo && r < hi) roots.push_back(r);
    return roots;
  }
  std::vector<double> breaks{lo};
  for (double c : RootsIn(Derivative(p), lo, hi)) breaks.push_back(c);
  breaks.push_back(hi);
  for (size_t i = 0; i + 1 < breaks.size(); ++i) {
    double a = breaks[i], b = breaks[i + 1];
    const int sa = Sign(Eval(p, a)), sb = Sign(Eval(p, b));
    if (sb == 0) {
      if (b < hi) roots.push_back(b);
      continue;
    }
    if (sa * sb >= 0) continue;  // no sign change (sa == 0 was recorded as the previous b)
    // Bisection to the last representable split; at most ~1100 halvings of a
    // double interval, 200 is ample for any [0, B] here.
    for (int it = 0; it < 200; ++it) {
      const double mid = 0.5 * (a + b);
      if (mid <= a || mid >= b) break;
      if (Sign(Eval(p, mid)) == sa) {
        a = mid;
      } else {
        b = mid;
      }
    }
    roots.push_back(0.5 * (a + b));
  }
  return roots;
}

struct RadialPolys {
  Poly num, den, slope;  // N(s), D(s), and P(s) with g'(r) = P(s) / D(s)^2
};

RadialPolys MakeRadialPolys(const double* dist) {
  RadialPolys out;
  out.num = {1.0, dist[kK1], dist[kK2], dist[kK3]};
  out.den = {1.0, dist[kK4], dist[kK5], dist[kK6]};
  Trim(&out.num);
  Trim(&out.den);
  // g(r) = r N(s) / D(s), s = r^2:
  //   g'(r) = [(N + 2 s N') D - 2 s N D'] / D^2
  const Poly s_poly{0.0, 2.0};  // 2 s
  const Poly a = Multiply(Add(out.num, Multiply(s_poly, Derivative(out.num)), 1.0), out.den);
  const Poly b = Multiply(Multiply(s_poly, out.num), Derivative(out.den));
  out.slope = Add(a, b, -1.0);
  return out;
}

double FirstPositiveRoot(const Poly& p) {
  if (p.size() <= 1) return std::numeric_limits<double>::infinity();
  const std::vector<double> roots = RootsIn(p, 0.0, RootBound(p) + 1.0);
  return roots.empty() ? std::numeric_limits<double>::infinity() : roots.front();
}

// MaxTrustedRadius for the last coefficients seen by this thread: a fit
// evaluates many residuals with the same distortion block.
double CachedMaxTrustedRadius(const double* dist) {
  thread_local double key[6] = {0, 0, 0, 0, 0, 0};
  thread_local double value = -1;  // -1: not computed yet
  const double k[6] = {dist[kK1], dist[kK2], dist[kK3], dist[kK4], dist[kK5], dist[kK6]};
  bool same = value >= 0;
  for (int i = 0; i < 6 && same; ++i) same = k[i] == key[i];
  if (!same) {
    for (int i = 0; i < 6; ++i) key[i] = k[i];
    value = MaxTrustedRadius(dist);
  }
  return value;
}

double L1(const double v[2]) { return std::abs(v[0]) + std::abs(v[1]); }

}  // namespace

namespace internal {

// Newton's method from the distorted point, halving a step that does not
// reduce |f|_1 (at most 30 times), so that an overshoot cannot jump onto
// another branch of a folded map.
bool SolveDistortion(const double* dist, double xd, double yd, double* x_out, double* y_out,
                     int max_iterations) {
  const double r_max = CachedMaxTrustedRadius(dist);
  double x = xd, y = yd;
  double f[2], J[4];
  DistortionResidual(dist, x, y, xd, yd, f, J);
  for (int it = 0; it < max_iterations; ++it) {
    const double jdet = J[0] * J[3] - J[1] * J[2];
    if (!(jdet > 0)) return false;  // folded (or degenerate) map at the iterate
    const double dx = (f[0] * J[3] - J[1] * f[1]) / jdet;
    const double dy = (J[0] * f[1] - f[0] * J[2]) / jdet;
    double scale = 1.0;
    double x_new = x - dx, y_new = y - dy;
    double f_new[2], J_new[4];
    DistortionResidual(dist, x_new, y_new, xd, yd, f_new, J_new);
    for (int halvings = 0; halvings < 30 && !(L1(f_new) <= L1(f)); ++halvings) {
      scale *= 0.5;
      x_new = x - scale * dx;
      y_new = y - scale * dy;
      DistortionResidual(dist, x_new, y_new, xd, yd, f_new, J_new);
    }
    x = x_new;
    y = y_new;
    std::copy(f_new, f_new + 2, f);
    std::copy(J_new, J_new + 4, J);
    // Relative step test: at convergence the step is rounding noise of x.
    if (std::abs(dx) + std::abs(dy) <= 1e-15 * (1.0 + std::abs(x) + std::abs(y))) break;
  }
  *x_out = x;
  *y_out = y;
  return L1(f) < 1e-12 && x * x + y * y < r_max * r_max && J[0] * J[3] - J[1] * J[2] > 0.0;
}

}  // namespace internal

double MaxTrustedRadius(const double* dist) {
  const RadialPolys polys = MakeRadialPolys(dist);
  const double s = std::min(FirstPositiveRoot(polys.slope), FirstPositiveRoot(polys.den));
  return std::sqrt(s);
}

double MaxTrustedDistortedRadius(const double* dist) {
  const RadialPolys polys = MakeRadialPolys(dist);
  const double s_slope = FirstPositiveRoot(polys.slope);
  const double s_den = FirstPositiveRoot(polys.den);
  // Ending at a pole of the rational term, g grows without bound (it was
  // increasing and positive up to there).
  if (!(s_slope < s_den)) return std::numeric_limits<double>::infinity();
  return std::sqrt(s_slope) * Eval(polys.num, s_slope) / Eval(polys.den, s_slope);
}

}  // namespace rtscalib

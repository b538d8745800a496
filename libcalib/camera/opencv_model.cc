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

bool ProjectWithJacobian(const double* intrinsics, const double* d, const double* m,
                         const double dm_dtau[2][9], const double* point, double* pixel,
                         double* J) {
  ProjectionSteps<double> s;
  if (!ProjectWithTiltMatrix(intrinsics, d, m, point, pixel, &s)) return false;
  constexpr int kIntrinsicsVar = 3, kDistVar = 3 + kNumIntrinsics;
  double* ju = J;
  double* jv = J + kProjectionVars;
  std::fill(J, J + 2 * kProjectionVars, 0.0);
  const double fx = intrinsics[0], fy = intrinsics[1];
  const double x = s.x, y = s.y;
  // (x', y') <- point.
  const double iz = 1.0 / point[2];
  // (x'', y'') <- (x', y'): B, and the coefficients' columns.
  const double r2 = x * x + y * y, r4 = r2 * r2, r6 = r4 * r2;
  const double iden = 1.0 / (1.0 + d[kK4] * r2 + d[kK5] * r4 + d[kK6] * r6);
  const double radial = (1.0 + d[kK1] * r2 + d[kK2] * r4 + d[kK3] * r6) * iden;
  const double radial_r2 = ((d[kK1] + 2.0 * d[kK2] * r2 + 3.0 * d[kK3] * r4) -
                            radial * (d[kK4] + 2.0 * d[kK5] * r2 + 3.0 * d[kK6] * r4)) *
                           iden;
  const double b00 = radial + 2.0 * x * x * radial_r2 + 2.0 * d[kP1] * y + 6.0 * d[kP2] * x +
                     2.0 * d[kS1] * x + 4.0 * d[kS2] * r2 * x;
  const double b01 = 2.0 * x * y * radial_r2 + 2.0 * d[kP1] * x + 2.0 * d[kP2] * y +
                     2.0 * d[kS1] * y + 4.0 * d[kS2] * r2 * y;
  const double b10 = 2.0 * x * y * radial_r2 + 2.0 * d[kP1] * x + 2.0 * d[kP2] * y +
                     2.0 * d[kS3] * x + 4.0 * d[kS4] * r2 * x;
  const double b11 = radial + 2.0 * y * y * radial_r2 + 6.0 * d[kP1] * y + 2.0 * d[kP2] * x +
                     2.0 * d[kS3] * y + 4.0 * d[kS4] * r2 * y;
  // pixel <- (x'', y''): A, through the tilt and the intrinsics.
  const double izt = 1.0 / s.zt, px = s.xt * izt, py = s.yt * izt;
  const double a00 = fx * (m[0] - px * m[6]) * izt, a01 = fx * (m[1] - px * m[7]) * izt;
  const double a10 = fy * (m[3] - py * m[6]) * izt, a11 = fy * (m[4] - py * m[7]) * izt;
  // pixel <- (x', y') = A B, then <- point: dx'/dpoint = (1, 0, -x') / z,
  // dy'/dpoint = (0, 1, -y') / z.
  const double c00 = a00 * b00 + a01 * b10, c01 = a00 * b01 + a01 * b11;
  const double c10 = a10 * b00 + a11 * b10, c11 = a10 * b01 + a11 * b11;
  ju[0] = c00 * iz;
  ju[1] = c01 * iz;
  ju[2] = -(c00 * x + c01 * y) * iz;
  jv[0] = c10 * iz;
  jv[1] = c11 * iz;
  jv[2] = -(c10 * x + c11 * y) * iz;
  // Intrinsics: u = fx xt / zt + cx, v = fy yt / zt + cy.
  ju[kIntrinsicsVar + 0] = px;
  ju[kIntrinsicsVar + 2] = 1.0;
  jv[kIntrinsicsVar + 1] = py;
  jv[kIntrinsicsVar + 3] = 1.0;
  // Distortion coefficients: each moves (x'', y'') by (ex, ey), the pixel by A (ex, ey).
  auto coefficient = [&](int k, double ex, double ey) {
    ju[kDistVar + k] = a00 * ex + a01 * ey;
    jv[kDistVar + k] = a10 * ex + a11 * ey;
  };
  const double rad_terms[3] = {r2 * iden, r4 * iden, r6 * iden};
  coefficient(kK1, x * rad_terms[0], y * rad_terms[0]);
  coefficient(kK2, x * rad_terms[1], y * rad_terms[1]);
  coefficient(kK3, x * rad_terms[2], y * rad_terms[2]);
  coefficient(kK4, -x * radial * rad_terms[0], -y * radial * rad_terms[0]);
  coefficient(kK5, -x * radial * rad_terms[1], -y * radial * rad_terms[1]);
  coefficient(kK6, -x * radial * rad_terms[2], -y * radial * rad_terms[2]);
  coefficient(kP1, 2.0 * x * y, r2 + 2.0 * y * y);
  coefficient(kP2, r2 + 2.0 * x * x, 2.0 * x * y);
  coefficient(kS1, r2, 0.0);
  coefficient(kS2, r4, 0.0);
  coefficient(kS3, 0.0, r2);
  coefficient(kS4, 0.0, r4);
  // The tilt angles move the matrix: (xt, yt, zt) by dm (x'', y'', 1).
  for (int t = 0; t < 2; ++t) {
    const double* dm = dm_dtau[t];
    const double dxt = dm[0] * s.xd + dm[1] * s.yd + dm[2];
    const double dyt = dm[3] * s.xd + dm[4] * s.yd + dm[5];
    const double dzt = dm[6] * s.xd + dm[7] * s.yd + dm[8];
    ju[kDistVar + kTauX + t] = fx * (dxt - px * dzt) * izt;
    jv[kDistVar + kTauX + t] = fy * (dyt - py * dzt) * izt;
  }
  return true;
}

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

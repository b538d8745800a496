// OpenCV's pinhole camera with up to 14 distortion coefficients, templated for
// Ceres autodiff. Must agree with cv::projectPoints / cv::undistortPoints
// (tests/camera/opencv_model_test.cc checks it against OpenCV itself).
//
// Camera frame (SPEC section 2): z along the optical axis, x = image +u,
// y = image +v. Pixel (0,0) is the centre of the top-left pixel.
//
// Parameter blocks (one per zoom level):
//   intrinsics[4]  = fx, fy, cx, cy                                   (pixels)
//   distortion[14] = k1 k2 p1 p2 k3 k4 k5 k6 s1 s2 s3 s4 taux tauy   (OpenCV order)
//
// Projection of camera point X = (X, Y, Z), Z > 0:
//   x' = X/Z, y' = Y/Z, r2 = x'^2 + y'^2
//   radial = (1 + k1 r2 + k2 r2^2 + k3 r2^3) / (1 + k4 r2 + k5 r2^2 + k6 r2^3)
//   x'' = x' radial + 2 p1 x'y' + p2 (r2 + 2x'^2) + s1 r2 + s2 r2^2
//   y'' = y' radial + p1 (r2 + 2y'^2) + 2 p2 x'y' + s3 r2 + s4 r2^2
//   [xt yt zt] = Tilt(taux, tauy) [x'' y'' 1]     (cv::computeTiltProjectionMatrix)
//   u = fx xt/zt + cx,  v = fy yt/zt + cy
// This is the camera inside Klug et al. Eq. 12 (F_CAM, back-projection) and
// Eq. 62 (projection); units: pixels, metres, radians (taux, tauy).
// Valid region: projection for Z > 0; back-projection inside the trusted
// region of MaxTrustedRadius below (docs/camera.md has figures and examples).
#pragma once

#include <cmath>

namespace ceres {
template <typename T, int N>
struct Jet;  // as in ceres/jet_fwd.h; this header does not need Ceres itself
}  // namespace ceres

namespace rtscalib {

constexpr int kNumIntrinsics = 4;
constexpr int kNumDistortion = 14;

enum DistortionIndex {
  kK1 = 0,
  kK2,
  kP1,
  kP2,
  kK3,
  kK4,
  kK5,
  kK6,
  kS1,
  kS2,
  kS3,
  kS4,
  kTauX,
  kTauY
};

// OpenCV's tilt matrix: matProjZ * Ry(tauy) * Rx(taux) with OpenCV's sign
// conventions, row-major 3x3.
template <typename T>
void TiltMatrix(const T& taux, const T& tauy, T m[9]) {
  using std::cos;
  using std::sin;
  const T ctx = cos(taux), stx = sin(taux), cty = cos(tauy), sty = sin(tauy);
  // matRotXY = matRotY * matRotX with
  //   matRotX = [1 0 0; 0 ctx stx; 0 -stx ctx], matRotY = [cty 0 -sty; 0 1 0; sty 0 cty]
  const T r[9] = {cty,  sty * stx,  -sty * ctx,  //
                  T(0), ctx,        stx,         //
                  sty,  -cty * stx, cty * ctx};
  // matProjZ = [r22 0 -r02; 0 r22 -r12; 0 0 1]
  const T p[9] = {r[8], T(0), -r[2], T(0), r[8], -r[5], T(0), T(0), T(1)};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      m[3 * i + j] = p[3 * i + 0] * r[0 + j] + p[3 * i + 1] * r[3 + j] + p[3 * i + 2] * r[6 + j];
    }
  }
}

// Distorts normalised coordinates (x', y') -> (x'', y'') before tilt.
template <typename T>
void DistortNormalized(const T* dist, const T& x, const T& y, T* xd, T* yd) {
  const T r2 = x * x + y * y;
  const T r4 = r2 * r2;
  const T r6 = r4 * r2;
  const T radial = (T(1) + dist[kK1] * r2 + dist[kK2] * r4 + dist[kK3] * r6) /
                   (T(1) + dist[kK4] * r2 + dist[kK5] * r4 + dist[kK6] * r6);
  *xd = x * radial + T(2) * dist[kP1] * x * y + dist[kP2] * (r2 + T(2) * x * x) + dist[kS1] * r2 +
        dist[kS2] * r4;
  *yd = y * radial + dist[kP1] * (r2 + T(2) * y * y) + T(2) * dist[kP2] * x * y + dist[kS3] * r2 +
        dist[kS4] * r4;
}

// The intermediate values of one projection (the formula above), for its
// Jacobian (ProjectWithJacobian).
template <typename T>
struct ProjectionSteps {
  T x, y;        // x', y'
  T xd, yd;      // x'', y''
  T xt, yt, zt;  // Tilt [x'' y'' 1]
};

// Projects a point in the camera frame to a pixel, the tilt matrix given:
// `m` = TiltMatrix(dist[kTauX], dist[kTauY]), which depends on the
// distortion block only, so that a caller projecting many points with one
// camera (a cost function's photo) forms it once. Returns false for points
// on or behind the image plane (Z <= 0): a cost function must then fail,
// never zero its residual. `steps`, when given, receives the intermediate
// values.
template <typename T>
bool ProjectWithTiltMatrix(const T* intrinsics, const T* dist, const T* m, const T* point,
                           T* pixel, ProjectionSteps<T>* steps = nullptr) {
  if (!(point[2] > T(0))) return false;
  const T x = point[0] / point[2];
  const T y = point[1] / point[2];
  T xd, yd;
  DistortNormalized(dist, x, y, &xd, &yd);
  const T xt = m[0] * xd + m[1] * yd + m[2];
  const T yt = m[3] * xd + m[4] * yd + m[5];
  const T zt = m[6] * xd + m[7] * yd + m[8];
  pixel[0] = intrinsics[0] * xt / zt + intrinsics[2];
  pixel[1] = intrinsics[1] * yt / zt + intrinsics[3];
  if (steps != nullptr) *steps = {x, y, xd, yd, xt, yt, zt};
  return true;
}

// The variables of ProjectWithJacobian's Jacobian, in its column order: the
// camera point (3), the intrinsics (4), the distortion (14).
constexpr int kProjectionVars = 3 + kNumIntrinsics + kNumDistortion;

// ProjectWithTiltMatrix in double with its Jacobian
// J = d pixel / d(point, intrinsics, distortion), 2 x kProjectionVars,
// row-major, written out as the chain rule through the formula's steps
//   pixel <- (xt, yt, zt) <- (x'', y'') <- (x', y') <- point,
// each a 2 x 2 or 2 x 3 block, each coefficient entering at its step; the
// tilt angles through dm_dtau[0] = d m / d taux and dm_dtau[1] = d m / d tauy
// (row-major 3 x 3), which the caller forms with m once per camera. For cost
// functions that project many points and chain the result onto wide jets:
// autodiff in kProjectionVars-wide jets does that many times the work of
// the value at every operation, this a few dozen products per point
// (joint_refine_benchmark; tests/camera/opencv_model_test.cc checks J
// against autodiff of ProjectToPixel). False for Z <= 0.
bool ProjectWithJacobian(const double* intrinsics, const double* dist, const double* m,
                         const double dm_dtau[2][9], const double* point, double* pixel,
                         double* J);

// Projects a point in the camera frame to a pixel (ProjectWithTiltMatrix with
// its tilt matrix formed here); false for Z <= 0.
template <typename T>
bool ProjectToPixel(const T* intrinsics, const T* dist, const T* point, T* pixel) {
  T m[9];
  TiltMatrix(dist[kTauX], dist[kTauY], m);
  return ProjectWithTiltMatrix(intrinsics, dist, m, point, pixel);
}

// Trusted region of the back-projection (docs/camera.md). The radial part of
// the distortion maps the undistorted normalised radius r = |(x', y')| to
//   g(r) = r * radial(r^2).
// Back-projection is unique and well conditioned only while g is strictly
// increasing and the rational denominator is positive. MaxTrustedRadius
// returns the first r > 0 where g'(r) = 0 or the denominator vanishes (roots of
// polynomials in s = r^2 of degree <= 6 and <= 3, isolated exactly by the
// roots of their derivatives), or +infinity if there is none. Units: normalised
// image coordinates (r = tan of the angle off the optical axis).
// `dist` holds the 14 coefficients in OpenCV order.
double MaxTrustedRadius(const double* dist);
// g(MaxTrustedRadius(dist)): the largest distorted radius (before tilt) of the
// trusted region, normalised units; +infinity if unbounded.
double MaxTrustedDistortedRadius(const double* dist);

// Back-projects a pixel to normalised coordinates (x', y') such that
// ProjectToPixel((x', y', 1)) == pixel. Newton's method with backtracking on
// the distortion (cv::undistortPoints uses a fixed-point iteration instead;
// both agree inside the trusted region, tests/camera/opencv_model_test.cc).
// Returns false unless the solution
//   - reproduces the distorted point to 1e-12 (normalised units, ~1e-9 px),
//   - lies inside the trusted region: r < MaxTrustedRadius(dist), and
//   - has a positive Jacobian determinant of the full distortion map (so the
//     tangential and thin-prism terms have not folded the image either).
// Works with ceres::Jet: the iteration runs in double, then one Newton step
// in T at the converged point (J in double, f in T) gives exactly the
// implicit-function derivatives -J^-1 d(distortion)/d(params).
template <typename T>
bool UndistortPixel(const T* intrinsics, const T* dist, const T* pixel, T* xn, T* yn,
                    int max_iterations = 20);

// Unit ray in the camera frame for a pixel.
template <typename T>
bool PixelToRay(const T* intrinsics, const T* dist, const T* pixel, T* ray) {
  T x, y;
  if (!UndistortPixel(intrinsics, dist, pixel, &x, &y)) return false;
  using std::sqrt;
  const T n = sqrt(x * x + y * y + T(1));
  ray[0] = x / n;
  ray[1] = y / n;
  ray[2] = T(1) / n;
  return true;
}

// ---------------------------------------------------------------------------
namespace internal {

// Value of a double or of a ceres::Jet; the Jet overload is only instantiated
// when the caller has included Ceres.
inline double ScalarPart(double v) { return v; }
template <typename S, int N>
double ScalarPart(const ceres::Jet<S, N>& v) {
  return ScalarPart(v.a);
}

// Distortion residual f = distort(x, y) - (xd, yd) and its Jacobian
// J = d distort / d(x, y), row-major.
template <typename T>
void DistortionResidual(const T* dist, const T& x, const T& y, const T& xd, const T& yd, T f[2],
                        T J[4]) {
  const T r2 = x * x + y * y;
  const T r4 = r2 * r2, r6 = r4 * r2;
  const T num = T(1) + dist[kK1] * r2 + dist[kK2] * r4 + dist[kK3] * r6;
  const T den = T(1) + dist[kK4] * r2 + dist[kK5] * r4 + dist[kK6] * r6;
  const T radial = num / den;
  const T dnum = dist[kK1] + T(2) * dist[kK2] * r2 + T(3) * dist[kK3] * r4;
  const T dden = dist[kK4] + T(2) * dist[kK5] * r2 + T(3) * dist[kK6] * r4;
  const T dradial_dr2 = (dnum * den - num * dden) / (den * den);
  const T ds_x = dist[kS1] + T(2) * dist[kS2] * r2;  // d(s1 r2 + s2 r4)/dr2
  const T ds_y = dist[kS3] + T(2) * dist[kS4] * r2;
  f[0] = x * radial + T(2) * dist[kP1] * x * y + dist[kP2] * (r2 + T(2) * x * x) + dist[kS1] * r2 +
         dist[kS2] * r4 - xd;
  f[1] = y * radial + dist[kP1] * (r2 + T(2) * y * y) + T(2) * dist[kP2] * x * y + dist[kS3] * r2 +
         dist[kS4] * r4 - yd;
  // d r2/dx = 2x, d r2/dy = 2y
  J[0] = radial + T(2) * x * x * dradial_dr2 + T(2) * dist[kP1] * y + T(6) * dist[kP2] * x +
         T(2) * ds_x * x;
  J[1] = T(2) * x * y * dradial_dr2 + T(2) * dist[kP1] * x + T(2) * dist[kP2] * y + T(2) * ds_x * y;
  J[2] = T(2) * x * y * dradial_dr2 + T(2) * dist[kP1] * x + T(2) * dist[kP2] * y + T(2) * ds_y * x;
  J[3] = radial + T(2) * y * y * dradial_dr2 + T(6) * dist[kP1] * y + T(2) * dist[kP2] * x +
         T(2) * ds_y * y;
}

// Undoes the intrinsics and the tilt: pixel -> (x'', y''). False if the tilt
// makes the pixel's line of sight parallel to the sensor.
template <typename T>
bool UndoIntrinsicsAndTilt(const T* intrinsics, const T* dist, const T* pixel, T* xd, T* yd) {
  using std::abs;
  const T a = (pixel[0] - intrinsics[2]) / intrinsics[0];
  const T b = (pixel[1] - intrinsics[3]) / intrinsics[1];
  T m[9];
  TiltMatrix(dist[kTauX], dist[kTauY], m);
  // Solve m * [xd yd 1]^T ~ [a b 1]^T: (m0 - a m6) xd + (m1 - a m7) yd = a m8 - m2, etc.
  const T a00 = m[0] - a * m[6], a01 = m[1] - a * m[7], r0 = a * m[8] - m[2];
  const T a10 = m[3] - b * m[6], a11 = m[4] - b * m[7], r1 = b * m[8] - m[5];
  const T det = a00 * a11 - a01 * a10;
  if (!(abs(det) > T(0))) return false;
  *xd = (r0 * a11 - a01 * r1) / det;
  *yd = (a00 * r1 - r0 * a10) / det;
  return true;
}

// The double-precision Newton solve of distort(x, y) = (xd, yd) with the
// acceptance tests of UndistortPixel (opencv_model.cc).
bool SolveDistortion(const double* dist, double xd, double yd, double* x, double* y,
                     int max_iterations);

}  // namespace internal

template <typename T>
bool UndistortPixel(const T* intrinsics, const T* dist, const T* pixel, T* xn, T* yn,
                    int max_iterations) {
  T xd, yd;
  if (!internal::UndoIntrinsicsAndTilt(intrinsics, dist, pixel, &xd, &yd)) return false;
  double dist_values[kNumDistortion];
  for (int i = 0; i < kNumDistortion; ++i) dist_values[i] = internal::ScalarPart(dist[i]);
  double x0, y0;
  if (!internal::SolveDistortion(dist_values, internal::ScalarPart(xd), internal::ScalarPart(yd),
                                 &x0, &y0, max_iterations)) {
    return false;
  }
  // One Newton step in T from the converged point: the value moves by
  // rounding only, and for a ceres::Jet the derivative part becomes
  // -J^-1 d f / d(params), exactly the implicit-function derivative (the
  // iteration itself runs in double, which is what makes Jets cheap here).
  // Only f = distort(x, y) - (xd, yd) needs T: J's own derivatives would
  // enter multiplied by f, which vanishes at the solution (1e-12), so J is
  // taken in double.
  const T x(x0), y(y0);
  T fx, fy;
  DistortNormalized(dist, x, y, &fx, &fy);
  fx -= xd;
  fy -= yd;
  double f_value[2], J[4];
  internal::DistortionResidual(dist_values, x0, y0, internal::ScalarPart(xd),
                               internal::ScalarPart(yd), f_value, J);
  const double jdet = J[0] * J[3] - J[1] * J[2];
  *xn = x - (fx * J[3] - J[1] * fy) / jdet;
  *yn = y - (J[0] * fy - fx * J[2]) / jdet;
  return true;
}

}  // namespace rtscalib

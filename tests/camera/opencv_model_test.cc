#include "libcalib/camera/opencv_model.h"

#include <ceres/ceres.h>
#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <random>
#include <string>
#include <vector>

namespace rtscalib {
namespace {

// Tolerances, with where they come from (fx ~ 1000 px, image 1280 x 960).
// Projection: ours and cv::projectPoints evaluate the same closed form in a
// different order; double rounding of pixel values ~1e3 gives ~1e-13 px.
constexpr double kProjectTolPx = 1e-9;
// Undistortion: OpenCV's fixed-point iteration run to 1e-14 px against our
// Newton iteration; both end at rounding noise of normalised values ~1.
constexpr double kUndistortTolNormalised = 1e-12;  // ~1e-9 px at fx = 1000
// Round trip project(unproject(p)): Newton converged to rounding.
constexpr double kRoundTripTolPx = 1e-9;
// Central differences with step 1e-6 (relative): truncation ~h^2 f''' and
// rounding ~eps f / h give ~1e-9 relative error for these smooth maps.
constexpr double kJacobianRelTol = 1e-6;

constexpr int kWidth = 1280;
constexpr int kHeight = 960;

// Distortion groups as bit flags (SPEC 4 effect names).
enum Group {
  kRadial = 1,      // k1 k2 k3
  kTangential = 2,  // p1 p2
  kRational = 4,    // k4 k5 k6
  kThinPrism = 8,   // s1..s4
  kTilt = 16,       // taux tauy
  kAllGroups = 31,
};

std::string GroupsName(int mask) {
  if (mask == 0) return "none";
  std::string s;
  const char* names[] = {"radial", "tangential", "rational", "thin_prism", "tilt"};
  for (int i = 0; i < 5; ++i) {
    if (mask & (1 << i)) s += (s.empty() ? "" : "+") + std::string(names[i]);
  }
  return s;
}

struct TestCamera {
  std::array<double, kNumIntrinsics> intrinsics{};
  std::array<double, kNumDistortion> dist{};
};

// Coefficients of realistic size for a 1280 x 960 camera with a horizontal
// field of view of 56..71 degrees (image corners at r <= 0.9). The ranges keep
// the image and the test points (r <= 0.96) inside the trusted region; the
// tests assert that premise with MaxTrustedRadius.
TestCamera RandomCamera(int mask, std::mt19937* rng) {
  auto u = [rng](double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(*rng);
  };
  TestCamera c;
  const double f = u(900, 1200);
  c.intrinsics = {f, f * u(0.99, 1.01), u(620, 660), u(460, 500)};
  if (mask & kRadial) {
    c.dist[kK1] = u(-0.2, 0.1);
    c.dist[kK2] = u(-0.02, 0.1);
    c.dist[kK3] = u(-0.02, 0.02);
  }
  if (mask & kTangential) {
    c.dist[kP1] = u(-2e-3, 2e-3);
    c.dist[kP2] = u(-2e-3, 2e-3);
  }
  if (mask & kRational) {
    c.dist[kK4] = u(-0.1, 0.2);
    c.dist[kK5] = u(-0.02, 0.02);
    c.dist[kK6] = u(-0.01, 0.01);
  }
  if (mask & kThinPrism) {
    for (int i = kS1; i <= kS4; ++i) c.dist[i] = u(-2e-3, 2e-3);
  }
  if (mask & kTilt) {
    c.dist[kTauX] = u(-0.02, 0.02);
    c.dist[kTauY] = u(-0.02, 0.02);
  }
  return c;
}

cv::Mat CvCameraMatrix(const TestCamera& c) {
  return (cv::Mat_<double>(3, 3) << c.intrinsics[0], 0, c.intrinsics[2], 0, c.intrinsics[1],
          c.intrinsics[3], 0, 0, 1);
}

cv::Mat CvDistortion(const TestCamera& c) {
  cv::Mat d(1, kNumDistortion, CV_64F);
  for (int i = 0; i < kNumDistortion; ++i) d.at<double>(i) = c.dist[i];
  return d;
}

// Camera points whose images cover the image and a margin beyond it: random
// normalised coordinates plus the (undistorted) corner directions, at depths
// from 0.3 m to 30 m.
std::vector<cv::Point3d> TestPoints(std::mt19937* rng) {
  std::uniform_real_distribution<double> ux(-0.75, 0.75), uy(-0.6, 0.6), depth(0.3, 30.0);
  std::vector<cv::Point3d> pts;
  for (int i = 0; i < 200; ++i) {
    const double z = depth(*rng);
    pts.emplace_back(ux(*rng) * z, uy(*rng) * z, z);
  }
  for (double sx : {-1.0, 1.0}) {
    for (double sy : {-1.0, 1.0}) {
      for (double scale : {0.95, 1.0, 1.05}) {
        const double z = depth(*rng);
        pts.emplace_back(sx * 0.68 * scale * z, sy * 0.52 * scale * z, z);
      }
    }
  }
  return pts;
}

// Pixels over the whole image: a grid including the border pixels and the
// four corner pixels, plus random pixels.
std::vector<cv::Point2d> TestPixels(std::mt19937* rng) {
  std::vector<cv::Point2d> px;
  for (int i = 0; i <= 16; ++i) {
    for (int j = 0; j <= 12; ++j)
      px.emplace_back((kWidth - 1) * i / 16.0, (kHeight - 1) * j / 12.0);
  }
  std::uniform_real_distribution<double> uu(0, kWidth - 1), uv(0, kHeight - 1);
  for (int i = 0; i < 100; ++i) px.emplace_back(uu(*rng), uv(*rng));
  return px;
}

TEST(ProjectToPixel, MatchesCvProjectPointsForEveryDistortionGroupCombination) {
  std::mt19937 rng(42);
  double worst = 0;
  for (int mask = 0; mask <= kAllGroups; ++mask) {
    for (int trial = 0; trial < 3; ++trial) {
      const TestCamera cam = RandomCamera(mask, &rng);
      const std::vector<cv::Point3d> pts = TestPoints(&rng);
      std::vector<cv::Point2d> expected;
      cv::projectPoints(pts, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), CvCameraMatrix(cam),
                        CvDistortion(cam), expected);
      for (size_t i = 0; i < pts.size(); ++i) {
        const double X[3] = {pts[i].x, pts[i].y, pts[i].z};
        double uv[2];
        ASSERT_TRUE(ProjectToPixel(cam.intrinsics.data(), cam.dist.data(), X, uv));
        const double err = std::hypot(uv[0] - expected[i].x, uv[1] - expected[i].y);
        worst = std::max(worst, err);
        EXPECT_LT(err, kProjectTolPx) << GroupsName(mask) << " point " << i;
      }
    }
  }
  std::printf("[ figures  ] ProjectToPixel vs cv::projectPoints: max |d pixel| = %.3g px\n", worst);
}

TEST(ProjectToPixel, RejectsPointsOnOrBehindTheImagePlane) {
  const TestCamera cam;
  const double intr[4] = {1000, 1000, 640, 480};
  double uv[2];
  for (double z : {0.0, -1.0, -1e-12}) {
    const double X[3] = {0.1, 0.2, z};
    EXPECT_FALSE(ProjectToPixel(intr, cam.dist.data(), X, uv)) << z;
  }
}

TEST(UndistortPixel, MatchesCvUndistortPointsForEveryDistortionGroupCombination) {
  std::mt19937 rng(43);
  double worst = 0, worst_round_trip = 0;
  // OpenCV's fixed-point iteration, run until it is at rounding noise.
  const cv::TermCriteria criteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 1000, 1e-14);
  for (int mask = 0; mask <= kAllGroups; ++mask) {
    for (int trial = 0; trial < 3; ++trial) {
      const TestCamera cam = RandomCamera(mask, &rng);
      const std::vector<cv::Point2d> px = TestPixels(&rng);
      std::vector<cv::Point2d> expected;
      cv::undistortPoints(px, expected, CvCameraMatrix(cam), CvDistortion(cam), cv::noArray(),
                          cv::noArray(), criteria);
      const double r_max = MaxTrustedRadius(cam.dist.data());
      ASSERT_GT(r_max, 0.96) << GroupsName(mask);
      for (size_t i = 0; i < px.size(); ++i) {
        const double uv[2] = {px[i].x, px[i].y};
        double x, y;
        ASSERT_TRUE(UndistortPixel(cam.intrinsics.data(), cam.dist.data(), uv, &x, &y))
            << GroupsName(mask) << " pixel " << px[i];
        EXPECT_LT(std::hypot(x, y), r_max);
        const double err = std::hypot(x - expected[i].x, y - expected[i].y);
        worst = std::max(worst, err);
        EXPECT_LT(err, kUndistortTolNormalised) << GroupsName(mask) << " pixel " << px[i];

        const double X[3] = {x, y, 1.0};
        double back[2];
        ASSERT_TRUE(ProjectToPixel(cam.intrinsics.data(), cam.dist.data(), X, back));
        const double rt = std::hypot(back[0] - uv[0], back[1] - uv[1]);
        worst_round_trip = std::max(worst_round_trip, rt);
        EXPECT_LT(rt, kRoundTripTolPx) << GroupsName(mask) << " pixel " << px[i];
      }
    }
  }
  std::printf(
      "[ figures  ] UndistortPixel vs cv::undistortPoints: max |d xy| = %.3g (normalised)\n",
      worst);
  std::printf("[ figures  ] project(unproject(p)) - p: max %.3g px\n", worst_round_trip);
}

// unproject(project(X)) is X's direction (PixelToRay returns a unit vector).
TEST(PixelToRay, InvertsProjection) {
  std::mt19937 rng(44);
  double worst = 0;
  for (int mask = 0; mask <= kAllGroups; ++mask) {
    const TestCamera cam = RandomCamera(mask, &rng);
    ASSERT_GT(MaxTrustedRadius(cam.dist.data()), 0.96) << GroupsName(mask);
    for (const cv::Point3d& p : TestPoints(&rng)) {
      const double X[3] = {p.x, p.y, p.z};
      double uv[2], ray[3];
      ASSERT_TRUE(ProjectToPixel(cam.intrinsics.data(), cam.dist.data(), X, uv));
      ASSERT_TRUE(PixelToRay(cam.intrinsics.data(), cam.dist.data(), uv, ray)) << GroupsName(mask);
      const double n = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
      const double err =
          std::hypot(std::hypot(ray[0] - p.x / n, ray[1] - p.y / n), ray[2] - p.z / n);
      worst = std::max(worst, err);
      EXPECT_LT(err, 1e-12) << GroupsName(mask);
      EXPECT_NEAR(std::hypot(std::hypot(ray[0], ray[1]), ray[2]), 1.0, 1e-15);
    }
  }
  std::printf("[ figures  ] PixelToRay(ProjectToPixel(X)) vs X/|X|: max %.3g rad\n", worst);
}

// ---------------------------------------------------------------------------
// Trusted region of the Newton undistortion.

double RadialMap(const double* d, double r) {  // g(r) = r * radial(r^2)
  const double s = r * r;
  return r * (1 + d[kK1] * s + d[kK2] * s * s + d[kK3] * s * s * s) /
         (1 + d[kK4] * s + d[kK5] * s * s + d[kK6] * s * s * s);
}
double RadialDenominator(const double* d, double r) {
  const double s = r * r;
  return 1 + d[kK4] * s + d[kK5] * s * s + d[kK6] * s * s * s;
}

TEST(MaxTrustedRadius, UnboundedWithoutDistortion) {
  const std::array<double, kNumDistortion> d{};
  EXPECT_EQ(MaxTrustedRadius(d.data()), std::numeric_limits<double>::infinity());
  EXPECT_EQ(MaxTrustedDistortedRadius(d.data()), std::numeric_limits<double>::infinity());
}

// Closed forms: g = r (1 + k1 r^2) turns at r = 1/sqrt(-3 k1); g = r / (1 + k4 r^2)
// turns at r = 1/sqrt(k4) (k4 > 0) and has a pole at 1/sqrt(-k4) (k4 < 0).
TEST(MaxTrustedRadius, ClosedForms) {
  std::array<double, kNumDistortion> d{};
  d[kK1] = -0.3;
  EXPECT_NEAR(MaxTrustedRadius(d.data()), 1.0 / std::sqrt(0.9), 1e-14);
  EXPECT_NEAR(MaxTrustedDistortedRadius(d.data()), RadialMap(d.data(), 1.0 / std::sqrt(0.9)),
              1e-14);
  d[kK1] = 0.2;  // pincushion: monotone everywhere
  EXPECT_EQ(MaxTrustedRadius(d.data()), std::numeric_limits<double>::infinity());
  d = {};
  d[kK4] = 0.5;
  EXPECT_NEAR(MaxTrustedRadius(d.data()), std::sqrt(2.0), 1e-14);
  EXPECT_NEAR(MaxTrustedDistortedRadius(d.data()), std::sqrt(2.0) / 2.0, 1e-14);
  d[kK4] = -0.5;
  EXPECT_NEAR(MaxTrustedRadius(d.data()), std::sqrt(2.0), 1e-14);
  EXPECT_EQ(MaxTrustedDistortedRadius(d.data()), std::numeric_limits<double>::infinity());
}

// For random radial + rational coefficients (also strong ones), g is
// increasing with a positive denominator up to the limit and not beyond it.
TEST(MaxTrustedRadius, IsTheFirstTurnOrPoleOfTheRadialMap) {
  std::mt19937 rng(45);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int finite = 0;
  for (int trial = 0; trial < 500; ++trial) {
    std::array<double, kNumDistortion> d{};
    for (int i : {kK1, kK2, kK3, kK4, kK5, kK6}) d[i] = u(rng) * (trial % 2 ? 1.0 : 0.2);
    const double r_max = MaxTrustedRadius(d.data());
    const double r_scan = std::isfinite(r_max) ? r_max : 20.0;
    const double h = 1e-7;
    for (int i = 1; i <= 1000; ++i) {
      const double r = r_scan * i / 1000.0 * (1 - 1e-6);
      ASSERT_GT(RadialDenominator(d.data(), r), 0.0) << trial;
      ASSERT_GT(RadialMap(d.data(), r + h) - RadialMap(d.data(), r - h), 0.0)
          << trial << " r=" << r;
    }
    if (std::isfinite(r_max)) {
      ++finite;
      const double r = r_max * (1 + 1e-6);
      const bool turned = RadialMap(d.data(), r + h) < RadialMap(d.data(), r - h) + 1e-13;
      const bool pole = RadialDenominator(d.data(), r) <= 1e-5;
      EXPECT_TRUE(turned || pole) << trial;
    }
  }
  EXPECT_GT(finite, 100);  // the strong half of the trials mostly folds
}

// k1 = -0.5, k2 = 0.1: g'(r) = 1 - 1.5 r^2 + 0.5 r^4 vanishes at r = 1 and
// r = sqrt(2). g(1) = 0.6 is the edge of the trusted region; pixels beyond it
// have a preimage only on the third branch (r > sqrt 2), which is rejected.
TEST(UndistortPixel, RejectsPixelsOutsideTheTrustedRegion) {
  std::array<double, kNumDistortion> d{};
  d[kK1] = -0.5;
  d[kK2] = 0.1;
  const double intr[4] = {1000, 1000, 640, 480};
  EXPECT_NEAR(MaxTrustedRadius(d.data()), 1.0, 1e-14);
  EXPECT_NEAR(MaxTrustedDistortedRadius(d.data()), 0.6, 1e-14);
  double x, y;
  for (double rho : {0.1, 0.3, 0.5, 0.59, 0.5999}) {
    const double px[2] = {640 + 1000 * rho * 0.6, 480 + 1000 * rho * 0.8};
    ASSERT_TRUE(UndistortPixel(intr, d.data(), px, &x, &y, 100)) << rho;
    EXPECT_LT(std::hypot(x, y), 1.0);
    EXPECT_NEAR(RadialMap(d.data(), std::hypot(x, y)), rho, 1e-12);
  }
  for (double rho : {0.6001, 0.7, 1.0, 3.0}) {
    const double px[2] = {640 + 1000 * rho * 0.6, 480 + 1000 * rho * 0.8};
    EXPECT_FALSE(UndistortPixel(intr, d.data(), px, &x, &y, 100)) << rho;
  }
  // A point on the folded branch (r = 1.2) is seen at a pixel whose trusted
  // preimage is a different, nearer direction (r < 1): projection is not
  // injective beyond the limit, so calibration data must stay inside it.
  const double X[3] = {1.2 * 0.6, 1.2 * 0.8, 1.0};
  double uv[2];
  ASSERT_TRUE(ProjectToPixel(intr, d.data(), X, uv));
  ASSERT_TRUE(UndistortPixel(intr, d.data(), uv, &x, &y));
  EXPECT_LT(std::hypot(x, y), 1.0);
  EXPECT_NEAR(x / y, 0.75, 1e-12);
}

// OpenCV's fixed-point iteration and ours agree right up to the edge for a
// strongly distorted lens where the image corners are near the limit.
TEST(UndistortPixel, AgreesWithOpenCvNearTheEdgeOfTheTrustedRegion) {
  TestCamera cam;
  cam.intrinsics = {700, 700, 640, 480};
  cam.dist[kK1] = -0.35;  // g'(r) = 1 - 1.05 r^2 + 0.1 r^4: turns at r = 1.0303
  cam.dist[kK2] = 0.02;
  const double r_max = MaxTrustedRadius(cam.dist.data());
  const double rho_max = MaxTrustedDistortedRadius(cam.dist.data());
  ASSERT_TRUE(std::isfinite(r_max));
  std::vector<cv::Point2d> px;
  for (double frac : {0.5, 0.8, 0.9, 0.95, 0.98, 0.999}) {
    for (double ang : {0.1, 0.9, 2.0, 3.5, 5.0}) {
      const double rho = frac * rho_max;
      px.emplace_back(640 + 700 * rho * std::cos(ang), 480 + 700 * rho * std::sin(ang));
    }
  }
  std::vector<cv::Point2d> expected;
  cv::undistortPoints(
      px, expected, CvCameraMatrix(cam), CvDistortion(cam), cv::noArray(), cv::noArray(),
      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100000, 1e-14));
  double worst = 0;
  for (size_t i = 0; i < px.size(); ++i) {
    const double uv[2] = {px[i].x, px[i].y};
    double x, y;
    ASSERT_TRUE(UndistortPixel(cam.intrinsics.data(), cam.dist.data(), uv, &x, &y)) << px[i];
    EXPECT_LT(std::hypot(x, y), r_max);
    EXPECT_NEAR(x, expected[i].x, 1e-10) << px[i];
    EXPECT_NEAR(y, expected[i].y, 1e-10) << px[i];
    worst = std::max(worst, std::hypot(x - expected[i].x, y - expected[i].y));
  }
  std::printf(
      "[ figures  ] k1=-0.35 k2=0.02: r_max = %.6f, rho_max = %.6f; up to 0.999 rho_max "
      "|ours - OpenCV| <= %.3g (normalised)\n",
      r_max, rho_max, worst);
}

// ---------------------------------------------------------------------------
// Derivatives: ceres::Jet autodiff against central differences.

template <int N>
using JetN = ceres::Jet<double, N>;

// Central-difference Jacobian of f: R^n -> R^m at x (step relative to |x_j|).
template <typename F>
std::vector<std::vector<double>> NumericJacobian(const F& f, std::vector<double> x, int m) {
  std::vector<std::vector<double>> J(m, std::vector<double>(x.size()));
  for (size_t j = 0; j < x.size(); ++j) {
    const double h = 1e-6 * std::max(1.0, std::abs(x[j]));
    const double x0 = x[j];
    std::vector<double> fp(m), fm(m);
    x[j] = x0 + h;
    f(x, &fp);
    x[j] = x0 - h;
    f(x, &fm);
    x[j] = x0;
    for (int i = 0; i < m; ++i) J[i][j] = (fp[i] - fm[i]) / (2 * h);
  }
  return J;
}

TEST(ProjectToPixel, JetDerivativesMatchCentralDifferences) {
  constexpr int kN = 3 + kNumIntrinsics + kNumDistortion;
  std::mt19937 rng(46);
  for (int mask = 0; mask <= kAllGroups; ++mask) {
    const TestCamera cam = RandomCamera(mask, &rng);
    const std::vector<cv::Point3d> pts = TestPoints(&rng);
    for (size_t k = 0; k < pts.size(); k += 25) {
      std::vector<double> x = {pts[k].x, pts[k].y, pts[k].z};
      x.insert(x.end(), cam.intrinsics.begin(), cam.intrinsics.end());
      x.insert(x.end(), cam.dist.begin(), cam.dist.end());
      JetN<kN> jx[kN];
      for (int j = 0; j < kN; ++j) jx[j] = JetN<kN>(x[j], j);
      JetN<kN> uv[2];
      ASSERT_TRUE(ProjectToPixel(jx + 3, jx + 7, jx, uv));
      const auto f = [](const std::vector<double>& p, std::vector<double>* out) {
        ProjectToPixel(p.data() + 3, p.data() + 7, p.data(), out->data());
      };
      const auto J = NumericJacobian(f, x, 2);
      for (int i = 0; i < 2; ++i) {
        for (int j = 0; j < kN; ++j) {
          EXPECT_NEAR(uv[i].v[j], J[i][j], kJacobianRelTol * std::max(1.0, std::abs(J[i][j])))
              << GroupsName(mask) << " d uv[" << i << "] / d param " << j;
        }
      }
    }
  }
}

// The written-out Jacobian against autodiff of ProjectToPixel: the same
// derivatives in a different order of operations, so they agree to rounding
// of entries up to ~1e3 px per unit (1e-9 relative to the largest entry of
// the row, far below what central differences resolve); the value is the
// formula's own, bit for bit.
constexpr double kWrittenOutRelTol = 1e-9;

TEST(ProjectWithJacobian, EqualsAutodiffForEveryDistortionGroupCombination) {
  constexpr int kN = kProjectionVars;
  std::mt19937 rng(47);
  for (int mask = 0; mask <= kAllGroups; ++mask) {
    const TestCamera cam = RandomCamera(mask, &rng);
    // The tilt matrix and its derivatives, as a cost function forms them once.
    JetN<2> tau[2] = {JetN<2>(cam.dist[kTauX], 0), JetN<2>(cam.dist[kTauY], 1)};
    JetN<2> tilt[9];
    TiltMatrix(tau[0], tau[1], tilt);
    double m[9], dm_dtau[2][9];
    for (int i = 0; i < 9; ++i) {
      m[i] = tilt[i].a;
      dm_dtau[0][i] = tilt[i].v[0];
      dm_dtau[1][i] = tilt[i].v[1];
    }
    const std::vector<cv::Point3d> pts = TestPoints(&rng);
    for (size_t k = 0; k < pts.size(); k += 10) {
      const double point[3] = {pts[k].x, pts[k].y, pts[k].z};
      double pixel[2], J[2 * kN];
      ASSERT_TRUE(ProjectWithJacobian(cam.intrinsics.data(), cam.dist.data(), m, dm_dtau, point,
                                      pixel, J));
      double expected[2];
      ASSERT_TRUE(ProjectToPixel(cam.intrinsics.data(), cam.dist.data(), point, expected));
      EXPECT_EQ(pixel[0], expected[0]) << GroupsName(mask);
      EXPECT_EQ(pixel[1], expected[1]) << GroupsName(mask);
      JetN<kN> jx[kN];
      for (int j = 0; j < 3; ++j) jx[j] = JetN<kN>(point[j], j);
      for (int j = 0; j < kNumIntrinsics; ++j) jx[3 + j] = JetN<kN>(cam.intrinsics[j], 3 + j);
      for (int j = 0; j < kNumDistortion; ++j) jx[7 + j] = JetN<kN>(cam.dist[j], 7 + j);
      JetN<kN> uv[2];
      ASSERT_TRUE(ProjectToPixel(jx + 3, jx + 7, jx, uv));
      for (int i = 0; i < 2; ++i) {
        const double scale = std::max(1.0, uv[i].v.cwiseAbs().maxCoeff());
        for (int j = 0; j < kN; ++j) {
          EXPECT_NEAR(J[i * kN + j], uv[i].v[j], kWrittenOutRelTol * scale)
              << GroupsName(mask) << " d uv[" << i << "] / d variable " << j;
        }
      }
    }
  }
  const double behind[3] = {0.1, 0.2, -1.0};
  double pixel[2], J[2 * kN];
  const TestCamera cam = RandomCamera(kAllGroups, &rng);
  double m[9];
  TiltMatrix(cam.dist[kTauX], cam.dist[kTauY], m);
  const double dm_dtau[2][9] = {};
  EXPECT_FALSE(
      ProjectWithJacobian(cam.intrinsics.data(), cam.dist.data(), m, dm_dtau, behind, pixel, J));
}

TEST(PixelToRay, JetDerivativesMatchCentralDifferences) {
  constexpr int kN = 2 + kNumIntrinsics + kNumDistortion;
  std::mt19937 rng(47);
  for (int mask = 0; mask <= kAllGroups; ++mask) {
    const TestCamera cam = RandomCamera(mask, &rng);
    const std::vector<cv::Point2d> px = TestPixels(&rng);
    for (size_t k = 0; k < px.size(); k += 23) {
      std::vector<double> x = {px[k].x, px[k].y};
      x.insert(x.end(), cam.intrinsics.begin(), cam.intrinsics.end());
      x.insert(x.end(), cam.dist.begin(), cam.dist.end());
      JetN<kN> jx[kN];
      for (int j = 0; j < kN; ++j) jx[j] = JetN<kN>(x[j], j);
      JetN<kN> ray[3];
      ASSERT_TRUE(PixelToRay(jx + 2, jx + 6, jx, ray)) << GroupsName(mask) << " " << px[k];
      const auto f = [](const std::vector<double>& p, std::vector<double>* out) {
        PixelToRay(p.data() + 2, p.data() + 6, p.data(), out->data());
      };
      const auto J = NumericJacobian(f, x, 3);
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < kN; ++j) {
          EXPECT_NEAR(ray[i].v[j], J[i][j], kJacobianRelTol * std::max(1.0, std::abs(J[i][j])))
              << GroupsName(mask) << " d ray[" << i << "] / d param " << j << " at " << px[k];
        }
      }
    }
  }
}

// Near the edge of the trusted region g' is small and Newton's path is long;
// the derivatives must still be the implicit-function ones (the final full
// Newton step in UndistortPixel guarantees it).
TEST(PixelToRay, JetDerivativesNearTheEdgeOfTheTrustedRegion) {
  constexpr int kN = 2 + kNumIntrinsics + kNumDistortion;
  TestCamera cam;
  cam.intrinsics = {700, 700, 640, 480};
  cam.dist[kK1] = -0.35;
  cam.dist[kK2] = 0.02;
  const double rho_max = MaxTrustedDistortedRadius(cam.dist.data());
  for (double frac : {0.9, 0.97}) {
    std::vector<double> x = {640 + 700 * frac * rho_max * 0.6, 480 + 700 * frac * rho_max * 0.8};
    x.insert(x.end(), cam.intrinsics.begin(), cam.intrinsics.end());
    x.insert(x.end(), cam.dist.begin(), cam.dist.end());
    JetN<kN> jx[kN];
    for (int j = 0; j < kN; ++j) jx[j] = JetN<kN>(x[j], j);
    JetN<kN> ray[3];
    ASSERT_TRUE(PixelToRay(jx + 2, jx + 6, jx, ray)) << frac;
    const auto f = [](const std::vector<double>& p, std::vector<double>* out) {
      PixelToRay(p.data() + 2, p.data() + 6, p.data(), out->data());
    };
    const auto J = NumericJacobian(f, x, 3);
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < kN; ++j) {
        // Central differences lose accuracy as g' -> 0 (curvature grows).
        EXPECT_NEAR(ray[i].v[j], J[i][j], 1e-5 * std::max(1.0, std::abs(J[i][j])))
            << frac << " d ray[" << i << "] / d param " << j;
      }
    }
  }
}

// ---------------------------------------------------------------------------
// ceres::GradientChecker on small cost functors over a camera point and the
// intrinsics and distortion blocks.

struct ReprojectionError {
  double u, v;
  template <typename T>
  bool operator()(const T* point_in_cam, const T* intrinsics, const T* dist, T* residual) const {
    T uv[2];
    if (!ProjectToPixel(intrinsics, dist, point_in_cam, uv)) return false;
    residual[0] = uv[0] - T(u);
    residual[1] = uv[1] - T(v);
    return true;
  }
};

// The point at ray length d through a pixel (SPEC 2's F_CAM in the camera frame).
struct RayPointError {
  double u, v, d;
  Eigen::Vector3d observed;
  template <typename T>
  bool operator()(const T* intrinsics, const T* dist, T* residual) const {
    const T px[2] = {T(u), T(v)};
    T ray[3];
    if (!PixelToRay(intrinsics, dist, px, ray)) return false;
    for (int i = 0; i < 3; ++i) residual[i] = T(d) * ray[i] - T(observed[i]);
    return true;
  }
};

// Autodiff against Ridders' differences, entry by entry (relative 1e-5:
// entries such as d u / d k6 near the centre are ~1e-7 of their block and
// carry Ridders' ~1e-13 absolute error) and block by block (max abs error
// below 1e-9 of the block's largest entry).
void ExpectGradientsAgree(const ceres::CostFunction& cost, const double* const* blocks,
                          const std::string& what) {
  // GradientChecker uses Ridders' method, whose first step is
  // 2^(max_extrapolations / 2) = 32 times the initial relative step: with the
  // default 1e-2 that is 32% of a depth, far outside the region where a
  // central difference of 1/Z is accurate, and big enough to push a pixel
  // out of the trusted region. 1e-4 starts at 0.3%.
  ceres::NumericDiffOptions numeric_options;
  numeric_options.ridders_relative_initial_step_size = 1e-4;
  const std::vector<const ceres::Manifold*>* no_manifolds = nullptr;
  ceres::GradientChecker checker(&cost, no_manifolds, numeric_options);
  ceres::GradientChecker::ProbeResults results;
  EXPECT_TRUE(checker.Probe(blocks, 1e-5, &results)) << what << results.error_log;
  for (size_t b = 0; b < results.jacobians.size(); ++b) {
    const double scale = results.jacobians[b].cwiseAbs().maxCoeff();
    const double err = (results.jacobians[b] - results.numeric_jacobians[b]).cwiseAbs().maxCoeff();
    EXPECT_LE(err, 1e-9 * scale) << what << " block " << b;
  }
}

TEST(CostFunctors, PassGradientChecker) {
  std::mt19937 rng(48);
  for (int mask :
       {0, int(kRadial), kRadial | kTangential, kRational | kThinPrism, int(kAllGroups)}) {
    const TestCamera cam = RandomCamera(mask, &rng);
    std::array<double, 4> intr = cam.intrinsics;
    std::array<double, 14> dist = cam.dist;
    const std::vector<cv::Point3d> pts = TestPoints(&rng);
    for (size_t k = 0; k < pts.size(); k += 20) {
      double X[3] = {pts[k].x, pts[k].y, pts[k].z};
      double uv[2];
      ASSERT_TRUE(ProjectToPixel(intr.data(), dist.data(), X, uv));
      ceres::AutoDiffCostFunction<ReprojectionError, 2, 3, 4, 14> reproj(
          new ReprojectionError{uv[0] + 0.3, uv[1] - 0.2});
      const double* blocks[] = {X, intr.data(), dist.data()};
      ExpectGradientsAgree(reproj, blocks, "reprojection " + GroupsName(mask));

      ceres::AutoDiffCostFunction<RayPointError, 3, 4, 14> ray_cost(
          new RayPointError{uv[0], uv[1], 2.5, Eigen::Vector3d(0.1, -0.2, 2.4)});
      const double* ray_blocks[] = {intr.data(), dist.data()};
      ExpectGradientsAgree(ray_cost, ray_blocks, "ray point " + GroupsName(mask));
    }
  }
}

}  // namespace
}  // namespace rtscalib

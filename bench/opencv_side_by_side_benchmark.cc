// Side by side: libcalib/camera/opencv_model.h against OpenCV 4 on the same
// camera and points (time per point, and how far each result is from the
// converged reference). Camera: 1280 x 960, fx = 1000, every distortion group
// on with realistic coefficients; points over the whole image.
#include <benchmark/benchmark.h>
#include <ceres/jet.h>

#include <array>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <random>
#include <vector>

#include "libcalib/camera/opencv_model.h"

namespace rtscalib {
namespace {

constexpr int kPoints = 1000;

struct Setup {
  std::array<double, kNumIntrinsics> intrinsics{1000, 1003, 645, 478};
  std::array<double, kNumDistortion> dist{-0.12, 0.05, 8e-4,  -5e-4, -0.01, 0.05, -0.01,
                                          0.002, 1e-3, -5e-4, -8e-4, 3e-4,  0.01, -0.015};
  cv::Mat K, D;
  std::vector<cv::Point3d> points;        // camera frame
  std::vector<cv::Point2d> pixels;        // their images
  std::vector<cv::Point2d> reference_xy;  // normalised (x', y') of the points

  Setup() {
    K = (cv::Mat_<double>(3, 3) << intrinsics[0], 0, intrinsics[2], 0, intrinsics[1], intrinsics[3],
         0, 0, 1);
    D = cv::Mat(1, kNumDistortion, CV_64F, dist.data()).clone();
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> ux(-0.64, 0.64), uy(-0.48, 0.48), uz(1, 20);
    for (int i = 0; i < kPoints; ++i) {
      const double z = uz(rng), x = ux(rng), y = uy(rng);
      points.emplace_back(x * z, y * z, z);
      reference_xy.emplace_back(x, y);
    }
    cv::projectPoints(points, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, D, pixels);
  }
};

const Setup& TheSetup() {
  static const Setup setup;
  return setup;
}

double MaxError(const std::vector<cv::Point2d>& xy) {
  const Setup& s = TheSetup();
  double worst = 0;
  for (size_t i = 0; i < xy.size(); ++i) {
    worst =
        std::max(worst, std::hypot(xy[i].x - s.reference_xy[i].x, xy[i].y - s.reference_xy[i].y));
  }
  return worst;
}

void BM_Ours_ProjectToPixel(benchmark::State& state) {
  const Setup& s = TheSetup();
  std::vector<double> uv(2 * kPoints);
  for (auto _ : state) {
    for (int i = 0; i < kPoints; ++i) {
      const double X[3] = {s.points[i].x, s.points[i].y, s.points[i].z};
      ProjectToPixel(s.intrinsics.data(), s.dist.data(), X, &uv[2 * i]);
    }
    benchmark::DoNotOptimize(uv.data());
  }
  state.SetItemsProcessed(state.iterations() * kPoints);
}
BENCHMARK(BM_Ours_ProjectToPixel);

void BM_OpenCv_projectPoints(benchmark::State& state) {
  const Setup& s = TheSetup();
  std::vector<cv::Point2d> out;
  for (auto _ : state) {
    cv::projectPoints(s.points, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), s.K, s.D, out);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * kPoints);
}
BENCHMARK(BM_OpenCv_projectPoints);

void BM_Ours_UndistortPixel(benchmark::State& state) {
  const Setup& s = TheSetup();
  std::vector<cv::Point2d> xy(kPoints);
  for (auto _ : state) {
    for (int i = 0; i < kPoints; ++i) {
      const double px[2] = {s.pixels[i].x, s.pixels[i].y};
      UndistortPixel(s.intrinsics.data(), s.dist.data(), px, &xy[i].x, &xy[i].y);
    }
    benchmark::DoNotOptimize(xy.data());
  }
  state.SetItemsProcessed(state.iterations() * kPoints);
  state.counters["max_err"] = MaxError(xy);  // normalised units
}
BENCHMARK(BM_Ours_UndistortPixel);

// OpenCV's default: 5 fixed-point iterations.
void BM_OpenCv_undistortPoints_default(benchmark::State& state) {
  const Setup& s = TheSetup();
  std::vector<cv::Point2d> xy;
  for (auto _ : state) {
    cv::undistortPoints(s.pixels, xy, s.K, s.D);
    benchmark::DoNotOptimize(xy.data());
  }
  state.SetItemsProcessed(state.iterations() * kPoints);
  state.counters["max_err"] = MaxError(xy);
}
BENCHMARK(BM_OpenCv_undistortPoints_default);

// OpenCV run to convergence (`state.range(0)` iterations, eps 1e-14 px).
void BM_OpenCv_undistortPoints_iter(benchmark::State& state) {
  const Setup& s = TheSetup();
  const cv::TermCriteria criteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS,
                                  static_cast<int>(state.range(0)), 1e-14);
  std::vector<cv::Point2d> xy;
  for (auto _ : state) {
    cv::undistortPoints(s.pixels, xy, s.K, s.D, cv::noArray(), cv::noArray(), criteria);
    benchmark::DoNotOptimize(xy.data());
  }
  state.SetItemsProcessed(state.iterations() * kPoints);
  state.counters["max_err"] = MaxError(xy);
}
BENCHMARK(BM_OpenCv_undistortPoints_iter)->Arg(10)->Arg(20)->Arg(100);

// Back-projection with derivatives w.r.t. pixel, intrinsics and distortion
// (what a Ceres cost on F_CAM evaluates).
void BM_Ours_PixelToRay_Jet20(benchmark::State& state) {
  const Setup& s = TheSetup();
  using J = ceres::Jet<double, 20>;
  J intr[kNumIntrinsics], dist[kNumDistortion];
  for (int i = 0; i < kNumIntrinsics; ++i) intr[i] = J(s.intrinsics[i], 2 + i);
  for (int i = 0; i < kNumDistortion; ++i) dist[i] = J(s.dist[i], 6 + i);
  J ray[3];
  for (auto _ : state) {
    for (int i = 0; i < kPoints; ++i) {
      const J px[2] = {J(s.pixels[i].x, 0), J(s.pixels[i].y, 1)};
      PixelToRay(intr, dist, px, ray);
      benchmark::DoNotOptimize(ray);
    }
  }
  state.SetItemsProcessed(state.iterations() * kPoints);
}
BENCHMARK(BM_Ours_PixelToRay_Jet20);

// Uncached root isolation (UndistortPixel caches it per thread).
void BM_Ours_MaxTrustedRadius(benchmark::State& state) {
  std::array<double, kNumDistortion> d = TheSetup().dist;
  for (auto _ : state) {
    d[kK1] += 1e-12;  // new coefficients every call
    benchmark::DoNotOptimize(MaxTrustedRadius(d.data()));
  }
}
BENCHMARK(BM_Ours_MaxTrustedRadius);

}  // namespace
}  // namespace rtscalib

BENCHMARK_MAIN();

// Side by side with OpenCV: on the same simulated AprilTag corners,
// per zoom level, cv::calibrateCamera against rtscalib's joint model
// (InitFromPixels + Refine of all zooms and both faces at once): intrinsics
// error against the truth, and time. The joint model must be at least as
// accurate: it knows that every shot was taken by one instrument whose
// pointing is read from its angle encoders, where OpenCV fits a free pose per
// view.
//
// Data: a dh truth near Klug's PLT 300 with 3 cameras (640 x 480 px,
// f = 800, 1280, 2048 px, radial + tangential distortion), boards of
// ZoomScene (6 x 8 tags), 4 shots per usable board, zoom and face, 0.3 px
// pixel noise, seed 7. OpenCV gets each (shot, board) pair as one planar view
// in the board's own frame (what calibrateCamera needs), with k1 k2 p1 p2
// free and k3 fixed (CALIB_FIX_K3; the joint model fits k1 k2 k3 p1 p2),
// starting from cv::initCameraMatrix2D.
//
//   build-joint/bench/opencv_calibration_side_by_side_benchmark
// prints the table first, then times both with Google Benchmark.
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <opencv2/calib3d.hpp>

#include "libcalib/fit/init_from_pixels.h"
#include "libcalib/fit/refine.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib {
namespace {

constexpr int kZooms = 3;

SimulationOptions Options() {
  SimulationOptions o;
  o.seed = 7;
  o.truth = PaperTruth(kZooms);
  for (int z = 0; z < kZooms; ++z) {
    CameraTool& c = o.truth.cams[z];
    c.width = 640;
    c.height = 480;
    const double f = 800.0 * std::pow(1.6, z);
    c.intrinsics = {f, f * (1 + 3e-4), 324.0 - 2 * z, 237.0 + z};
    c.distortion.fill(0.0);
    c.distortion[kK1] = -0.1 / (1 + z);
    c.distortion[kK2] = 0.05 / (1 + z);
    c.distortion[kP1] = 5e-4;
    c.distortion[kP2] = -3e-4;
  }
  o.truth.effects.Add(Effect::kRadialDistortion);
  o.truth.effects.Add(Effect::kTangentialDistortion);
  o.targets = ZoomScene(o.truth, 6, 8, 3.0);
  o.shots.shots_per_board = 4;
  o.plan.faces = {1, 2};
  o.plan.zooms = {0, 1, 2};
  o.noise.pixel_px = 0.3;
  return o;
}

struct Data {
  SimulationOptions options = Options();
  Observations obs;
  Data() {
    obs = Simulate(options).obs;
    obs.records.clear();
  }
};

const Data& TheData() {
  static const Data data;
  return data;
}

struct Result {
  std::array<double, 4> intrinsics{};
  std::array<double, 4> sigma{};  // reported (joint) or OpenCV's stdDeviationsIntrinsics
  double seconds = 0;
  int views = 0;
};

// One planar view per (shot, board) of one zoom, in the board's frame.
Result OpenCvZoom(const Data& d, int zoom) {
  const TargetScene& scene = d.options.targets;
  std::map<std::pair<std::string, int>,
           std::pair<std::vector<cv::Point3f>, std::vector<cv::Point2f>>>
      views;
  for (const PixelObservation& p : d.obs.pixels) {
    if (p.zoom != zoom) continue;
    int board = -1;
    for (size_t b = 0; b < scene.boards.size(); ++b) {
      if (p.target >= scene.boards[b].first_id &&
          p.target < scene.boards[b].first_id + scene.boards[b].NumTags()) {
        board = static_cast<int>(b);
      }
    }
    const Eigen::Vector3d xb = scene.boards[board].ref_from_board.Inverse() * p.X;
    auto& v = views[{p.shot, board}];
    v.first.emplace_back(static_cast<float>(xb.x()), static_cast<float>(xb.y()), 0.0f);
    v.second.emplace_back(static_cast<float>(p.uv.x()), static_cast<float>(p.uv.y()));
  }
  std::vector<std::vector<cv::Point3f>> object;
  std::vector<std::vector<cv::Point2f>> image;
  for (auto& [key, v] : views) {
    if (v.first.size() < 8) continue;
    object.push_back(v.first);
    image.push_back(v.second);
  }
  const CameraTool& cam = d.options.truth.cams[zoom];
  const cv::Size size(cam.width, cam.height);
  const auto t0 = std::chrono::steady_clock::now();
  cv::Mat k = cv::initCameraMatrix2D(object, image, size);
  cv::Mat dist = cv::Mat::zeros(1, 5, CV_64F);
  std::vector<cv::Mat> rvecs, tvecs;
  cv::Mat std_intr, std_extr, per_view;
  cv::calibrateCamera(
      object, image, size, k, dist, rvecs, tvecs, std_intr, std_extr, per_view,
      cv::CALIB_USE_INTRINSIC_GUESS | cv::CALIB_FIX_K3,
      cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, DBL_EPSILON));
  Result r;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.intrinsics = {k.at<double>(0, 0), k.at<double>(1, 1), k.at<double>(0, 2), k.at<double>(1, 2)};
  for (int i = 0; i < 4; ++i) r.sigma[i] = std_intr.at<double>(i);
  r.views = static_cast<int>(object.size());
  return r;
}

// The joint model of all zooms and faces; per-zoom results, total time.
std::vector<Result> Joint(const Data& d) {
  const auto t0 = std::chrono::steady_clock::now();
  InitFromPixelsOptions io;
  io.kinematics = Kinematics::kDh;
  io.distortion.radial = io.distortion.tangential = true;
  for (const CameraTool& c : d.options.truth.cams) {
    CameraTool size;
    size.width = c.width;
    size.height = c.height;
    io.cameras.push_back(size);
  }
  InstrumentModel model = InitFromPixels(d.obs.pixels, io).model;
  model.effects.Add(Effect::kRadialDistortion);
  model.effects.Add(Effect::kTangentialDistortion);
  FitOptions fo;
  fo.fit_intrinsics = true;
  fo.sigma_pixel_px = 0.3;
  Refine(d.obs, fo, &model);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::vector<Result> out(kZooms);
  for (int z = 0; z < kZooms; ++z) {
    out[z].intrinsics = model.cams[z].intrinsics;
    out[z].sigma = model.sigmas.intrinsics[z];
    out[z].seconds = seconds;
  }
  return out;
}

double MaxError(const Result& r, const CameraTool& truth) {
  double e = 0;
  for (int i = 0; i < 4; ++i) e = std::max(e, std::abs(r.intrinsics[i] - truth.intrinsics[i]));
  return e;
}

void PrintTable() {
  const Data& d = TheData();
  const std::vector<Result> joint = Joint(d);
  std::printf("intrinsics error against the truth [px] (|fit - truth|; sigma reported by each)\n");
  std::printf("%-4s %-8s %9s %9s %9s %9s %9s %8s %6s\n", "zoom", "method", "dfx", "dfy", "dcx",
              "dcy", "max", "time_s", "views");
  bool ok = true;
  for (int z = 0; z < kZooms; ++z) {
    const CameraTool& t = d.options.truth.cams[z];
    const Result cv = OpenCvZoom(d, z);
    for (const auto& [name, r] : {std::pair<const char*, const Result&>{"opencv", cv},
                                  std::pair<const char*, const Result&>{"joint", joint[z]}}) {
      std::printf("%-4d %-8s", z, name);
      for (int i = 0; i < 4; ++i)
        std::printf(" %9.4f", std::abs(r.intrinsics[i] - t.intrinsics[i]));
      std::printf(" %9.4f %8.3f %6d\n", MaxError(r, t), r.seconds, r.views);
      std::printf("%-4s %-8s", "", "  sigma");
      for (int i = 0; i < 4; ++i) std::printf(" %9.4f", r.sigma[i]);
      std::printf("\n");
    }
    ok = ok && MaxError(joint[z], t) <= MaxError(cv, t);
  }
  std::printf("joint time is for all %d zooms together (start from pixels + refinement)\n", kZooms);
  std::printf("joint model at least as accurate as OpenCV at every zoom: %s\n\n",
              ok ? "yes" : "NO");
}

void BM_OpenCvCalibrateCamera(benchmark::State& state) {
  const Data& d = TheData();
  Result r;
  for (auto _ : state) r = OpenCvZoom(d, static_cast<int>(state.range(0)));
  state.counters["max_err_px"] = MaxError(r, d.options.truth.cams[state.range(0)]);
}
BENCHMARK(BM_OpenCvCalibrateCamera)->DenseRange(0, kZooms - 1)->Unit(benchmark::kMillisecond);

void BM_JointAllZooms(benchmark::State& state) {
  const Data& d = TheData();
  std::vector<Result> r;
  for (auto _ : state) r = Joint(d);
  for (int z = 0; z < kZooms; ++z) {
    state.counters["max_err_px_z" + std::to_string(z)] = MaxError(r[z], d.options.truth.cams[z]);
  }
}
BENCHMARK(BM_JointAllZooms)->Unit(benchmark::kMillisecond)->Iterations(2);

}  // namespace
}  // namespace rtscalib

int main(int argc, char** argv) {
  rtscalib::PrintTable();
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

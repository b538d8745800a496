// A camera on a bench, side by side with OpenCV: the 13 photos of
// configs/bench.yaml (OpenCV's own left01 ... left14.jpg, 640 x 480, a
// 9 x 6 inner-corner chessboard, Debian's opencv-doc).
//
//   BM_BenchConfigSideBySide/threads:T  per iteration, first OpenCV as its
//       calibration tutorial does it (cv::imread grey, findChessboardCorners
//       with its default flags, cornerSubPix 11 x 11 with (30, 1e-3),
//       calibrateCamera with its default model k1 k2 p1 p2 k3), then
//       `rtscalib --config configs/bench.yaml` in this process (detection,
//       calibration, diagnosis, report, figures: the whole run, into a fresh
//       output folder, ended once its report is complete). The benchmark's
//       time is rtscalib's run; counters: OpenCV's time in all and its
//       detection and calibration, and `x_opencv` = rtscalib's time /
//       OpenCV's. Threads, the same for both sides: T = 1, OpenCV's thread
//       pool off (cv::setNumThreads(1)), its photos one after the other,
//       rtscalib's detection with one job (its diagnosis and figures still
//       run beside the main thread); T = 2, OpenCV's photos split
//       over its thread pool of 2 threads (cv::parallel_for_; OpenCV's own
//       parallel loops inside a photo then run in that photo's thread), and
//       rtscalib's detection with 2 jobs (bench.yaml's detect.jobs), which
//       also turns OpenCV's pool off inside each photo.
//   BM_LargePhotoDetect/width:W  one photo of a synthesized scene (the
//       bench's board, 42 % of the frame wide, seen at an angle, on a
//       cluttered background, blurred by 1.2 px and with sensor noise at
//       6000 x 4000, JPEG quality 95) at W x 2W/3 pixels, the same scene
//       shrunk from 6000 x 4000: reading and the chessboard search
//       (detect::DetectPhotos, one job, as data.shots detects it); counter
//       ns/px. Time in proportion to the pixels: ns/px does not grow with W.
//   BM_LargePhotoOpenCv/width:W  the same photos through OpenCV's tutorial
//       steps (imread, findChessboardCorners with CALIB_CB_FAST_CHECK,
//       cornerSubPix 11 x 11), for scale.
//
//   build/bench/opencv_bench_side_by_side_benchmark --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/commands.h"
#include "bench/quiet_stdout.h"
#include "detect/photos.h"
#include "libcalib/io/shots.h"
#include "libcalib/io/targets_io.h"

namespace rtscalib::bench {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

// A temporary folder, removed with the object.
class TempDir {
 public:
  explicit TempDir(const std::string& stem) {
    std::string tmpl = (fs::temp_directory_path() / (stem + "-XXXXXX")).string();
    if (::mkdtemp(tmpl.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
    path_ = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// The bench's photos and board, read from the config's own files.
struct BenchPhotos {
  std::vector<std::string> files;
  cv::Size pattern;  // inner corners per row, per column
  double square = 0;
  BenchPhotos() {
    const std::string dir = std::string(RTSCALIB_SOURCE_DIR) + "/configs/bench/";
    for (const PhotoShot& s : ReadShots(dir + "shots.csv").shots) files.push_back(s.image_path);
    const std::map<std::string, int> families = detect::DetectableCodeCounts();
    const TagBoard& b = ReadTargets(dir + "targets.yaml", &families).boards.at(0);
    pattern = cv::Size(b.cols - 1, b.rows - 1);
    square = b.square_size;
  }
};

const BenchPhotos& Photos() {
  static const BenchPhotos photos;
  return photos;
}

// OpenCV's thread count for one benchmark: set at its start, the
// previous one back at its end.
struct CvThreadCount {
  explicit CvThreadCount(int n) : previous(cv::getNumThreads()) { cv::setNumThreads(n); }
  ~CvThreadCount() { cv::setNumThreads(previous); }
  int previous;
};

struct OpenCvRun {
  double detect_s = 0, calibrate_s = 0, rms_px = 0;
  int views = 0;
};

// OpenCV's calibration tutorial on the bench's photos; `parallel`: the
// photos split over OpenCV's thread pool.
OpenCvRun OpenCvSide(const BenchPhotos& p, bool parallel) {
  OpenCvRun run;
  const auto start = Clock::now();
  const int n = static_cast<int>(p.files.size());
  std::vector<std::vector<cv::Point2f>> found(n);
  std::vector<char> ok(n, 0);
  std::vector<cv::Size> sizes(n);
  auto photo = [&](int i) {
    const cv::Mat gray = cv::imread(p.files[i], cv::IMREAD_GRAYSCALE);
    sizes[i] = gray.size();
    if (!cv::findChessboardCorners(gray, p.pattern, found[i])) return;
    cv::cornerSubPix(gray, found[i], cv::Size(11, 11), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 1e-3));
    ok[i] = 1;
  };
  if (parallel) {
    cv::parallel_for_(cv::Range(0, n), [&](const cv::Range& r) {
      for (int i = r.start; i < r.end; ++i) photo(i);
    }, n);
  } else {
    for (int i = 0; i < n; ++i) photo(i);
  }
  std::vector<cv::Point3f> board;
  for (int r = 0; r < p.pattern.height; ++r) {
    for (int c = 0; c < p.pattern.width; ++c) {
      board.emplace_back(static_cast<float>(c * p.square), static_cast<float>(r * p.square), 0.0f);
    }
  }
  std::vector<std::vector<cv::Point3f>> object;
  std::vector<std::vector<cv::Point2f>> image;
  for (int i = 0; i < n; ++i) {
    if (!ok[i]) continue;
    object.push_back(board);
    image.push_back(found[i]);
  }
  run.detect_s = Seconds(start);
  const auto calibrate = Clock::now();
  cv::Mat k, d;
  std::vector<cv::Mat> rvecs, tvecs;
  if (!object.empty()) {
    run.rms_px = cv::calibrateCamera(object, image, sizes[0], k, d, rvecs, tvecs);
  }
  run.calibrate_s = Seconds(calibrate);
  run.views = static_cast<int>(object.size());
  return run;
}

void BM_BenchConfigSideBySide(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const BenchPhotos& photos = Photos();
  const CvThreadCount cv_threads(threads);
  const TempDir tmp("rtscalib-bench-side-by-side");
  app::RunArgs args;
  args.config = std::string(RTSCALIB_SOURCE_DIR) + "/configs/bench.yaml";
  args.quiet = true;
  args.jobs = threads;
  OpenCvRun sum;
  double rtscalib_s = 0;
  int iteration = 0;
  for (auto _ : state) {
    const OpenCvRun o = OpenCvSide(photos, threads > 1);
    sum.detect_s += o.detect_s;
    sum.calibrate_s += o.calibrate_s;
    sum.rms_px = o.rms_px;
    sum.views = o.views;
    // A fresh output folder per run: the run reads its folder's history.
    args.output = (tmp.path() / ("out" + std::to_string(iteration++))).string();
    const auto start = Clock::now();
    int code = 0;
    {
      const QuietStdout quiet;
      code = app::RunCalibration(args);
    }
    const double s = Seconds(start);
    if (code != 0) {
      state.SkipWithError("rtscalib --config configs/bench.yaml failed");
      return;
    }
    state.SetIterationTime(s);
    rtscalib_s += s;
    std::error_code ec;
    fs::remove_all(args.output, ec);
  }
  const double n = static_cast<double>(state.iterations());
  const double opencv_s = sum.detect_s + sum.calibrate_s;
  state.counters["opencv_ms"] = 1e3 * opencv_s / n;
  state.counters["opencv_detect_ms"] = 1e3 * sum.detect_s / n;
  state.counters["opencv_calibrate_ms"] = 1e3 * sum.calibrate_s / n;
  state.counters["opencv_rms_px"] = sum.rms_px;
  state.counters["opencv_views"] = sum.views;
  state.counters["x_opencv"] = rtscalib_s / opencv_s;
}
BENCHMARK(BM_BenchConfigSideBySide)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseManualTime()
    ->MinTime(3.0);

// ---------------------------------------------------------------------------
// Large photos: one scene at several sizes.

constexpr int kLargestWidth = 6000, kLargestHeight = 4000;

// The bench's printed board (10 x 7 squares, a white margin of one square),
// `px` pixels a square, 0 = ink, 255 = paper.
cv::Mat PrintedBoard(int px) {
  cv::Mat board(9 * px, 12 * px, CV_8UC1, cv::Scalar(255));
  for (int r = 0; r < 7; ++r) {
    for (int c = 0; c < 10; ++c) {
      if ((r + c) % 2 == 0) board(cv::Rect((c + 1) * px, (r + 1) * px, px, px)).setTo(0);
    }
  }
  return board;
}

// The scene at 6000 x 4000: a grey gradient with 60 random shapes (clutter
// for the searches), the board 42 % of the frame wide, turned by 8 degrees
// and seen at an angle, ink at 35 and paper at 210 grey levels; a lens blur
// of 1.2 px (Gaussian sigma) and sensor noise of 2 grey levels.
cv::Mat LargestScene() {
  const int w = kLargestWidth, h = kLargestHeight;
  cv::Mat scene(h, w, CV_8UC1);
  for (int y = 0; y < h; ++y) {
    unsigned char* row = scene.ptr<unsigned char>(y);
    for (int x = 0; x < w; ++x) row[x] = static_cast<unsigned char>(90 + 60 * x / w + 20 * y / h);
  }
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> ux(0, w), uy(0, h), size(40, 500), grey(20, 235);
  for (int i = 0; i < 60; ++i) {
    const cv::Point at(ux(rng), uy(rng));
    if (i % 2 == 0) {
      cv::circle(scene, at, size(rng) / 2, cv::Scalar(grey(rng)), cv::FILLED, cv::LINE_AA);
    } else {
      cv::rectangle(scene, cv::Rect(at, cv::Size(size(rng), size(rng))), cv::Scalar(grey(rng)),
                    cv::FILLED, cv::LINE_AA);
    }
  }
  const cv::Mat board = PrintedBoard(240);
  const float bw = static_cast<float>(board.cols), bh = static_cast<float>(board.rows);
  const std::vector<cv::Point2f> from = {{0, 0}, {bw, 0}, {bw, bh}, {0, bh}};
  // The board's outline in the image before the turn: a trapezoid (the
  // right edge farther away), 0.42 w wide, centred at (0.52 w, 0.47 h).
  const float half_w = 0.21f * w, half_h = half_w * bh / bw;
  const cv::Point2f c(0.52f * w, 0.47f * h);
  std::vector<cv::Point2f> to = {{c.x - half_w, c.y - half_h},
                                 {c.x + 0.93f * half_w, c.y - 0.88f * half_h},
                                 {c.x + 0.95f * half_w, c.y + 0.9f * half_h},
                                 {c.x - half_w, c.y + half_h}};
  const float a = 8.0f * static_cast<float>(M_PI) / 180.0f;
  for (cv::Point2f& p : to) {
    const cv::Point2f d = p - c;
    p = c + cv::Point2f(std::cos(a) * d.x - std::sin(a) * d.y, std::sin(a) * d.x + std::cos(a) * d.y);
  }
  const cv::Mat h_img_board = cv::getPerspectiveTransform(from, to);
  cv::Mat ink(board.size(), CV_8UC1);
  board.convertTo(ink, CV_8UC1, (210.0 - 35.0) / 255.0, 35.0);
  cv::Mat warped, mask;
  cv::warpPerspective(ink, warped, h_img_board, scene.size(), cv::INTER_LINEAR);
  cv::warpPerspective(cv::Mat(board.size(), CV_8UC1, cv::Scalar(255)), mask, h_img_board,
                      scene.size(), cv::INTER_LINEAR);
  // Anti-aliased outline: the scene and the board mixed by the warped mask.
  cv::Mat scene_f, warped_f, mask_f;
  scene.convertTo(scene_f, CV_32F);
  warped.convertTo(warped_f, CV_32F);
  mask.convertTo(mask_f, CV_32F, 1.0 / 255.0);
  cv::Mat mixed = scene_f.mul(1.0 - mask_f) + warped_f.mul(mask_f);
  cv::GaussianBlur(mixed, mixed, cv::Size(0, 0), 1.2);
  cv::Mat noise(mixed.size(), CV_32F);
  cv::randn(noise, 0.0, 2.0);
  mixed += noise;
  cv::Mat out;
  mixed.convertTo(out, CV_8UC1);
  return out;
}

// The scene's photos at each width of the benchmarks, as JPEG files with a
// shots.csv each; made once per process.
class LargePhotos {
 public:
  LargePhotos() : dir_("rtscalib-large-photos") {
    const cv::Mat largest = LargestScene();
    for (int w = kLargestWidth; w >= 750; w /= 2) {
      cv::Mat photo = largest;
      if (w != kLargestWidth) {
        cv::resize(largest, photo, cv::Size(w, w * kLargestHeight / kLargestWidth), 0, 0,
                   cv::INTER_AREA);
      }
      const std::string name = "scene_" + std::to_string(w) + ".jpg";
      if (!cv::imwrite((dir_.path() / name).string(), photo, {cv::IMWRITE_JPEG_QUALITY, 95})) {
        throw std::runtime_error("cannot write " + name);
      }
      const fs::path shots = dir_.path() / ("shots_" + std::to_string(w) + ".csv");
      std::ofstream(shots) << "face,zoom,phi,theta,image,placement\n1,0,,,"
                           << name << ",p\n";
    }
  }
  std::string photo(int w) const {
    return (dir_.path() / ("scene_" + std::to_string(w) + ".jpg")).string();
  }
  std::string shots(int w) const {
    return (dir_.path() / ("shots_" + std::to_string(w) + ".csv")).string();
  }

 private:
  TempDir dir_;
};

const LargePhotos& Large() {
  static const LargePhotos photos;
  return photos;
}

// Counters of a photo of width `w` that took `seconds` in all iterations.
void SetPixelCounters(benchmark::State& state, int w, double seconds) {
  const double pixels = static_cast<double>(w) * w * kLargestHeight / kLargestWidth;
  state.counters["Mpx"] = pixels / 1e6;
  state.counters["ns/px"] = 1e9 * seconds / static_cast<double>(state.iterations()) / pixels;
}

// The widths of the scene's photos, 750 to 6000 px.
void LargePhotoWidths(benchmark::internal::Benchmark* b) {
  b->ArgName("width")->Unit(benchmark::kMillisecond)->UseRealTime();
  for (int w = 750; w <= kLargestWidth; w *= 2) b->Arg(w);
}

void BM_LargePhotoDetect(benchmark::State& state) {
  const int w = static_cast<int>(state.range(0));
  const LargePhotos& large = Large();
  const std::string dir = std::string(RTSCALIB_SOURCE_DIR) + "/configs/bench/";
  const std::map<std::string, int> families = detect::DetectableCodeCounts();
  const TargetScene targets = ReadTargets(dir + "targets.yaml", &families);
  const ShotsFile shots = ReadShots(large.shots(w));
  detect::PhotoDetectionOptions options;
  options.jobs = 1;
  options.progress = false;
  const CvThreadCount cv_threads(1);
  size_t corners = 0;
  const auto start = Clock::now();
  for (auto _ : state) {
    const detect::PhotoDetectionResult r = detect::DetectPhotos(shots, targets, options);
    corners = r.photos.at(0).tags.size();
  }
  SetPixelCounters(state, w, Seconds(start));
  state.counters["corners"] = static_cast<double>(corners);
}
BENCHMARK(BM_LargePhotoDetect)->Apply(LargePhotoWidths);

void BM_LargePhotoOpenCv(benchmark::State& state) {
  const int w = static_cast<int>(state.range(0));
  const std::string photo = Large().photo(w);
  const CvThreadCount cv_threads(1);
  size_t corners = 0;
  const auto start = Clock::now();
  for (auto _ : state) {
    const cv::Mat gray = cv::imread(photo, cv::IMREAD_GRAYSCALE);
    std::vector<cv::Point2f> found;
    corners = 0;
    if (cv::findChessboardCorners(gray, Photos().pattern, found,
                                  cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE |
                                      cv::CALIB_CB_FAST_CHECK)) {
      cv::cornerSubPix(gray, found, cv::Size(11, 11), cv::Size(-1, -1),
                       cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 1e-3));
      corners = found.size();
    }
  }
  SetPixelCounters(state, w, Seconds(start));
  state.counters["corners"] = static_cast<double>(corners);
}
BENCHMARK(BM_LargePhotoOpenCv)->Apply(LargePhotoWidths);

}  // namespace
}  // namespace rtscalib::bench

BENCHMARK_MAIN();

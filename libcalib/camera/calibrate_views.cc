#include "libcalib/camera/calibrate_views.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <random>
#include <sstream>
#include <stdexcept>

namespace rtscalib::camera {
namespace {

using Matrix = Eigen::MatrixXd;
using Vector = Eigen::VectorXd;
using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Vector6 = Eigen::Matrix<double, 6, 1>;

struct Shot {
  std::string id;
  int face = 1;
  double phi = 0, theta = 0;
  int first_line = 0;
  std::vector<Eigen::Vector3d> X;  // reference frame [m]
  std::vector<Eigen::Vector2d> uv;
  std::vector<int> target;
};

std::string LineOf(const PixelObservation& p) {
  return p.line > 0 ? " (line " + std::to_string(p.line) + ")" : "";
}

std::vector<Shot> GroupShots(const std::vector<PixelObservation>& pixels, int* zoom) {
  std::vector<Shot> shots;
  std::map<std::string, size_t> index;
  *zoom = pixels.front().zoom;
  for (const PixelObservation& p : pixels) {
    if (p.zoom != *zoom) {
      std::ostringstream msg;
      msg << "CalibrateViews: observations of one zoom level expected; shot '" << p.shot << "'"
          << LineOf(p) << " has zoom " << p.zoom << " but the first row has zoom " << *zoom
          << " (calibrate each zoom level separately)";
      throw std::invalid_argument(msg.str());
    }
    if (!p.X.allFinite() || !p.uv.allFinite()) {
      throw std::invalid_argument("CalibrateViews: non-finite point or pixel in shot '" + p.shot +
                                  "'" + LineOf(p));
    }
    auto it = index.find(p.shot);
    if (it == index.end()) {
      it = index.emplace(p.shot, shots.size()).first;
      Shot s;
      s.id = p.shot;
      s.face = p.face;
      s.phi = p.phi;
      s.theta = p.theta;
      s.first_line = p.line;
      shots.push_back(s);
    }
    Shot& s = shots[it->second];
    if (p.face != s.face || p.phi != s.phi || p.theta != s.theta) {
      std::ostringstream msg;
      msg << "CalibrateViews: shot '" << p.shot << "' is one image, so every row must have the "
          << "same face, phi and theta; expected (" << s.face << ", " << s.phi << ", " << s.theta
          << ") as on its first row, got (" << p.face << ", " << p.phi << ", " << p.theta << ")"
          << LineOf(p);
      throw std::invalid_argument(msg.str());
    }
    s.X.push_back(p.X);
    s.uv.push_back(p.uv);
    s.target.push_back(p.target);
  }
  return shots;
}

// ---------------------------------------------------------------------------
// Planar subsets.

struct Plane {
  Eigen::Vector3d centroid;
  Eigen::Matrix3d ref_from_plane;  // columns: in-plane axes, normal
};

// Least-squares plane through the points `idx`; false if they are (nearly)
// collinear, i.e. spread less than `tol` across the line.
bool FitPlane(const std::vector<Eigen::Vector3d>& X, const std::vector<int>& idx, double tol,
              Plane* plane) {
  if (idx.size() < 3) return false;
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int i : idx) c += X[i];
  c /= static_cast<double>(idx.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int i : idx) cov += (X[i] - c) * (X[i] - c).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);  // ascending eigenvalues
  if (std::sqrt(std::max(0.0, eig.eigenvalues()[1]) / idx.size()) <= tol) return false;
  const Eigen::Vector3d e1 = eig.eigenvectors().col(2), e2 = eig.eigenvectors().col(1);
  plane->centroid = c;
  plane->ref_from_plane.col(0) = e1;
  plane->ref_from_plane.col(1) = e2;
  plane->ref_from_plane.col(2) = e1.cross(e2);
  return true;
}

std::vector<int> Inliers(const std::vector<Eigen::Vector3d>& X, const std::vector<bool>& used,
                         const Plane& plane, double tol) {
  const Eigen::Vector3d n = plane.ref_from_plane.col(2);
  std::vector<int> out;
  for (size_t i = 0; i < X.size(); ++i) {
    if (!used[i] && std::abs(n.dot(X[i] - plane.centroid)) <= tol)
      out.push_back(static_cast<int>(i));
  }
  return out;
}

// Greedy decomposition of a shot's points into planes (largest first).
// Candidate planes pass through each target's corners (a tag is planar);
// without targets of >= 3 points, through seeded random triples.
std::vector<std::vector<int>> PlanarSubsets(const Shot& shot, double tol) {
  const std::vector<Eigen::Vector3d>& X = shot.X;
  std::vector<bool> used(X.size(), false);
  std::vector<std::vector<int>> subsets;
  std::mt19937 rng(12345);
  for (size_t guard = 0; guard < X.size(); ++guard) {
    std::map<int, std::vector<int>> by_target;
    std::vector<int> remaining;
    for (size_t i = 0; i < X.size(); ++i) {
      if (used[i]) continue;
      by_target[shot.target[i]].push_back(static_cast<int>(i));
      remaining.push_back(static_cast<int>(i));
    }
    if (remaining.size() < 4) break;
    std::vector<std::vector<int>> seeds;
    for (const auto& [target, idx] : by_target) {
      if (idx.size() >= 3) seeds.push_back(idx);
    }
    if (seeds.empty()) {
      std::uniform_int_distribution<size_t> pick(0, remaining.size() - 1);
      for (int t = 0; t < 200; ++t) {
        seeds.push_back({remaining[pick(rng)], remaining[pick(rng)], remaining[pick(rng)]});
      }
    }
    std::vector<int> best;
    for (const std::vector<int>& seed : seeds) {
      Plane plane;
      if (!FitPlane(X, seed, tol, &plane)) continue;
      std::vector<int> in = Inliers(X, used, plane, tol);
      for (int refit = 0; refit < 2 && FitPlane(X, in, tol, &plane); ++refit) {
        in = Inliers(X, used, plane, tol);
      }
      if (in.size() > best.size()) best = in;
    }
    if (best.size() < 4) break;
    for (int i : best) used[i] = true;
    subsets.push_back(best);
  }
  return subsets;
}

// ---------------------------------------------------------------------------
// OpenCV initialisation.

cv::Mat CameraMatrix(const std::array<double, kNumIntrinsics>& k) {
  return (cv::Mat_<double>(3, 3) << k[0], 0, k[2], 0, k[1], k[3], 0, 0, 1);
}

int OpenCvFlags(const DistortionGroups& g) {
  int flags = cv::CALIB_USE_INTRINSIC_GUESS;
  if (!g.radial) flags |= cv::CALIB_FIX_K1 | cv::CALIB_FIX_K2 | cv::CALIB_FIX_K3;
  if (!g.tangential) flags |= cv::CALIB_ZERO_TANGENT_DIST;
  flags |= g.rational ? cv::CALIB_RATIONAL_MODEL
                      : (cv::CALIB_FIX_K4 | cv::CALIB_FIX_K5 | cv::CALIB_FIX_K6);
  flags |= g.thin_prism ? cv::CALIB_THIN_PRISM_MODEL : cv::CALIB_FIX_S1_S2_S3_S4;
  flags |= g.sensor_tilt ? cv::CALIB_TILTED_MODEL : cv::CALIB_FIX_TAUX_TAUY;
  return flags;
}

// Intrinsics that can serve as a start: finite, positive focal lengths and
// the principal point in the image. (A start whose distortion folds inside
// the image is still usable: projection, all the refinement needs, is defined
// everywhere in front of the camera.)
bool Plausible(const std::array<double, kNumIntrinsics>& k,
               const std::array<double, kNumDistortion>& d, int width, int height) {
  for (double v : k) {
    if (!std::isfinite(v)) return false;
  }
  for (double v : d) {
    if (!std::isfinite(v)) return false;
  }
  return k[0] > 0 && k[1] > 0 && k[2] >= 0 && k[2] <= width && k[3] >= 0 && k[3] <= height;
}

struct Init {
  std::array<double, kNumIntrinsics> intrinsics{};
  std::array<double, kNumDistortion> distortion{};
  std::string note;
};

// Candidate starts from OpenCV, best guess first: calibrateCamera with the
// enabled groups, with radial k1 k2 only, without distortion, and
// initCameraMatrix2D alone. The caller keeps the one that reprojects best.
std::vector<Init> OpenCvStarts(const std::vector<Shot>& shots, int width, int height,
                               const CalibrateViewsOptions& options, std::string* failures) {
  std::vector<std::vector<cv::Point3f>> object;
  std::vector<std::vector<cv::Point2f>> image;
  size_t largest = 0;
  for (const Shot& shot : shots) {
    for (const std::vector<int>& subset : PlanarSubsets(shot, options.plane_tolerance_m)) {
      largest = std::max(largest, subset.size());
      if (static_cast<int>(subset.size()) < options.min_points_per_plane) continue;
      Plane plane;
      if (!FitPlane(shot.X, subset, options.plane_tolerance_m, &plane)) continue;
      std::vector<cv::Point3f> obj;
      std::vector<cv::Point2f> img;
      for (int i : subset) {
        const Eigen::Vector3d p = plane.ref_from_plane.transpose() * (shot.X[i] - plane.centroid);
        obj.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), 0.0f);
        img.emplace_back(static_cast<float>(shot.uv[i].x()), static_cast<float>(shot.uv[i].y()));
      }
      object.push_back(obj);
      image.push_back(img);
    }
  }
  if (object.empty()) {
    std::ostringstream msg;
    msg << "CalibrateViews: no shot has " << options.min_points_per_plane
        << " coplanar points (within " << options.plane_tolerance_m
        << " m) to initialise the intrinsics from; the largest planar subset has " << largest
        << " points (lower min_points_per_plane or add board shots)";
    throw std::invalid_argument(msg.str());
  }
  // OpenCV's calibrateCamera solves its normal equations by SVD over all
  // views' poses (cost ~ (6 views)^3 per iteration); a start needs a few
  // views of different orientation, not all of them: keep an evenly spaced
  // selection in shot order.
  constexpr size_t kMaxOpenCvViews = 12;
  if (object.size() > kMaxOpenCvViews) {
    std::vector<std::vector<cv::Point3f>> obj_sel;
    std::vector<std::vector<cv::Point2f>> img_sel;
    for (size_t i = 0; i < kMaxOpenCvViews; ++i) {
      const size_t j = i * object.size() / kMaxOpenCvViews;
      obj_sel.push_back(object[j]);
      img_sel.push_back(image[j]);
    }
    object.swap(obj_sel);
    image.swap(img_sel);
  }
  const std::string on = " on " + std::to_string(object.size()) + " planar subsets";

  const cv::Size size(width, height);
  cv::Mat K;
  try {
    K = cv::initCameraMatrix2D(object, image, size, 1.0);
  } catch (const cv::Exception& e) {
    throw std::runtime_error(std::string("CalibrateViews: cv::initCameraMatrix2D failed: ") +
                             e.what());
  }
  const std::array<double, kNumIntrinsics> k0{K.at<double>(0, 0), K.at<double>(1, 1),
                                              K.at<double>(0, 2), K.at<double>(1, 2)};
  // OpenCV only provides the start (step 4 refines): its default 30 iterations.
  const cv::TermCriteria criteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 1e-10);

  DistortionGroups radial_only;
  radial_only.radial = options.distortion.radial;
  DistortionGroups none;
  none.radial = false;
  struct Attempt {
    DistortionGroups groups;
    int extra_flags;
    const char* note;
  };
  const Attempt attempts[] = {
      {options.distortion, 0, "cv::calibrateCamera with the enabled distortion groups"},
      {radial_only, cv::CALIB_FIX_K3, "cv::calibrateCamera with radial k1 k2 only"},
      {none, 0, "cv::calibrateCamera without distortion"}};
  std::vector<Init> starts;
  for (const Attempt& a : attempts) {
    cv::Mat Ka = CameraMatrix(k0);
    // calibrateCamera's output has 5, 8, 12 or 14 coefficients depending on
    // the model flags and rejects a longer input vector.
    const int n = a.groups.sensor_tilt ? 14 : a.groups.thin_prism ? 12 : a.groups.rational ? 8 : 5;
    cv::Mat Da = cv::Mat::zeros(1, n, CV_64F);
    std::vector<cv::Mat> rvecs, tvecs;
    try {
      cv::calibrateCamera(object, image, size, Ka, Da, rvecs, tvecs,
                          OpenCvFlags(a.groups) | a.extra_flags, criteria);
    } catch (const cv::Exception& e) {
      *failures += std::string(" [") + a.note + ": " + e.what() + "]";
      continue;
    }
    Init init;
    init.intrinsics = {Ka.at<double>(0, 0), Ka.at<double>(1, 1), Ka.at<double>(0, 2),
                       Ka.at<double>(1, 2)};
    for (int i = 0; i < std::min<int>(kNumDistortion, static_cast<int>(Da.total())); ++i) {
      init.distortion[i] = Da.at<double>(i);
    }
    if (!Plausible(init.intrinsics, init.distortion, width, height)) {
      *failures += std::string(" [") + a.note + ": implausible intrinsics]";
      continue;
    }
    init.note = a.note + on;
    starts.push_back(init);
  }
  Init init;
  init.intrinsics = k0;
  init.note = "cv::initCameraMatrix2D" + on;
  if (Plausible(init.intrinsics, init.distortion, width, height)) starts.push_back(init);
  return starts;
}

// Step 3 for one start: every shot's pose by cv::solvePnP and the RMS.
struct Start {
  Init init;
  std::vector<Rigid3> cam_from_ref;  // per posed shot
  std::vector<int> posed;            // indices into the shots
  std::vector<ExcludedShot> failed;
  double rms_px = std::numeric_limits<double>::infinity();
};

Start PoseShots(const Init& init, const std::vector<Shot>& shots) {
  Start start;
  start.init = init;
  const cv::Mat K = CameraMatrix(init.intrinsics);
  std::array<double, kNumDistortion> d = init.distortion;
  const cv::Mat D(1, kNumDistortion, CV_64F, d.data());
  double sum = 0;
  int n = 0;
  for (size_t k = 0; k < shots.size(); ++k) {
    const Shot& shot = shots[k];
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& X : shot.X) c += X;
    c /= static_cast<double>(shot.X.size());
    std::vector<cv::Point3d> obj;
    std::vector<cv::Point2d> img;
    for (size_t i = 0; i < shot.X.size(); ++i) {
      const Eigen::Vector3d p = shot.X[i] - c;  // centred: better conditioned
      obj.emplace_back(p.x(), p.y(), p.z());
      img.emplace_back(shot.uv[i].x(), shot.uv[i].y());
    }
    cv::Mat rvec, tvec;
    bool ok = false;
    try {
      ok = cv::solvePnP(obj, img, K, D, rvec, tvec, false, cv::SOLVEPNP_SQPNP) &&
           cv::solvePnP(obj, img, K, D, rvec, tvec, true, cv::SOLVEPNP_ITERATIVE);
    } catch (const cv::Exception& e) {
      start.failed.push_back({shot.id, static_cast<int>(shot.X.size()),
                              std::string("cv::solvePnP failed: ") + e.what()});
      continue;
    }
    Rigid3 cam_from_ref;
    double shot_sum = 0;
    if (ok) {
      cv::Mat R;
      cv::Rodrigues(rvec, R);
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) cam_from_ref.rotation(i, j) = R.at<double>(i, j);
      }
      const Eigen::Vector3d t(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
      cam_from_ref.translation = t - cam_from_ref.rotation * c;
      for (size_t i = 0; i < shot.X.size() && ok; ++i) {
        const Eigen::Vector3d Xc = cam_from_ref * shot.X[i];
        double px[2];
        ok = ProjectToPixel(init.intrinsics.data(), init.distortion.data(), Xc.data(), px);
        shot_sum += (Eigen::Vector2d(px[0], px[1]) - shot.uv[i]).squaredNorm();
      }
    }
    if (!ok) {
      start.failed.push_back({shot.id, static_cast<int>(shot.X.size()),
                              "no pose with every point in front of the camera"});
      continue;
    }
    start.cam_from_ref.push_back(cam_from_ref);
    start.posed.push_back(static_cast<int>(k));
    sum += shot_sum;
    n += static_cast<int>(shot.X.size());
  }
  if (n > 0) start.rms_px = std::sqrt(sum / n);
  return start;
}

// ---------------------------------------------------------------------------
// Joint refinement: Levenberg-Marquardt over [intrinsics, free distortion
// coefficients] and every shot's cam_from_ref, with exact Jacobians (forward
// mode through the templated ProjectToPixel) and an orthogonal solve. Both
// matter for the rational model, whose k1..k3 and k4..k6 are nearly redundant
// over an image: central differences or normal equations stall Gauss-Newton
// in that valley.

constexpr int kMaxCamera = kNumIntrinsics + kNumDistortion;
constexpr int kNumDual = kMaxCamera + 6;

// Minimal forward-mode dual number: value `a`, gradient `v`; just the
// operations ProjectToPixel needs.
struct Dual {
  using Grad = Eigen::Matrix<double, kNumDual, 1>;
  double a = 0;
  Grad v = Grad::Zero();
  Dual() = default;
  explicit Dual(double value) : a(value) {}
  Dual(double value, const Grad& grad) : a(value), v(grad) {}
  static Dual Variable(double value, int k) {
    Dual d(value);
    d.v[k] = 1;
    return d;
  }
};
inline Dual operator+(const Dual& x, const Dual& y) { return {x.a + y.a, x.v + y.v}; }
inline Dual operator-(const Dual& x, const Dual& y) { return {x.a - y.a, x.v - y.v}; }
inline Dual operator-(const Dual& x) { return {-x.a, -x.v}; }
inline Dual operator*(const Dual& x, const Dual& y) { return {x.a * y.a, y.a * x.v + x.a * y.v}; }
inline Dual operator/(const Dual& x, const Dual& y) {
  const double q = x.a / y.a;
  return {q, (x.v - q * y.v) / y.a};
}
inline Dual& operator+=(Dual& x, const Dual& y) { return x = x + y; }
inline Dual& operator-=(Dual& x, const Dual& y) { return x = x - y; }
inline bool operator>(const Dual& x, const Dual& y) { return x.a > y.a; }
inline bool operator<(const Dual& x, const Dual& y) { return x.a < y.a; }
inline Dual sin(const Dual& x) { return {std::sin(x.a), std::cos(x.a) * x.v}; }
inline Dual cos(const Dual& x) { return {std::cos(x.a), -std::sin(x.a) * x.v}; }

struct Problem {
  const std::vector<Shot>* shots;
  std::vector<int> free;  // free distortion indices
  int NumCamera() const { return kNumIntrinsics + static_cast<int>(free.size()); }
};

struct State {
  std::array<double, kNumIntrinsics> intrinsics{};
  std::array<double, kNumDistortion> distortion{};
  std::vector<Rigid3> cam_from_ref;
};

double CameraParam(const Problem& pb, const State& s, int j) {
  return j < kNumIntrinsics ? s.intrinsics[j] : s.distortion[pb.free[j - kNumIntrinsics]];
}
double& CameraParam(const Problem& pb, State* s, int j) {
  return j < kNumIntrinsics ? s->intrinsics[j] : s->distortion[pb.free[j - kNumIntrinsics]];
}

Eigen::Matrix3d ExpRotation(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  if (angle == 0.0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

// Pose increment [w, dt]: R <- Exp(w) R, t <- t + dt, so that a camera point
// y = R X + t moves by w x (R X) + dt.
Rigid3 Perturb(const Rigid3& pose, const Vector6& delta) {
  return {ExpRotation(delta.head<3>()) * pose.rotation, pose.translation + delta.tail<3>()};
}

bool Residual(const State& s, const Rigid3& cam_from_ref, const Eigen::Vector3d& X,
              const Eigen::Vector2d& uv, Eigen::Vector2d* r) {
  const Eigen::Vector3d Xc = cam_from_ref * X;
  double px[2];
  if (!ProjectToPixel(s.intrinsics.data(), s.distortion.data(), Xc.data(), px)) return false;
  *r = Eigen::Vector2d(px[0], px[1]) - uv;
  return true;
}

// Sum of squared residuals; false if a point is behind its camera.
bool Cost(const Problem& pb, const State& s, double* cost) {
  *cost = 0;
  for (size_t k = 0; k < pb.shots->size(); ++k) {
    const Shot& shot = (*pb.shots)[k];
    for (size_t i = 0; i < shot.X.size(); ++i) {
      Eigen::Vector2d r;
      if (!Residual(s, s.cam_from_ref[k], shot.X[i], shot.uv[i], &r)) return false;
      *cost += r.squaredNorm();
    }
  }
  return true;
}

// Jacobians and residuals of every shot, kept as rows (not normal
// equations): the solve below works on J itself.
struct Linearization {
  std::vector<Matrix> Jc;  // 2n x camera, per shot
  std::vector<Matrix> Jp;  // 2n x 6, per shot
  std::vector<Vector> r;   // 2n, per shot
};

bool Linearize(const Problem& pb, const State& s, Linearization* lin) {
  const int nc = pb.NumCamera();
  const size_t ns = pb.shots->size();
  lin->Jc.resize(ns);
  lin->Jp.resize(ns);
  lin->r.resize(ns);
  // Camera parameters as dual numbers: gradient slots 0..nc-1; slots
  // kMaxCamera..kMaxCamera+5 are the pose increment [w, dt].
  Dual intrinsics[kNumIntrinsics], dist[kNumDistortion];
  for (int j = 0; j < kNumIntrinsics; ++j) intrinsics[j] = Dual::Variable(s.intrinsics[j], j);
  for (int i = 0; i < kNumDistortion; ++i) dist[i] = Dual(s.distortion[i]);
  for (size_t f = 0; f < pb.free.size(); ++f) {
    dist[pb.free[f]] =
        Dual::Variable(s.distortion[pb.free[f]], kNumIntrinsics + static_cast<int>(f));
  }
  for (size_t k = 0; k < ns; ++k) {
    const Shot& shot = (*pb.shots)[k];
    const Rigid3& pose = s.cam_from_ref[k];
    const int rows = 2 * static_cast<int>(shot.X.size());
    lin->Jc[k].resize(rows, nc);
    lin->Jp[k].resize(rows, 6);
    lin->r[k].resize(rows);
    for (size_t i = 0; i < shot.X.size(); ++i) {
      const Eigen::Vector3d rx = pose.rotation * shot.X[i];
      const Eigen::Vector3d y = rx + pose.translation;
      Dual Xc[3];
      for (int a = 0; a < 3; ++a) {
        Xc[a] = Dual(y[a]);
        Xc[a].v[kMaxCamera + 3 + a] = 1;  // d y / d dt
      }
      // d y / d w = -[R X]_x, column j = e_j x (R X).
      Xc[1].v[kMaxCamera + 0] = -rx[2];
      Xc[2].v[kMaxCamera + 0] = rx[1];
      Xc[0].v[kMaxCamera + 1] = rx[2];
      Xc[2].v[kMaxCamera + 1] = -rx[0];
      Xc[0].v[kMaxCamera + 2] = -rx[1];
      Xc[1].v[kMaxCamera + 2] = rx[0];
      Dual px[2];
      if (!ProjectToPixel(intrinsics, dist, Xc, px)) return false;
      for (int row = 0; row < 2; ++row) {
        const int at = 2 * static_cast<int>(i) + row;
        lin->r[k][at] = px[row].a - shot.uv[i][row];
        lin->Jc[k].row(at) = px[row].v.head(nc).transpose();
        lin->Jp[k].row(at) = px[row].v.segment<6>(kMaxCamera).transpose();
      }
    }
  }
  return true;
}

// Damped Gauss-Newton step min |J d + r|^2 + lambda |d|^2 in Jacobi-scaled
// variables (unit column norms, so pixels, metres, radians and coefficients
// of r^12 are comparable; Marquardt's diag(J^T J) damping becomes lambda I).
// Solved with orthogonal factorisations, never normal equations: the
// rational model's near-redundant columns make cond(J) ~1e8, and J^T J would
// square that beyond double precision. Each shot's pose columns are
// eliminated by a QR of that block (a square-root Schur complement); the
// stacked camera rows are solved by a column-pivoted QR.
bool SolveStep(const Linearization& lin, double lambda, Vector* dc, std::vector<Vector6>* dp) {
  const size_t ns = lin.Jc.size();
  const int nc = static_cast<int>(lin.Jc.front().cols());
  const double sqrt_lambda = std::sqrt(lambda);
  auto scale_of = [](double norm) { return norm > 0 ? 1.0 / norm : 1.0; };
  Vector col_sq = Vector::Zero(nc);
  int reduced_rows = nc;
  for (size_t k = 0; k < ns; ++k) {
    col_sq += lin.Jc[k].colwise().squaredNorm().transpose();
    reduced_rows += static_cast<int>(lin.Jc[k].rows());
  }
  Vector sc(nc);
  for (int j = 0; j < nc; ++j) sc[j] = scale_of(std::sqrt(col_sq[j]));

  Matrix reduced = Matrix::Zero(reduced_rows, nc + 1);  // [camera columns | rhs]
  std::vector<Eigen::Matrix<double, 6, 6>> R(ns);
  std::vector<Matrix> top(ns);  // first 6 rows of Q^T [Jc | -r] per shot
  std::vector<Vector6> sp(ns);
  int at = 0;
  for (size_t k = 0; k < ns; ++k) {
    const int rows = static_cast<int>(lin.Jp[k].rows());
    for (int j = 0; j < 6; ++j) sp[k][j] = scale_of(lin.Jp[k].col(j).norm());
    Matrix A(rows + 6, 6);
    A.topRows(rows) = lin.Jp[k] * sp[k].asDiagonal();
    A.bottomRows(6) = sqrt_lambda * Matrix6::Identity();
    Matrix M = Matrix::Zero(rows + 6, nc + 1);
    M.topLeftCorner(rows, nc) = lin.Jc[k] * sc.asDiagonal();
    M.topRightCorner(rows, 1) = -lin.r[k];
    const Eigen::HouseholderQR<Matrix> qr(A);
    M.applyOnTheLeft(qr.householderQ().adjoint());
    R[k] = qr.matrixQR().topLeftCorner<6, 6>().triangularView<Eigen::Upper>();
    if (!(R[k].diagonal().array().abs() > 0).all()) return false;
    top[k] = M.topRows(6);
    reduced.middleRows(at, rows) = M.bottomRows(rows);
    at += rows;
  }
  reduced.block(at, 0, nc, nc) = sqrt_lambda * Matrix::Identity(nc, nc);
  const Eigen::ColPivHouseholderQR<Matrix> qr(reduced.leftCols(nc));
  const Vector dc_scaled = qr.solve(reduced.col(nc));
  if (!dc_scaled.allFinite()) return false;
  *dc = sc.asDiagonal() * dc_scaled;
  dp->resize(ns);
  for (size_t k = 0; k < ns; ++k) {
    const Vector6 rhs = top[k].col(nc) - top[k].leftCols(nc) * dc_scaled;
    const Vector6 dp_scaled = R[k].triangularView<Eigen::Upper>().solve(rhs);
    (*dp)[k] = sp[k].asDiagonal() * dp_scaled;
    if (!(*dp)[k].allFinite()) return false;
  }
  return true;
}

State ApplyStep(const Problem& pb, const State& s, const Vector& dc,
                const std::vector<Vector6>& dp) {
  State out = s;
  for (int j = 0; j < pb.NumCamera(); ++j) CameraParam(pb, &out, j) += dc[j];
  for (size_t k = 0; k < dp.size(); ++k) out.cam_from_ref[k] = Perturb(s.cam_from_ref[k], dp[k]);
  return out;
}

bool StepIsNegligible(const Problem& pb, const State& s, const Vector& dc,
                      const std::vector<Vector6>& dp) {
  constexpr double kTol = 1e-13;
  for (int j = 0; j < pb.NumCamera(); ++j) {
    if (std::abs(dc[j]) > kTol * (1.0 + std::abs(CameraParam(pb, s, j)))) return false;
  }
  for (size_t k = 0; k < dp.size(); ++k) {
    const double t_scale = 1.0 + s.cam_from_ref[k].translation.norm();
    if (dp[k].head<3>().norm() > kTol || dp[k].tail<3>().norm() > kTol * t_scale) return false;
  }
  return true;
}

// Stops when a step is negligible, when an accepted step improves the RMS by
// less than `rms_tolerance_px` (or the cost by a relative 1e-14), or when no
// damping gives descent (not converged).
void Refine(const Problem& pb, int max_iterations, double rms_tolerance_px, int num_points,
            State* s, int* iterations, bool* converged) {
  *iterations = 0;
  *converged = false;
  double cost;
  if (!Cost(pb, *s, &cost)) return;
  double lambda = 1e-4;
  Linearization lin;
  bool rebuild = true;
  for (int it = 0; it < max_iterations; ++it) {
    *iterations = it + 1;
    if (cost == 0.0) {
      *converged = true;
      return;
    }
    if (rebuild && !Linearize(pb, *s, &lin)) return;
    Vector dc;
    std::vector<Vector6> dp;
    if (!SolveStep(lin, lambda, &dc, &dp)) {
      lambda *= 10;
      rebuild = false;
      continue;
    }
    if (StepIsNegligible(pb, *s, dc, dp)) {
      *converged = true;
      return;
    }
    const State candidate = ApplyStep(pb, *s, dc, dp);
    double new_cost;
    if (Cost(pb, candidate, &new_cost) && new_cost < cost) {
      const double decrease = (cost - new_cost) / cost;
      const double rms_decrease = std::sqrt(cost / num_points) - std::sqrt(new_cost / num_points);
      *s = candidate;
      cost = new_cost;
      // No practical floor: the orthogonal solve stays accurate as lambda -> 0,
      // and a floor above sigma_min^2 (~1e-17 for the rational model, scaled)
      // would turn Gauss-Newton into slow gradient steps along that direction.
      lambda = std::max(lambda / 10, 1e-30);
      rebuild = true;
      if (decrease < 1e-14 || rms_decrease < rms_tolerance_px) {
        *converged = true;
        return;
      }
    } else {
      lambda *= 10;
      rebuild = false;
      if (lambda > 1e16) return;  // no descent at any damping: stuck
    }
  }
}

}  // namespace

// ---------------------------------------------------------------------------

std::vector<int> DistortionGroups::FreeCoefficients() const {
  std::vector<int> out;
  for (int i = 0; i < kNumDistortion; ++i) {
    const bool free = (i == kK1 || i == kK2 || i == kK3)   ? radial
                      : (i == kP1 || i == kP2)             ? tangential
                      : (i == kK4 || i == kK5 || i == kK6) ? rational
                      : (i >= kS1 && i <= kS4)             ? thin_prism
                                                           : sensor_tilt;
    if (free) out.push_back(i);
  }
  return out;
}

std::string DistortionGroups::Names() const {
  std::string s;
  auto add = [&s](bool on, const char* name) {
    if (on) s += (s.empty() ? "" : "+") + std::string(name);
  };
  add(radial, "radial");
  add(tangential, "tangential");
  add(rational, "rational");
  add(thin_prism, "thin_prism");
  add(sensor_tilt, "sensor_tilt");
  return s.empty() ? "none" : s;
}

std::string CalibrateViewsOptions::Check() const {
  std::ostringstream msg;
  if (min_shots < 1) msg << "min_shots must be >= 1, got " << min_shots << "; ";
  if (min_points_per_shot < 4) {
    msg << "min_points_per_shot must be >= 4 (a pose needs 4 points), got " << min_points_per_shot
        << "; ";
  }
  if (min_points_per_plane < 4) {
    msg << "min_points_per_plane must be >= 4 (a homography needs 4 points), got "
        << min_points_per_plane << "; ";
  }
  if (!(plane_tolerance_m > 0) || !std::isfinite(plane_tolerance_m)) {
    msg << "plane_tolerance_m must be a positive number of metres, got " << plane_tolerance_m
        << "; ";
  }
  if (max_iterations < 1) msg << "max_iterations must be >= 1, got " << max_iterations << "; ";
  if (!(rms_tolerance_px > 0) || !std::isfinite(rms_tolerance_px)) {
    msg << "rms_tolerance_px must be a positive number of pixels, got " << rms_tolerance_px << "; ";
  }
  std::string s = msg.str();
  if (!s.empty()) s.resize(s.size() - 2);
  return s;
}

ViewsCalibration CalibrateViews(const std::vector<PixelObservation>& pixels, int width, int height,
                                const CalibrateViewsOptions& options) {
  if (const std::string error = options.Check(); !error.empty()) {
    throw std::invalid_argument("CalibrateViews options: " + error);
  }
  if (width <= 0 || height <= 0) {
    throw std::invalid_argument("CalibrateViews: image size must be positive, got " +
                                std::to_string(width) + " x " + std::to_string(height));
  }
  if (pixels.empty()) throw std::invalid_argument("CalibrateViews: no pixel observations");

  ViewsCalibration out;
  out.width = width;
  out.height = height;
  std::vector<Shot> all_shots = GroupShots(pixels, &out.zoom);

  std::vector<Shot> shots;
  for (Shot& shot : all_shots) {
    if (static_cast<int>(shot.X.size()) < options.min_points_per_shot) {
      out.excluded.push_back({shot.id, static_cast<int>(shot.X.size()),
                              "fewer than min_points_per_shot = " +
                                  std::to_string(options.min_points_per_shot) + " points"});
    } else {
      shots.push_back(std::move(shot));
    }
  }
  auto require_shots = [&](const char* stage) {
    if (static_cast<int>(shots.size()) < options.min_shots) {
      std::ostringstream msg;
      msg << "CalibrateViews (zoom " << out.zoom << "): " << shots.size() << " usable shot(s) "
          << stage << ", at least min_shots = " << options.min_shots << " needed ("
          << all_shots.size() << " shot(s) in the input, " << out.excluded.size() << " excluded)";
      for (const ExcludedShot& e : out.excluded) msg << "; '" << e.shot << "': " << e.reason;
      throw std::invalid_argument(msg.str());
    }
  };
  require_shots("with enough points");

  // Steps 2 and 3: the OpenCV start that poses the most shots and then
  // reprojects best.
  std::string failures;
  const std::vector<Init> inits = OpenCvStarts(shots, width, height, options, &failures);
  if (inits.empty()) {
    throw std::runtime_error("CalibrateViews: OpenCV initialisation failed:" + failures);
  }
  Start best;
  for (const Init& init : inits) {
    Start start = PoseShots(init, shots);
    if (start.posed.size() > best.posed.size() ||
        (start.posed.size() == best.posed.size() && start.rms_px < best.rms_px)) {
      best = std::move(start);
    }
  }
  out.init_note = best.init.note + failures;
  out.opencv_rms_px = best.rms_px;
  for (const ExcludedShot& e : best.failed) out.excluded.push_back(e);
  State state;
  state.intrinsics = best.init.intrinsics;
  state.distortion = best.init.distortion;
  state.cam_from_ref = best.cam_from_ref;
  {
    std::vector<Shot> posed;
    for (int k : best.posed) posed.push_back(std::move(shots[k]));
    shots = std::move(posed);
  }
  require_shots("with a pose");

  Problem problem;
  problem.shots = &shots;
  problem.free = options.distortion.FreeCoefficients();
  // Disabled groups are exactly zero, whatever the initialisation did.
  for (int i = 0; i < kNumDistortion; ++i) {
    if (std::find(problem.free.begin(), problem.free.end(), i) == problem.free.end()) {
      state.distortion[i] = 0.0;
    }
  }
  int num_points = 0;
  for (const Shot& shot : shots) num_points += static_cast<int>(shot.X.size());
  const int unknowns = problem.NumCamera() + 6 * static_cast<int>(shots.size());
  if (2 * num_points <= unknowns) {
    std::ostringstream msg;
    msg << "CalibrateViews (zoom " << out.zoom << "): " << num_points << " points give "
        << 2 * num_points << " equations for " << unknowns << " unknowns (" << problem.NumCamera()
        << " camera parameters with distortion " << options.distortion.Names()
        << ", 6 per shot for " << shots.size() << " shots); more points are needed";
    throw std::invalid_argument(msg.str());
  }

  // Step 4.
  Refine(problem, options.max_iterations, options.rms_tolerance_px, num_points, &state,
         &out.iterations, &out.converged);

  out.intrinsics = state.intrinsics;
  out.distortion = state.distortion;
  out.num_points = num_points;
  out.max_trusted_radius = MaxTrustedRadius(state.distortion.data());
  double total = 0;
  for (size_t k = 0; k < shots.size(); ++k) {
    const Shot& shot = shots[k];
    ShotPose pose;
    pose.shot = shot.id;
    pose.face = shot.face;
    pose.phi = shot.phi;
    pose.theta = shot.theta;
    pose.ref_from_cam = state.cam_from_ref[k].Inverse();
    pose.num_points = static_cast<int>(shot.X.size());
    double sum = 0;
    for (size_t i = 0; i < shot.X.size(); ++i) {
      Eigen::Vector2d r;
      if (!Residual(state, state.cam_from_ref[k], shot.X[i], shot.uv[i], &r)) {
        throw std::runtime_error("CalibrateViews: refinement put a point of shot '" + shot.id +
                                 "' behind the camera");
      }
      sum += r.squaredNorm();
      const Eigen::Vector3d Xc = state.cam_from_ref[k] * shot.X[i];
      if (Xc.head<2>().norm() / Xc.z() >= out.max_trusted_radius)
        ++out.points_beyond_trusted_radius;
    }
    pose.rms_px = std::sqrt(sum / pose.num_points);
    total += sum;
    out.shots.push_back(pose);
  }
  out.rms_px = std::sqrt(total / num_points);
  return out;
}

}  // namespace rtscalib::camera

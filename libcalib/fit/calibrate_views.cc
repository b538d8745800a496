#include "libcalib/fit/calibrate_views.h"

#include <ceres/autodiff_cost_function.h>
#include <ceres/problem.h>
#include <ceres/solver.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <future>
#include <limits>
#include <map>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <random>
#include <sstream>
#include <stdexcept>

#include "libcalib/fit/cost_functions.h"
#include "libcalib/fit/manifolds.h"
#include "libcalib/model/kinematics.h"

namespace rtscalib {
namespace {

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

// " (pixels from line 12)": where a zoom's rows start, for its messages.
std::string FirstLine(const std::vector<PixelObservation>& pixels) {
  return pixels.empty() || pixels.front().line <= 0
             ? ""
             : " (pixels from line " + std::to_string(pixels.front().line) + ")";
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

// The views OpenCV's initialisation sees: each shot's planar subsets of at
// least min_points_per_plane points in their own plane frame (z = 0), and
// cv::initCameraMatrix2D's camera matrix from them.
struct OpenCvViews {
  std::vector<std::vector<cv::Point3f>> object;
  std::vector<std::vector<cv::Point2f>> image;
  cv::Size size;
  std::array<double, kNumIntrinsics> k0{};
  std::string on;  // " on N planar subsets", for the notes
};

OpenCvViews PlanarViews(const std::vector<Shot>& shots, int width, int height,
                        const CalibrateViewsOptions& options) {
  OpenCvViews v;
  std::vector<std::vector<cv::Point3f>>& object = v.object;
  std::vector<std::vector<cv::Point2f>>& image = v.image;
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
  // selection in shot order. Step 4 refines over every shot. Six: on
  // OpenCV's 13 sample photos (configs/bench.yaml) they give the same fit as
  // twelve in about two thirds of the start's time (the run's log), and the
  // real-photo suite's sets, mrcal's 186 views included, start from them.
  constexpr size_t kMaxOpenCvViews = 6;
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
  v.on = " on " + std::to_string(object.size()) + " planar subsets";
  v.size = cv::Size(width, height);
  cv::Mat K;
  try {
    K = cv::initCameraMatrix2D(object, image, v.size, 1.0);
  } catch (const cv::Exception& e) {
    throw std::runtime_error(std::string("CalibrateViews: cv::initCameraMatrix2D failed: ") +
                             e.what());
  }
  v.k0 = {K.at<double>(0, 0), K.at<double>(1, 1), K.at<double>(0, 2), K.at<double>(1, 2)};
  return v;
}

// The candidate starts from OpenCV, best guess first: calibrateCamera with
// the enabled groups, with radial k1 k2 only, without distortion, and
// initCameraMatrix2D alone.
constexpr int kNumOpenCvStarts = 4;

// Start `which` (0 .. kNumOpenCvStarts - 1), or false with *failures saying
// why (OpenCV's error, or intrinsics that cannot serve as a start).
bool OpenCvStart(const OpenCvViews& v, int which, const CalibrateViewsOptions& options,
                 Init* init, std::string* failures) {
  init->distortion.fill(0.0);
  if (which == kNumOpenCvStarts - 1) {
    init->intrinsics = v.k0;
    init->note = "cv::initCameraMatrix2D" + v.on;
    return Plausible(init->intrinsics, init->distortion, v.size.width, v.size.height);
  }
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
  const Attempt attempts[kNumOpenCvStarts - 1] = {
      {options.distortion, 0, "cv::calibrateCamera with the enabled distortion groups"},
      {radial_only, cv::CALIB_FIX_K3, "cv::calibrateCamera with radial k1 k2 only"},
      {none, 0, "cv::calibrateCamera without distortion"}};
  const Attempt& a = attempts[which];
  cv::Mat Ka = CameraMatrix(v.k0);
  // calibrateCamera's output has 5, 8, 12 or 14 coefficients depending on
  // the model flags and rejects a longer input vector.
  const int n = a.groups.sensor_tilt ? 14 : a.groups.thin_prism ? 12 : a.groups.rational ? 8 : 5;
  cv::Mat Da = cv::Mat::zeros(1, n, CV_64F);
  std::vector<cv::Mat> rvecs, tvecs;
  try {
    cv::calibrateCamera(v.object, v.image, v.size, Ka, Da, rvecs, tvecs,
                        OpenCvFlags(a.groups) | a.extra_flags, criteria);
  } catch (const cv::Exception& e) {
    *failures += std::string(" [") + a.note + ": " + e.what() + "]";
    return false;
  }
  init->intrinsics = {Ka.at<double>(0, 0), Ka.at<double>(1, 1), Ka.at<double>(0, 2),
                      Ka.at<double>(1, 2)};
  for (int i = 0; i < std::min<int>(kNumDistortion, static_cast<int>(Da.total())); ++i) {
    init->distortion[i] = Da.at<double>(i);
  }
  if (!Plausible(init->intrinsics, init->distortion, v.size.width, v.size.height)) {
    *failures += std::string(" [") + a.note + ": implausible intrinsics]";
    return false;
  }
  init->note = a.note + v.on;
  return true;
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
        if (ok) shot_sum += (Eigen::Vector2d(px[0], px[1]) - shot.uv[i]).squaredNorm();
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
// Step 4: joint refinement of intrinsics, free distortion coefficients and
// every shot's cam_from_ref by Ceres's Levenberg-Marquardt, with exact
// Jacobians (autodiff through the templated ProjectToPixel).

// Reprojection residuals of one shot, ProjectToPixel(cam_from_ref * X) - uv
// [px], two per point (u, v), over the parameter blocks
//   intrinsics(4)  distortion(14)  cam_from_ref_q(4)  cam_from_ref_t(3)
// (opencv_model.h order; the rotation a unit quaternion in Eigen order
// x y z w; the translation in metres).
struct ShotReprojection {
  const Shot* shot = nullptr;

  template <typename T>
  bool operator()(const T* intrinsics, const T* distortion, const T* cam_from_ref_q,
                  const T* cam_from_ref_t, T* residuals) const {
    const RigidT<T> cam_from_ref = PoseFromBlocks(cam_from_ref_q, cam_from_ref_t);
    // The camera's formula with its tilt matrix, which depends on the
    // distortion block only, formed once per shot (opencv_model.h).
    T tilt[9];
    TiltMatrix(distortion[kTauX], distortion[kTauY], tilt);
    for (size_t i = 0; i < shot->X.size(); ++i) {
      // Jet times double: the reference point carries no derivative.
      const Vec3<T> x_cam = cam_from_ref.R * shot->X[i] + cam_from_ref.t;
      T pixel[2];
      // Behind the camera: the evaluation fails and Ceres rejects the step.
      if (!ProjectWithTiltMatrix(intrinsics, distortion, tilt, x_cam.data(), pixel)) {
        return false;
      }
      residuals[2 * i + 0] = pixel[0] - T(shot->uv[i].x());
      residuals[2 * i + 1] = pixel[1] - T(shot->uv[i].y());
    }
    return true;
  }
};

constexpr int kQuaternionSize = 4;
constexpr int kTranslationSize = 3;

// The one place a shot's cost function is made (the final per-shot RMS
// evaluates the same functor in double).
ceres::CostFunction* MakeShotCost(const Shot& shot) {
  return new ceres::AutoDiffCostFunction<ShotReprojection, ceres::DYNAMIC, kNumIntrinsics,
                                         kNumDistortion, kQuaternionSize, kTranslationSize>(
      new ShotReprojection{&shot}, 2 * static_cast<int>(shot.X.size()));
}

// The refinement's parameter blocks; Ceres optimises this memory.
struct State {
  struct Pose {
    std::array<double, kQuaternionSize> q{};   // cam_from_ref rotation, x y z w
    std::array<double, kTranslationSize> t{};  // cam_from_ref translation [m]
  };
  std::array<double, kNumIntrinsics> intrinsics{};
  std::array<double, kNumDistortion> distortion{};
  std::vector<Pose> cam_from_ref;  // per shot

  static Pose ToBlocks(const Rigid3& cam_from_ref) {
    Pose p;
    Eigen::Map<Eigen::Quaterniond>(p.q.data()) = Eigen::Quaterniond(cam_from_ref.rotation);
    Eigen::Map<Eigen::Quaterniond>(p.q.data()).normalize();
    Eigen::Map<Eigen::Vector3d>(p.t.data()) = cam_from_ref.translation;
    return p;
  }
  Rigid3 CamFromRef(size_t k) const {
    const RigidT<double> pose = PoseFromBlocks(cam_from_ref[k].q.data(), cam_from_ref[k].t.data());
    return {pose.R, pose.t};
  }
};

// Ceres's tolerances are relative; CalibrateViewsOptions::rms_tolerance_px is
// an absolute RMS [px]. Stops (converged) once `in_a_row` accepted steps in a
// row have each improved sqrt(mean(du^2 + dv^2)) by less, and gives up (not
// converged) once no damping up to 1e16 (trust region radius 1e-16) gives
// descent, where Ceres would go on to its own limit of 1e-32.
class RmsTolerance : public ceres::IterationCallback {
 public:
  RmsTolerance(int num_points, double tolerance_px, int in_a_row)
      : num_points_(num_points), tolerance_px_(tolerance_px), in_a_row_(in_a_row) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    trust_region_radius_ = s.trust_region_radius;
    if (s.trust_region_radius < 1e-16) return ceres::SOLVER_ABORT;
    if (s.iteration == 0 || !s.step_is_successful) return ceres::SOLVER_CONTINUE;
    // Ceres's cost is half the sum of squared residuals.
    const double before = std::sqrt(2.0 * (s.cost + s.cost_change) / num_points_);
    const double after = std::sqrt(2.0 * s.cost / num_points_);
    small_steps_ = before - after < tolerance_px_ ? small_steps_ + 1 : 0;
    return small_steps_ >= in_a_row_ ? ceres::SOLVER_TERMINATE_SUCCESSFULLY
                                     : ceres::SOLVER_CONTINUE;
  }
  double trust_region_radius() const { return trust_region_radius_; }

 private:
  int num_points_;
  double tolerance_px_;
  int in_a_row_;
  int small_steps_ = 0;
  double trust_region_radius_ = 0;
};

// Converged: Ceres met a tolerance or the RMS criterion within
// options.max_iterations (not converged: no step gave descent, or the
// iteration limit).
void Refine(const std::vector<Shot>& shots, const std::vector<int>& free,
            const CalibrateViewsOptions& options, int num_points, State* s, int* iterations,
            bool* converged) {
  ceres::Problem problem;
  for (size_t k = 0; k < shots.size(); ++k) {
    State::Pose& pose = s->cam_from_ref[k];
    problem.AddResidualBlock(MakeShotCost(shots[k]), nullptr, s->intrinsics.data(),
                             s->distortion.data(), pose.q.data(), pose.t.data());
    ParameterizeBlock(&problem, pose.q.data(), BlockKind::kQuaternion, kQuaternionSize, {});
  }
  // Disabled distortion groups stay exactly zero.
  std::vector<int> frozen;
  for (int i = 0; i < kNumDistortion; ++i) {
    if (std::find(free.begin(), free.end(), i) == free.end()) frozen.push_back(i);
  }
  const BlockKind distortion_kind = free.empty()     ? BlockKind::kConstant
                                    : frozen.empty() ? BlockKind::kFree
                                                     : BlockKind::kSubset;
  ParameterizeBlock(&problem, s->distortion.data(), distortion_kind, kNumDistortion, frozen);

  ceres::Solver::Options so;
  // OpenCV's start is close: begin near Gauss-Newton (failed steps shrink
  // the region fast). The damping must be able to fall below sigma_min^2
  // ~4e-17 of the scaled Jacobian of the rational model (below); Ceres's
  // default largest radius (1e16) would hold it above and turn Gauss-Newton
  // into a creep along k1..k6.
  so.initial_trust_region_radius = 1e16;
  so.max_trust_region_radius = 1e30;
  so.max_num_iterations = options.max_iterations;
  // Exact data reach ~1e-13 px; these only stop the solver once steps are
  // at rounding level (RmsTolerance usually stops it first).
  so.function_tolerance = 1e-14;
  so.parameter_tolerance = 1e-13;
  so.gradient_tolerance = 0.0;
  so.logging_type = ceres::SILENT;
  // The Schur complement over the camera block (the normal equations after
  // eliminating each shot's pose) is fast and, without the rational group,
  // as accurate as an orthogonal solve.
  so.linear_solver_type = ceres::DENSE_SCHUR;
  const bool rational = options.distortion.rational;
  // With the rational group, k1..k3 and k4..k6 are nearly redundant over an
  // image (smallest singular value of the scaled camera Jacobian ~7e-9 in
  // the tests' scene, cond(J) ~4e8): the normal equations square that beyond
  // double precision, and Schur steps stall at ~3e-12 px with k1 ~4e-6 off.
  // They only take the RMS down to where its improvements fall below
  // kSchurHandoverPx, far above the rounding floor (~1e-13 px) so that the
  // trust region still sees the cost decrease of the steps that follow;
  // the dense QR of the Jacobi-scaled Jacobian, an orthogonal solve,
  // finishes from there.
  constexpr double kSchurHandoverPx = 1e-6;
  RmsTolerance schur_tolerance(
      num_points,
      rational ? std::max(kSchurHandoverPx, options.rms_tolerance_px) : options.rms_tolerance_px,
      1);
  so.callbacks = {&schur_tolerance};
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  *iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
  if (rational && *iterations < options.max_iterations) {
    // The first QR step that no longer improves the RMS has reached the RMS
    // floor but not yet settled k1..k6 (k1 ~3e-7 off, ~1e-13 px in the
    // tests' scene); the full Gauss-Newton step after it has, so two small
    // steps in a row are required.
    so.linear_solver_type = ceres::DENSE_QR;
    so.max_num_iterations = options.max_iterations - *iterations;
    // Continue with the damping the Schur steps ended with: restarting at
    // 1e16 would creep along k1..k6 again.
    so.initial_trust_region_radius =
        std::max(so.initial_trust_region_radius, schur_tolerance.trust_region_radius());
    RmsTolerance qr_tolerance(num_points, options.rms_tolerance_px, 2);
    so.callbacks = {&qr_tolerance};
    ceres::Solve(so, &problem, &summary);
    *iterations += summary.num_successful_steps + summary.num_unsuccessful_steps;
  }
  *converged = summary.termination_type == ceres::CONVERGENCE ||
               summary.termination_type == ceres::USER_SUCCESS;
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
  if (threads < 1) msg << "threads must be >= 1, got " << threads << "; ";
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
      msg << "zoom " << out.zoom << FirstLine(pixels) << ": " << shots.size() << " usable shot(s) " << stage
          << ", at least min_shots = " << options.min_shots << " needed (" << all_shots.size()
          << " shot(s) in the input, " << out.excluded.size() << " excluded)";
      for (const ExcludedShot& e : out.excluded) msg << "; '" << e.shot << "': " << e.reason;
      throw std::invalid_argument(msg.str());
    }
  };
  require_shots("with enough points");

  // Steps 2 and 3: the OpenCV start that poses the most shots and then
  // reprojects best. With groups beyond OpenCV's default five coefficients
  // (rational, thin prism, tilt) the first two starts are always tried:
  // with the rational group OpenCV's 30 iterations end farther from the
  // minimum than with k1 k2 alone, from where step 4 converges (the tests'
  // scene: 0.0255 against 0.0176 px, and step 4 from the former stalls at
  // 4e-6 px). Within the five, the first start is OpenCV's own calibration
  // of the same model and is tried alone first (OpenCV's 13 sample photos:
  // 0.41 px, every shot posed; the k1 k2 start would cost as much again for
  // a start that step 4 does not need). The
  // others are tried only while no start poses every shot within
  // kGoodStartPx: they are for starts that fail, leave shots without a pose
  // or end far off (the full model's calibrateCamera can end in a wrong
  // minimum on a wide lens with the rational group), and the one without
  // distortion costs the most: its 30 iterations do not converge
  // (opencv_bench_side_by_side_benchmark times the whole calibration of
  // OpenCV's sample photos).
  constexpr double kGoodStartPx = 1.0;
  const OpenCvViews views = PlanarViews(shots, width, height, options);
  // One start and its poses, or nothing with *fails saying why.
  struct Tried {
    bool ok = false;
    Start start;
    std::string fails;
  };
  auto attempt = [&](int which) {
    Tried t;
    Init init;
    t.ok = OpenCvStart(views, which, options, &init, &t.fails);
    if (t.ok) t.start = PoseShots(init, shots);
    return t;
  };
  std::string failures;
  Start best;
  bool started = false;
  // The starts in rounds of one or two, the second of a pair on a thread of
  // its own with options.threads > 1; then chosen from in order, as one
  // after the other.
  const DistortionGroups& g = options.distortion;
  std::vector<std::vector<int>> rounds;
  int which = 0;
  if (!(g.rational || g.thin_prism || g.sensor_tilt)) rounds.push_back({which++});
  for (; which < kNumOpenCvStarts; which += 2) {
    rounds.push_back({which});
    if (which + 1 < kNumOpenCvStarts) rounds.back().push_back(which + 1);
  }
  for (const std::vector<int>& round : rounds) {
    std::vector<Tried> pair(round.size());
    {
      std::future<Tried> second;
      if (round.size() > 1 && options.threads > 1) {
        second = std::async(std::launch::async, attempt, round[1]);
      }
      pair[0] = attempt(round[0]);
      if (round.size() > 1) pair[1] = second.valid() ? second.get() : attempt(round[1]);
    }
    for (Tried& t : pair) {
      failures += t.fails;
      if (!t.ok) continue;
      if (!started || t.start.posed.size() > best.posed.size() ||
          (t.start.posed.size() == best.posed.size() && t.start.rms_px < best.rms_px)) {
        best = std::move(t.start);
      }
      started = true;
    }
    if (best.posed.size() == shots.size() && best.rms_px <= kGoodStartPx) break;
  }
  if (!started) {
    throw std::runtime_error("CalibrateViews: OpenCV initialisation failed:" + failures);
  }
  out.init_note = best.init.note + failures;
  out.opencv_rms_px = best.rms_px;
  for (const ExcludedShot& e : best.failed) out.excluded.push_back(e);
  {
    std::vector<Shot> posed;
    for (int k : best.posed) posed.push_back(std::move(shots[k]));
    shots = std::move(posed);
  }
  require_shots("with a pose");

  const std::vector<int> free = options.distortion.FreeCoefficients();
  const int num_camera = kNumIntrinsics + static_cast<int>(free.size());
  int num_points = 0;
  for (const Shot& shot : shots) num_points += static_cast<int>(shot.X.size());
  const int unknowns = num_camera + 6 * static_cast<int>(shots.size());
  if (2 * num_points <= unknowns) {
    std::ostringstream msg;
    msg << "zoom " << out.zoom << FirstLine(pixels) << ": " << num_points << " points give "
        << 2 * num_points << " equations for " << unknowns << " unknowns (" << num_camera
        << " camera parameters with distortion " << options.distortion.Names()
        << ", 6 per shot for " << shots.size() << " shots); more points are needed";
    throw std::invalid_argument(msg.str());
  }

  // Step 4.
  State state;
  state.intrinsics = best.init.intrinsics;
  // Disabled groups are exactly zero, whatever the initialisation did.
  for (int i : free) state.distortion[i] = best.init.distortion[i];
  for (const Rigid3& cam_from_ref : best.cam_from_ref) {
    state.cam_from_ref.push_back(State::ToBlocks(cam_from_ref));
  }
  Refine(shots, free, options, num_points, &state, &out.iterations, &out.converged);

  out.intrinsics = state.intrinsics;
  out.distortion = state.distortion;
  out.num_points = num_points;
  out.max_trusted_radius = MaxTrustedRadius(state.distortion.data());
  double total = 0;
  for (size_t k = 0; k < shots.size(); ++k) {
    const Shot& shot = shots[k];
    const Rigid3 cam_from_ref = state.CamFromRef(k);
    ShotPose pose;
    pose.shot = shot.id;
    pose.face = shot.face;
    pose.phi = shot.phi;
    pose.theta = shot.theta;
    pose.ref_from_cam = cam_from_ref.Inverse();
    pose.num_points = static_cast<int>(shot.X.size());
    std::vector<double> r(2 * shot.X.size());
    if (!ShotReprojection{&shot}(state.intrinsics.data(), state.distortion.data(),
                                 state.cam_from_ref[k].q.data(), state.cam_from_ref[k].t.data(),
                                 r.data())) {
      throw std::runtime_error("CalibrateViews: refinement put a point of shot '" + shot.id +
                               "' behind the camera");
    }
    double sum = 0;
    for (double v : r) sum += v * v;
    for (const Eigen::Vector3d& X : shot.X) {
      const Eigen::Vector3d x_cam = cam_from_ref * X;
      if (x_cam.head<2>().norm() / x_cam.z() >= out.max_trusted_radius) {
        ++out.points_beyond_trusted_radius;
      }
    }
    pose.rms_px = std::sqrt(sum / pose.num_points);
    total += sum;
    out.shots.push_back(pose);
  }
  out.rms_px = std::sqrt(total / num_points);
  return out;
}

}  // namespace rtscalib

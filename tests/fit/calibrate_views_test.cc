#include "libcalib/fit/calibrate_views.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "libcalib/model/targets.h"

namespace rtscalib {
namespace {

// Exact-projection tests: pixels are ProjectToPixel of known corners, so the
// refinement must reach the truth up to rounding and conditioning. Tolerances:
//   rms:        1e-9 px   (rounding of pixel values ~1e3 is ~1e-13 px)
//   intrinsics: 1e-6 px   (conditioning of fx vs. depth and of cx vs. rotation
//                          amplifies the rounding floor by < 1e7)
//   distortion: 1e-8      (coefficients O(0.1), same amplification)
//   poses:      1e-9 rad, 1e-9 m
constexpr double kExactRmsPx = 1e-9;
constexpr double kExactIntrinsicsPx = 1e-6;
constexpr double kExactDistortion = 1e-8;
constexpr double kExactPose = 1e-9;

constexpr int kWidth = 1280;
constexpr int kHeight = 960;

// A board of 6 x 8 tags (1.17 m x 0.87 m) centred at `centre`, facing the
// viewer and turned by (tilt_x, tilt_y) about its own axes, so that the boards
// of a scene are not coplanar.
TagBoard FacingBoard(const Eigen::Vector3d& centre, const Eigen::Vector3d& viewer, double tilt_x,
                     double tilt_y, int first_id) {
  TagBoard b;
  b.rows = 6;
  b.cols = 8;
  b.tag_size = 0.12;
  b.spacing = 0.03;
  b.first_id = first_id;
  const Eigen::Vector3d up(0, 0, 1);
  const Eigen::Vector3d z = (centre - viewer).normalized();  // into the board
  const Eigen::Vector3d y = (-up + up.dot(z) * z).normalized();
  Eigen::Matrix3d r;
  r << y.cross(z), y, z;
  b.ref_from_board.rotation = r * Rx(tilt_x) * Ry(tilt_y);
  const double w = b.cols * b.tag_size + (b.cols - 1) * b.spacing;
  const double h = b.rows * b.tag_size + (b.rows - 1) * b.spacing;
  b.ref_from_board.translation =
      centre - b.ref_from_board.rotation * Eigen::Vector3d(w / 2, h / 2, 0);
  return b;
}

TargetScene FiveBoardScene() {
  const Eigen::Vector3d o = Eigen::Vector3d::Zero();
  TargetScene scene;
  scene.boards.push_back(FacingBoard({0.0, 2.5, 0.0}, o, 0.3, -0.2, 0));
  scene.boards.push_back(FacingBoard({1.8, 1.8, 0.4}, o, -0.25, 0.3, 100));
  scene.boards.push_back(FacingBoard({-1.8, 1.8, -0.3}, o, 0.2, 0.35, 200));
  scene.boards.push_back(FacingBoard({2.5, -0.3, 0.2}, o, -0.3, -0.3, 300));
  scene.boards.push_back(FacingBoard({-0.5, -2.6, 0.5}, o, 0.35, 0.1, 400));
  return scene;
}

struct Truth {
  std::array<double, kNumIntrinsics> intrinsics{1000, 1003, 645, 478};
  std::array<double, kNumDistortion> distortion{};
  std::vector<std::string> shots;
  std::vector<Rigid3> ref_from_cam;
};

// Camera looking from `position` at `aim`, image y down, rolled about its axis.
Rigid3 LookAt(const Eigen::Vector3d& position, const Eigen::Vector3d& aim, double roll) {
  const Eigen::Vector3d up(0, 0, 1);
  const Eigen::Vector3d z = (aim - position).normalized();
  const Eigen::Vector3d y = (-up + up.dot(z) * z).normalized();
  Eigen::Matrix3d r;
  r << y.cross(z), y, z;
  return {r * Rz(roll), position};
}

// Shots from near the origin (a total station's camera), `per_board` per board
// aimed around its centre so that its corners land all over the image, every
// third one upside down (a face-2 image); plus shots between neighbouring
// boards, which see two non-coplanar boards at once.
std::vector<PixelObservation> Observe(const TargetScene& scene, Truth* truth, int per_board,
                                      double noise_px, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  std::normal_distribution<double> noise(0, noise_px);
  std::vector<std::pair<Eigen::Vector3d, double>> aims;  // aim point, roll
  for (size_t b = 0; b < scene.boards.size(); ++b) {
    const Eigen::Vector3d c = scene.boards[b].CentreInRef();
    for (int j = 0; j < per_board; ++j) {
      aims.push_back({c + Eigen::Vector3d(0.6 * u(rng), 0.6 * u(rng), 0.45 * u(rng)),
                      (j % 3 == 2 ? M_PI : 0.0) + 0.05 * u(rng)});
    }
  }
  for (size_t b = 0; b + 1 < std::min<size_t>(3, scene.boards.size()); ++b) {
    aims.push_back(
        {0.5 * (scene.boards[b].CentreInRef() + scene.boards[b + 1].CentreInRef()), 0.0});
  }
  std::vector<PixelObservation> out;
  for (size_t s = 0; s < aims.size(); ++s) {
    const Eigen::Vector3d position(0.05 * u(rng), 0.05 * u(rng), 0.05 * u(rng));
    const Rigid3 ref_from_cam = LookAt(position, aims[s].first, aims[s].second);
    const Rigid3 cam_from_ref = ref_from_cam.Inverse();
    const std::string id = "shot" + std::to_string(s);
    truth->shots.push_back(id);
    truth->ref_from_cam.push_back(ref_from_cam);
    for (const TagBoard& board : scene.boards) {
      // Only the printed side is visible: the camera looks along the board's +z.
      if ((board.CentreInRef() - position).dot(board.ref_from_board.rotation.col(2)) <= 0) continue;
      for (int i = 0; i < board.NumTags(); ++i) {
        const auto corners = board.CornersInBoard(i);
        for (int k = 0; k < 4; ++k) {
          const Eigen::Vector3d X = board.ref_from_board * corners[k];
          const Eigen::Vector3d Xc = cam_from_ref * X;
          if (Xc.z() < 0.1 || Xc.head<2>().norm() / Xc.z() > 1.0) continue;
          double uv[2];
          if (!ProjectToPixel(truth->intrinsics.data(), truth->distortion.data(), Xc.data(), uv))
            continue;
          if (uv[0] < 0 || uv[0] > kWidth - 1 || uv[1] < 0 || uv[1] > kHeight - 1) continue;
          PixelObservation p;
          p.shot = id;
          p.face = std::abs(aims[s].second) > 1 ? 2 : 1;
          p.phi = 0.1 * s;
          p.theta = 1.5;
          p.target = board.first_id + i;
          p.corner = k;
          p.X = X;
          p.uv = Eigen::Vector2d(uv[0] + noise(rng), uv[1] + noise(rng));
          out.push_back(p);
        }
      }
    }
  }
  return out;
}

void ExpectPosesMatch(const ViewsCalibration& cal, const Truth& truth, double tol) {
  for (const ShotPose& pose : cal.shots) {
    const auto it = std::find(truth.shots.begin(), truth.shots.end(), pose.shot);
    ASSERT_NE(it, truth.shots.end());
    const Rigid3& t = truth.ref_from_cam[it - truth.shots.begin()];
    EXPECT_LT((pose.ref_from_cam.rotation - t.rotation).norm(), tol) << pose.shot;
    EXPECT_LT((pose.ref_from_cam.translation - t.translation).norm(), tol) << pose.shot;
  }
}

// Largest pixel difference between two cameras over a grid of camera points
// whose images cover the image.
double MaxMapDifference(const ViewsCalibration& cal, const Truth& truth) {
  double worst = 0;
  for (int i = 0; i <= 32; ++i) {
    for (int j = 0; j <= 24; ++j) {
      const double px[2] = {(kWidth - 1) * i / 32.0, (kHeight - 1) * j / 24.0};
      double ray[3], back[2];
      if (!PixelToRay(truth.intrinsics.data(), truth.distortion.data(), px, ray)) continue;
      if (!ProjectToPixel(cal.intrinsics.data(), cal.distortion.data(), ray, back)) return 1e9;
      worst = std::max(worst, std::hypot(back[0] - px[0], back[1] - px[1]));
    }
  }
  return worst;
}

void PrintFigures(const char* name, const ViewsCalibration& cal) {
  std::printf(
      "[ figures  ] %s: %zu shots, %d points, OpenCV start %.3g px, refined %.3g px in %d "
      "iterations (%s)\n",
      name, cal.shots.size(), cal.num_points, cal.opencv_rms_px, cal.rms_px, cal.iterations,
      cal.init_note.c_str());
}

TEST(CalibrateViews, RecoversRadialAndTangentialDistortionFromExactPixels) {
  Truth truth;
  truth.distortion[kK1] = -0.12;
  truth.distortion[kK2] = 0.05;
  truth.distortion[kK3] = -0.01;
  truth.distortion[kP1] = 8e-4;
  truth.distortion[kP2] = -5e-4;
  const auto pixels = Observe(FiveBoardScene(), &truth, 4, 0.0, 1);
  CalibrateViewsOptions options;
  options.distortion.radial = true;
  options.distortion.tangential = true;
  const ViewsCalibration cal = CalibrateViews(pixels, kWidth, kHeight, options);
  PrintFigures("radial+tangential", cal);
  EXPECT_TRUE(cal.converged);
  EXPECT_TRUE(cal.excluded.empty());
  EXPECT_EQ(cal.shots.size(), truth.shots.size());
  EXPECT_EQ(cal.num_points, static_cast<int>(pixels.size()));
  EXPECT_LT(cal.rms_px, kExactRmsPx);
  for (int i = 0; i < kNumIntrinsics; ++i) {
    EXPECT_NEAR(cal.intrinsics[i], truth.intrinsics[i], kExactIntrinsicsPx) << i;
  }
  for (int i = 0; i < kNumDistortion; ++i) {
    EXPECT_NEAR(cal.distortion[i], truth.distortion[i], kExactDistortion) << i;
  }
  ExpectPosesMatch(cal, truth, kExactPose);
  EXPECT_EQ(cal.points_beyond_trusted_radius, 0);
  EXPECT_GT(cal.max_trusted_radius, 1.0);
}

TEST(CalibrateViews, RecoversPinholeWithoutDistortion) {
  Truth truth;
  const auto pixels = Observe(FiveBoardScene(), &truth, 3, 0.0, 2);
  CalibrateViewsOptions options;
  options.distortion.radial = false;
  const ViewsCalibration cal = CalibrateViews(pixels, kWidth, kHeight, options);
  PrintFigures("none", cal);
  EXPECT_LT(cal.rms_px, kExactRmsPx);
  for (int i = 0; i < kNumIntrinsics; ++i) {
    EXPECT_NEAR(cal.intrinsics[i], truth.intrinsics[i], kExactIntrinsicsPx) << i;
  }
  for (double d : cal.distortion) EXPECT_EQ(d, 0.0);
  ExpectPosesMatch(cal, truth, kExactPose);
}

// Radial plus each other group in turn, truth containing exactly those groups.
TEST(CalibrateViews, RecoversEachDistortionGroup) {
  struct Case {
    const char* name;
    DistortionGroups groups;
    std::vector<std::pair<int, double>> coefficients;
  };
  DistortionGroups radial, tangential, rational, prism, tilt;
  tangential.tangential = true;
  rational.rational = true;
  prism.thin_prism = true;
  tilt.sensor_tilt = true;
  const std::vector<std::pair<int, double>> base = {{kK1, -0.1}, {kK2, 0.03}};
  std::vector<Case> cases = {
      {"radial", radial, base},
      {"radial+tangential", tangential, {{kP1, 1e-3}, {kP2, -6e-4}}},
      {"radial+rational", rational, {{kK4, 0.08}, {kK5, -0.02}, {kK6, 0.005}}},
      {"radial+thin_prism", prism, {{kS1, 1e-3}, {kS2, -5e-4}, {kS3, -8e-4}, {kS4, 3e-4}}},
      {"radial+sensor_tilt", tilt, {{kTauX, 0.01}, {kTauY, -0.015}}},
  };
  for (Case& c : cases) {
    SCOPED_TRACE(c.name);
    Truth truth;
    for (const auto& [i, v] : base) truth.distortion[i] = v;
    for (const auto& [i, v] : c.coefficients) truth.distortion[i] = v;
    const auto pixels = Observe(FiveBoardScene(), &truth, 4, 0.0, 3);
    CalibrateViewsOptions options;
    options.distortion = c.groups;
    options.distortion.radial = true;
    const ViewsCalibration cal = CalibrateViews(pixels, kWidth, kHeight, options);
    PrintFigures(c.name, cal);
    EXPECT_TRUE(cal.converged);
    EXPECT_LT(cal.rms_px, kExactRmsPx);
    EXPECT_LT(MaxMapDifference(cal, truth), 1e-8);
    for (int i = 0; i < kNumIntrinsics; ++i) {
      EXPECT_NEAR(cal.intrinsics[i], truth.intrinsics[i], kExactIntrinsicsPx) << i;
    }
    // Also for the rational model, whose k1..k3 and k4..k6 are nearly
    // redundant over an image (smallest scaled singular value ~7e-9): exact
    // data and an orthogonal solve pin k1 and k4 to ~1.4e-9.
    for (int i = 0; i < kNumDistortion; ++i) {
      EXPECT_NEAR(cal.distortion[i], truth.distortion[i], kExactDistortion) << i;
    }
    ExpectPosesMatch(cal, truth, kExactPose);
  }
}

TEST(CalibrateViews, RecoversEveryGroupAtOnce) {
  Truth truth;
  truth.distortion = {-0.1,  0.03, 1e-3,  -6e-4, -0.005, 0.05, -0.01,
                      0.002, 1e-3, -5e-4, -8e-4, 3e-4,   0.01, -0.015};
  const auto pixels = Observe(FiveBoardScene(), &truth, 5, 0.0, 4);
  CalibrateViewsOptions options;
  options.distortion = {true, true, true, true, true};
  const ViewsCalibration cal = CalibrateViews(pixels, kWidth, kHeight, options);
  PrintFigures("all groups", cal);
  EXPECT_TRUE(cal.converged);
  EXPECT_LT(cal.rms_px, kExactRmsPx);
  EXPECT_LT(MaxMapDifference(cal, truth), 1e-8);
  for (int i = 0; i < kNumIntrinsics; ++i) {
    EXPECT_NEAR(cal.intrinsics[i], truth.intrinsics[i], kExactIntrinsicsPx) << i;
  }
  for (int i = 0; i < kNumDistortion; ++i) {
    EXPECT_NEAR(cal.distortion[i], truth.distortion[i], kExactDistortion) << i;
  }
  ExpectPosesMatch(cal, truth, kExactPose);
}

// One board only: every shot planar (Zhang's setting).
TEST(CalibrateViews, RecoversFromASingleBoard) {
  Truth truth;
  truth.distortion[kK1] = -0.08;
  TargetScene scene;
  scene.boards.push_back(FacingBoard({0.0, 2.0, 0.0}, Eigen::Vector3d::Zero(), 0.2, -0.1, 0));
  // A board seen from one point has a weak focal length; move the camera.
  std::vector<PixelObservation> pixels;
  Truth t1 = truth;
  pixels = Observe(scene, &t1, 8, 0.0, 5);
  const ViewsCalibration cal = CalibrateViews(pixels, kWidth, kHeight);
  PrintFigures("single board", cal);
  EXPECT_LT(cal.rms_px, kExactRmsPx);
  for (int i = 0; i < kNumIntrinsics; ++i)
    EXPECT_NEAR(cal.intrinsics[i], truth.intrinsics[i], 1e-5);
  EXPECT_NEAR(cal.distortion[kK1], truth.distortion[kK1], 1e-8);
}

// Gaussian pixel noise: the RMS estimates the noise (sqrt(2) sigma for two
// coordinates, times sqrt(1 - unknowns / equations) ~ 0.985 here) and the
// intrinsics stay within 1 px (seen: ~0.4 px; with every shot's translation
// free, focal length trades off against depth at this 65 degree field of view).
TEST(CalibrateViews, NoisyPixels) {
  Truth truth;
  truth.distortion[kK1] = -0.12;
  truth.distortion[kK2] = 0.05;
  const double sigma = 0.3;
  const auto pixels = Observe(FiveBoardScene(), &truth, 4, sigma, 6);
  const ViewsCalibration cal = CalibrateViews(pixels, kWidth, kHeight);
  PrintFigures("noise 0.3 px", cal);
  EXPECT_TRUE(cal.converged);
  EXPECT_NEAR(cal.rms_px, std::sqrt(2.0) * sigma, 0.05);
  for (int i = 0; i < kNumIntrinsics; ++i)
    EXPECT_NEAR(cal.intrinsics[i], truth.intrinsics[i], 1.0) << i;
  std::printf(
      "[ figures  ] noise 0.3 px: fx fy cx cy errors %.3f %.3f %.3f %.3f px, k1 k2 errors "
      "%.2g %.2g\n",
      cal.intrinsics[0] - truth.intrinsics[0], cal.intrinsics[1] - truth.intrinsics[1],
      cal.intrinsics[2] - truth.intrinsics[2], cal.intrinsics[3] - truth.intrinsics[3],
      cal.distortion[kK1] - truth.distortion[kK1], cal.distortion[kK2] - truth.distortion[kK2]);
}

// OpenCV's starts made two at a time give the start made one after the
// other: the same choice, the same result to the last bit.
TEST(CalibrateViews, StartsSideBySideChooseTheSameStart) {
  Truth truth;
  truth.distortion[kK1] = -0.1;
  truth.distortion[kK2] = 0.03;
  const auto pixels = Observe(FiveBoardScene(), &truth, 4, 0.2, 7);
  const CalibrateViewsOptions one;
  CalibrateViewsOptions two = one;
  two.threads = 2;
  const ViewsCalibration a = CalibrateViews(pixels, kWidth, kHeight, one);
  const ViewsCalibration b = CalibrateViews(pixels, kWidth, kHeight, two);
  EXPECT_EQ(a.init_note, b.init_note);
  EXPECT_EQ(a.opencv_rms_px, b.opencv_rms_px);
  EXPECT_EQ(a.rms_px, b.rms_px);
  EXPECT_EQ(a.intrinsics, b.intrinsics);
  EXPECT_EQ(a.distortion, b.distortion);
  CalibrateViewsOptions none = one;
  none.threads = 0;
  EXPECT_NE(none.Check().find("threads must be >= 1, got 0"), std::string::npos) << none.Check();
}

// ---------------------------------------------------------------------------
// Input errors.

std::string ErrorOf(const std::vector<PixelObservation>& pixels,
                    const CalibrateViewsOptions& o = {}) {
  try {
    CalibrateViews(pixels, kWidth, kHeight, o);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(CalibrateViews, TooFewShotsIsAnError) {
  Truth truth;
  auto pixels = Observe(FiveBoardScene(), &truth, 1, 0.0, 7);
  std::vector<PixelObservation> one_shot;
  for (const PixelObservation& p : pixels) {
    if (p.shot == "shot0") one_shot.push_back(p);
  }
  const std::string msg = ErrorOf(one_shot);
  EXPECT_NE(msg.find("1 usable shot(s)"), std::string::npos) << msg;
  EXPECT_NE(msg.find("min_shots = 2"), std::string::npos) << msg;
  CalibrateViewsOptions single;
  single.min_shots = 1;
  // Allowed, the shot count is no longer the complaint (one planar view
  // leaves the principal point weak, but that is for the caller to judge).
  EXPECT_EQ(ErrorOf(one_shot, single).find("usable shot"), std::string::npos);
}

TEST(CalibrateViews, ShotsWithTooFewPointsAreExcludedAndReported) {
  Truth truth;
  auto pixels = Observe(FiveBoardScene(), &truth, 3, 0.0, 8);
  PixelObservation stray = pixels.front();
  stray.shot = "stray";
  pixels.push_back(stray);
  pixels.push_back(stray);
  const ViewsCalibration cal = CalibrateViews(pixels, kWidth, kHeight);
  ASSERT_EQ(cal.excluded.size(), 1u);
  EXPECT_EQ(cal.excluded[0].shot, "stray");
  EXPECT_EQ(cal.excluded[0].num_points, 2);
  EXPECT_NE(cal.excluded[0].reason.find("min_points_per_shot"), std::string::npos);
  EXPECT_EQ(cal.num_points, static_cast<int>(pixels.size()) - 2);
}

TEST(CalibrateViews, TooFewPointsForTheUnknownsIsAnError) {
  // 2 shots x 4 points = 16 equations < 4 + 14 + 12 unknowns.
  Truth truth;
  auto pixels = Observe(FiveBoardScene(), &truth, 2, 0.0, 9);
  std::vector<PixelObservation> few;
  std::map<std::string, int> count;
  for (const PixelObservation& p : pixels) {
    if (count.size() < 2 || count.count(p.shot)) {
      if (count[p.shot] < 4) {
        few.push_back(p);
        ++count[p.shot];
      }
    }
  }
  CalibrateViewsOptions o;
  o.min_points_per_plane = 4;
  o.distortion = {true, true, true, true, true};
  const std::string msg = ErrorOf(few, o);
  EXPECT_NE(msg.find("unknowns"), std::string::npos) << msg;
}

TEST(CalibrateViews, MixedZoomLevelsAndInconsistentShotsAreErrors) {
  Truth truth;
  auto pixels = Observe(FiveBoardScene(), &truth, 2, 0.0, 10);
  auto mixed = pixels;
  mixed.back().zoom = 3;
  mixed.back().line = 77;
  std::string msg = ErrorOf(mixed);
  EXPECT_NE(msg.find("zoom 3"), std::string::npos) << msg;
  EXPECT_NE(msg.find("line 77"), std::string::npos) << msg;

  auto inconsistent = pixels;
  inconsistent.back().theta += 0.01;
  msg = ErrorOf(inconsistent);
  EXPECT_NE(msg.find("same face, phi and theta"), std::string::npos) << msg;

  EXPECT_NE(ErrorOf({}).find("no pixel observations"), std::string::npos);
  CalibrateViewsOptions bad;
  bad.min_points_per_shot = 2;
  bad.plane_tolerance_m = -1;
  msg = ErrorOf(pixels, bad);
  EXPECT_NE(msg.find("min_points_per_shot"), std::string::npos) << msg;
  EXPECT_NE(msg.find("plane_tolerance_m"), std::string::npos) << msg;
}

// Scattered (non-coplanar) points: nothing for cv::initCameraMatrix2D.
TEST(CalibrateViews, NoPlanarSubsetIsAnError) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  const Truth truth;
  std::vector<PixelObservation> pixels;
  for (int s = 0; s < 3; ++s) {
    for (int i = 0; i < 30; ++i) {
      PixelObservation p;
      p.shot = "s" + std::to_string(s);
      p.target = i;  // one point per target: no tag planes
      const Eigen::Vector3d Xc(u(rng), 0.7 * u(rng), 3 + u(rng));
      p.X = Xc + Eigen::Vector3d(0.1 * s, 0, 0);
      double uv[2];
      ASSERT_TRUE(ProjectToPixel(truth.intrinsics.data(), truth.distortion.data(), Xc.data(), uv));
      p.uv = {uv[0], uv[1]};
      pixels.push_back(p);
    }
  }
  const std::string msg = ErrorOf(pixels);
  EXPECT_NE(msg.find("coplanar"), std::string::npos) << msg;
}

}  // namespace
}  // namespace rtscalib

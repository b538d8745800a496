// Rendered-and-detected corners against exact projections. The renderer's own
// geometry is tested in scene_renderer_test.cc, the exact projections in
// tests/camera, the detector on images synthesized without the renderer in
// tests/detect.
#include "detect/detector.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "libcalib/camera/opencv_model.h"
#include "render/scene_renderer.h"
#include "tests/render/render_fixture.h"

namespace rtscalib::render {
namespace {

using detect::DetectorOptions;
using detect::TagDetection;
using detect::TagDetector;
using testing::AimAt;
using testing::EnsureDisplay;
using testing::FrontBoard;
using testing::SceneOf;
using testing::TestCamera;

struct Errors {
  double sum_sq = 0;
  double max = 0;
  int corners = 0;
  int tags = 0;
  double Rms() const { return corners > 0 ? std::sqrt(sum_sq / corners) : 0.0; }
};

// Compares every detection with the exact projections of its tag's corners,
// in TargetCorner order.
void Accumulate(const std::vector<TagDetection>& detections, const TargetScene& scene,
                const Rigid3& ref_from_cam, const CameraTool& cam, Errors* errors) {
  std::map<int, std::array<Eigen::Vector3d, 4>> corners;
  for (const TargetCorner& c : scene.AllCorners()) corners[c.target][c.corner] = c.X;
  const Rigid3 cam_from_ref = ref_from_cam.Inverse();
  for (const TagDetection& d : detections) {
    ASSERT_EQ(corners.count(d.id), 1u) << "unknown id " << d.id;
    EXPECT_EQ(d.refinement, detect::CornerRefinement::kEdges) << "tag " << d.id;
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d p = cam_from_ref * corners[d.id][k];
      double px[2];
      ASSERT_TRUE(ProjectToPixel(cam.intrinsics.data(), cam.distortion.data(), p.data(), px));
      const double e = (d.corners[k] - Eigen::Vector2d(px[0], px[1])).norm();
      errors->sum_sq += e * e;
      errors->max = std::max(errors->max, e);
      ++errors->corners;
    }
    ++errors->tags;
  }
}

TEST(DetectorTest, CornerOrderIsTargetCornerOrder) {
  EnsureDisplay();
  const TargetScene scene = SceneOf(FrontBoard());
  SceneRenderer renderer(scene);
  const CameraTool cam = TestCamera(false);
  // Upright and rolled by 90 degrees: the order follows the tag, not the image.
  for (double roll : {0.0, M_PI / 2}) {
    const Rigid3 pose = AimAt(Eigen::Vector3d::Zero(), scene.boards[0].CentreInRef(),
                              cam.intrinsics[2], cam.intrinsics[3], roll, cam);
    TagDetector detector;
    const std::vector<TagDetection> detections = detector.Detect(renderer.Render(pose, cam));
    ASSERT_EQ(detections.size(), 12u);
    Errors errors;
    Accumulate(detections, scene, pose, cam, &errors);
    // A wrong order would be a whole tag edge (40 px) off.
    EXPECT_LT(errors.max, 0.05) << "roll " << roll;
  }
}

// The accuracy requirement: RMS <= 0.1 px with lens distortion on, over shots
// that put the board all over the image, rolled and tilted.
TEST(DetectorTest, RefinedCornersMatchExactProjectionsWithDistortion) {
  EnsureDisplay();
  const TargetScene scene = SceneOf(FrontBoard(5, 7, 2.0));
  SceneRenderer renderer(scene);
  const CameraTool cam = TestCamera(true);
  TagDetector detector;
  Errors errors, apriltag;
  int shots = 0;
  const Eigen::Vector3d target = scene.boards[0].CentreInRef();
  for (double u : {260.0, 640.0, 1020.0}) {
    for (double v : {230.0, 480.0, 730.0}) {
      // Off to the side (a tilted view of the board) and rolled.
      const Eigen::Vector3d centre(0.3 * (u - 640) / 380, -0.2 * (v - 480) / 250, 0.0);
      const Rigid3 pose = AimAt(centre, target, u, v, 0.15 * (shots % 3 - 1), cam);
      const std::vector<TagDetection> detections = detector.Detect(renderer.Render(pose, cam));
      EXPECT_EQ(detections.size(), 35u) << "shot at " << u << "," << v;
      Accumulate(detections, scene, pose, cam, &errors);
      std::vector<TagDetection> raw = detections;
      for (TagDetection& d : raw) d.corners = d.apriltag_corners;
      Accumulate(raw, scene, pose, cam, &apriltag);
      ++shots;
    }
  }
  ASSERT_EQ(errors.tags, 9 * 35);
  // Measured 0.015 px (docs/rendering.md); the requirement is 0.1 px.
  EXPECT_LE(errors.Rms(), 0.1);
  EXPECT_LE(errors.max, 0.2);
  // The refinement must beat libapriltag's own corners.
  EXPECT_LT(errors.Rms(), 0.5 * apriltag.Rms());
  RecordProperty("rms_px", std::to_string(errors.Rms()));
  std::printf("refined RMS %.4f px (max %.4f), libapriltag RMS %.4f px over %d corners\n",
              errors.Rms(), errors.max, apriltag.Rms(), errors.corners);
}

TEST(DetectorTest, AllFourteenDistortionCoefficients) {
  EnsureDisplay();
  const TargetScene scene = SceneOf(FrontBoard(4, 5, 2.0));
  SceneRenderer renderer(scene);
  CameraTool cam = TestCamera(false);
  // k1 k2 p1 p2 k3 k4 k5 k6 s1 s2 s3 s4 taux tauy: rational, thin prism and a
  // tilted sensor all move the picture by pixels at the rim.
  cam.distortion = {-0.08,  0.02, 2e-4,  -1e-4, 0.002, 0.01,  0.001,
                    0.0005, 1e-3, -1e-4, -1e-3, 1e-4,  0.002, -0.001};
  TagDetector detector;
  Errors errors;
  for (int i = 0; i < 4; ++i) {
    const Rigid3 pose = AimAt(Eigen::Vector3d(0.05 * i, 0, 0), scene.boards[0].CentreInRef(),
                              300.0 + 220 * i, 260.0 + 150 * i, -0.1 * i, cam);
    const std::vector<TagDetection> detections = detector.Detect(renderer.Render(pose, cam));
    EXPECT_EQ(detections.size(), 20u);
    Accumulate(detections, scene, pose, cam, &errors);
  }
  EXPECT_LE(errors.Rms(), 0.1);
  std::printf("14-coefficient RMS %.4f px (max %.4f) over %d corners\n", errors.Rms(), errors.max,
              errors.corners);
}

TEST(DetectorTest, NoiseAndBlurKeepSubPixelAccuracy) {
  EnsureDisplay();
  const TargetScene scene = SceneOf(FrontBoard(4, 5, 2.0));
  RenderOptions options;
  options.noise_sigma = 2.0;
  options.blur_sigma = 0.7;
  SceneRenderer renderer(scene, options);
  const CameraTool cam = TestCamera(true);
  TagDetector detector;
  Errors errors;
  for (int i = 0; i < 4; ++i) {
    const Rigid3 pose = AimAt(Eigen::Vector3d(0.1 * i, 0, 0), scene.boards[0].CentreInRef(),
                              400.0 + 150 * i, 350.0 + 80 * i, 0.1 * i, cam);
    const std::vector<TagDetection> detections = detector.Detect(renderer.Render(pose, cam, i));
    EXPECT_EQ(detections.size(), 20u);
    Accumulate(detections, scene, pose, cam, &errors);
  }
  EXPECT_LE(errors.Rms(), 0.1);
  std::printf("noisy RMS %.4f px (max %.4f) over %d corners\n", errors.Rms(), errors.max,
              errors.corners);
}

TEST(DetectorTest, OtherFamilies) {
  EnsureDisplay();
  for (const std::string family : {"tag25h9", "tag16h5", "tagStandard41h12"}) {
    TagBoard board = FrontBoard(2, 3, 1.5);
    board.family = family;
    board.spacing = family == "tagStandard41h12" ? 0.07 : 0.03;
    const TargetScene scene = SceneOf(board);
    SceneRenderer renderer(scene);
    const CameraTool cam = TestCamera(true);
    const Rigid3 pose = AimAt(Eigen::Vector3d(0.1, 0, 0), board.CentreInRef(), 700, 420, 0.2, cam);
    DetectorOptions options;
    options.families = {family};
    TagDetector detector(options);
    const std::vector<TagDetection> detections = detector.Detect(renderer.Render(pose, cam));
    EXPECT_EQ(detections.size(), 6u) << family;
    Errors errors;
    Accumulate(detections, scene, pose, cam, &errors);
    EXPECT_LE(errors.Rms(), 0.1) << family;
  }
}

}  // namespace
}  // namespace rtscalib::render

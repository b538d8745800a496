// Rendered-and-detected corners against exact projections. The renderer's own
// geometry is tested in scene_renderer_test.cc, the exact projections in
// tests/camera, the detector on images synthesized without the renderer in
// tests/detect.
#include "detect/detector.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "detect/board_growth.h"
#include "libcalib/camera/opencv_model.h"
#include "render/scene_renderer.h"
#include "render/tag_matching.h"
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

// Kalibr's AprilGrid as the renderer prints it (2-bit tags and the black
// squares that touch their corners, SPEC 7.2; 8 cm tags, Kalibr's
// tagSpacing 0.3), detected as data.shots detects it: libapriltag's pass
// for 2-bit borders, then the board grown from the tags found. Every tag of
// every shot (tilted, rolled, with lens distortion) is found and refined,
// its corners within the 1-bit boards' requirement above (RMS <= 0.1 px,
// no corner off by more than 0.2 px).
TEST(DetectorTest, AprilGridWithItsSquares) {
  EnsureDisplay();
  TagBoard board = FrontBoard(4, 5, 2.0);
  board.border_bits = 2;
  board.spacing = 0.3 * board.tag_size;
  board.ref_from_board.translation =
      Eigen::Vector3d(-board.Width() / 2, -board.Height() / 2, 2.0);
  const TargetScene scene = SceneOf(board);
  SceneRenderer renderer(scene);
  const CameraTool cam = TestCamera(true);
  DetectorOptions options;
  options.families = {detect::PrintedFamily{board.family, board.border_bits}};
  TagDetector detector(options);
  Errors errors;
  for (int i = 0; i < 4; ++i) {
    const Rigid3 pose = AimAt(Eigen::Vector3d(0.1 * i - 0.15, 0.05 * i, 0), board.CentreInRef(),
                              380.0 + 170 * i, 300.0 + 110 * i, 0.12 * i - 0.2, cam);
    const cv::Mat photo = renderer.Render(pose, cam);
    std::vector<TagDetection> detections = detector.Detect(photo);
    detect::GrowBoardTags(photo, board, &detector, &detections);
    std::vector<TagDetection> kept;
    for (const TagDetection& d : detections) {
      if (board.HasId(d.id) && d.refined()) kept.push_back(d);
    }
    EXPECT_EQ(kept.size(), 20u) << "shot " << i;
    Accumulate(kept, scene, pose, cam, &errors);
  }
  EXPECT_LE(errors.Rms(), 0.1);
  EXPECT_LE(errors.max, 0.2);
  std::printf("AprilGrid RMS %.4f px (max %.4f) over %d corners\n", errors.Rms(), errors.max,
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
    options.families = {detect::PrintedFamily{family}};
    TagDetector detector(options);
    const std::vector<TagDetection> detections = detector.Detect(renderer.Render(pose, cam));
    EXPECT_EQ(detections.size(), 6u) << family;
    Errors errors;
    Accumulate(detections, scene, pose, cam, &errors);
    EXPECT_LE(errors.Rms(), 0.1) << family;
  }
}

// Small tags at each of the demo's zoom levels (configs/zoom3.yaml: fx 1500,
// 3000 and 6000 px with their distortion; its 6 x 8 boards of 6 cm tag36h11
// 1.5 cm apart; supersample 2 and 1 grey level of noise): per zoom, four
// boards in one photo, at the distances that make their code bits 1.7, 2.2,
// 3.0 and 4.2 px. Whole-tag recall (tags with all four corners in the image,
// detected and refined) and the kept corners against their exact
// projections, per size class.
TEST(DetectorTest, SmallTagsAtEveryZoom) {
  EnsureDisplay();
  struct Zoom {
    double fx;
    double k1, k2, p1, p2;
  };
  const Zoom zooms[] = {{1500, -0.08, 0.05, 2e-4, -1e-4},
                        {3000, -0.04, 0.02, 1e-4, -5e-5},
                        {6000, -0.02, 0.01, 5e-5, -2e-5}};
  // Code bit [px] along a tag's shortest edge.
  struct SizeClass {
    double lo, hi;
    Errors errors;
  };
  std::vector<SizeClass> classes = {{1.5, 2.5, {}}, {2.5, 3.5, {}}, {3.5, 5.0, {}}};
  RenderOptions render;
  render.noise_sigma = 1.0;
  VisibilityOptions visibility;
  visibility.border_margin_px = 0;  // every tag wholly in the image counts
  visibility.min_bit_px = detect::DetectorOptions().min_pattern_bit_pixels;
  TagDetector detector;
  for (size_t z = 0; z < std::size(zooms); ++z) {
    CameraTool cam = TestCamera(false);
    cam.intrinsics = {zooms[z].fx, zooms[z].fx, 637.5, 481.5};
    cam.distortion[kK1] = zooms[z].k1;
    cam.distortion[kK2] = zooms[z].k2;
    cam.distortion[kP1] = zooms[z].p1;
    cam.distortion[kP2] = zooms[z].p2;
    // One board per image quadrant, centred 300 px and 200 px off the
    // centre, facing the camera.
    TargetScene scene;
    const double bits[] = {1.7, 2.2, 3.0, 4.2};
    for (int i = 0; i < 4; ++i) {
      TagBoard board;
      board.rows = 6;
      board.cols = 8;
      board.tag_size = 0.06;
      board.spacing = 0.015;
      board.first_id = 48 * i;
      const double distance = zooms[z].fx * board.tag_size / 8 / bits[i];
      const double w = board.cols * board.tag_size + (board.cols - 1) * board.spacing;
      const double h = board.rows * board.tag_size + (board.rows - 1) * board.spacing;
      const Eigen::Vector2d offset(i % 2 == 0 ? -300 : 300, i < 2 ? -200 : 200);
      const Eigen::Vector3d centre = distance * Eigen::Vector3d(offset.x() / zooms[z].fx,
                                                                offset.y() / zooms[z].fx, 1);
      board.ref_from_board.translation = centre - Eigen::Vector3d(w / 2, h / 2, 0);
      scene.boards.push_back(board);
    }
    SceneRenderer renderer(scene, render);
    // Turned a little and rolled, so that no edge runs along the pixel grid.
    const Rigid3 pose = AimAt(Eigen::Vector3d::Zero(), Eigen::Vector3d(0.01, -0.01, 1),
                              cam.intrinsics[2] + 20, cam.intrinsics[3] - 10, 0.2, cam);
    const std::vector<TagDetection> detections =
        detector.Detect(renderer.Render(pose, cam, z + 1));
    const std::vector<ExpectedTag> expected = ExpectTags(scene, pose, cam, visibility);
    std::map<int, const ExpectedTag*> by_id;
    for (const ExpectedTag& t : expected) by_id[t.id] = &t;
    ShotStats stats;
    for (const MatchedTag& m : MatchDetections(detections, expected, MatchOptions(), &stats)) {
      const ExpectedTag& t = *by_id.at(m.id);
      for (SizeClass& c : classes) {
        if (t.bit_px < c.lo || t.bit_px >= c.hi) continue;
        for (int k = 0; k < 4; ++k) {
          const double e = (m.uv[k] - t.uv[k]).norm();
          c.errors.sum_sq += e * e;
          c.errors.max = std::max(c.errors.max, e);
          ++c.errors.corners;
        }
        ++c.errors.tags;
      }
    }
    EXPECT_EQ(stats.mismatched, 0) << "zoom " << z;
    ASSERT_EQ(stats.expected, 4 * 48) << "zoom " << z << ": every tag wholly in the image";
    const double recall = static_cast<double>(stats.found) / stats.expected;
    std::printf(
        "zoom %zu (fx %.0f): %d of %d tags wholly in the image found and refined (%.1f %%)\n", z,
        zooms[z].fx, stats.found, stats.expected, 100 * recall);
    EXPECT_GE(recall, 0.95) << "zoom " << z;
  }
  for (const SizeClass& c : classes) {
    std::printf("%.1f-%.1f px per bit: %d tags, corner RMS %.4f px, max %.4f px\n", c.lo, c.hi,
                c.errors.tags, c.errors.Rms(), c.errors.max);
    ASSERT_GT(c.errors.tags, 100);
    // Measured 0.009-0.010 px in each class (the pattern fit below 2.5 px per
    // bit, the edges above); 0.05 px is half the accuracy requirement of
    // RefinedCornersMatchExactProjectionsWithDistortion and a third of what
    // libapriltag's own corners are off at these sizes (0.11-0.19 px).
    EXPECT_LT(c.errors.Rms(), 0.05) << c.lo << "-" << c.hi << " px per bit";
    EXPECT_LT(c.errors.max, 0.2) << c.lo << "-" << c.hi << " px per bit";
  }
}

}  // namespace
}  // namespace rtscalib::render

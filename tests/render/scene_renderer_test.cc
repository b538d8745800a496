// The renderer's geometry and image model (rendering only; detection is in
// detector_test.cc).
#include "render/scene_renderer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <opencv2/imgproc.hpp>

#include "libcalib/camera/opencv_model.h"
#include "tests/render/render_fixture.h"

namespace rtscalib::render {
namespace {

using testing::EnsureDisplay;
using testing::FrontBoard;
using testing::SceneOf;
using testing::TestCamera;

Eigen::Vector2d Project(const CameraTool& cam, const Rigid3& ref_from_cam,
                        const Eigen::Vector3d& x_ref) {
  const Eigen::Vector3d p = ref_from_cam.Inverse() * x_ref;
  double px[2];
  EXPECT_TRUE(ProjectToPixel(cam.intrinsics.data(), cam.distortion.data(), p.data(), px));
  return {px[0], px[1]};
}

TEST(OpenGlProjectionTest, PutsPointsAtOpenCvPixels) {
  // NDC -> GL window -> OpenCV pixel, for the matrix the renderer uses.
  const double fx = 1234.5, fy = 1230.25, cx = 611.3, cy = 397.8;
  const int w = 1280, h = 800;
  const Eigen::Matrix4d p = OpenGlProjection(fx, fy, cx, cy, w, h, 0.1, 100.0);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> xy(-1.0, 1.0), depth(0.2, 90.0);
  for (int i = 0; i < 100; ++i) {
    const Eigen::Vector3d cam(xy(rng), xy(rng), depth(rng));  // OpenCV camera frame
    const Eigen::Vector4d view(cam.x(), -cam.y(), -cam.z(), 1.0);
    const Eigen::Vector4d clip = p * view;
    const Eigen::Vector3d ndc = clip.head<3>() / clip.w();
    // GL: window x = (ndc + 1) w / 2 with pixel centres at i + 1/2, rows from
    // the bottom; OpenCV: centres at integers, rows from the top.
    const double u = (ndc.x() + 1) * w / 2 - 0.5;
    const double v = h - (ndc.y() + 1) * h / 2 - 0.5;
    EXPECT_NEAR(u, fx * cam.x() / cam.z() + cx, 1e-9);
    EXPECT_NEAR(v, fy * cam.y() / cam.z() + cy, 1e-9);
    EXPECT_GT(ndc.z(), -1 - 1e-12);
    EXPECT_LT(ndc.z(), 1 + 1e-12);
  }
  // Depth range maps to [-1, 1].
  const Eigen::Vector4d near_pt = p * Eigen::Vector4d(0, 0, -0.1, 1);
  const Eigen::Vector4d far_pt = p * Eigen::Vector4d(0, 0, -100.0, 1);
  EXPECT_NEAR(near_pt.z() / near_pt.w(), -1.0, 1e-12);
  EXPECT_NEAR(far_pt.z() / far_pt.w(), 1.0, 1e-12);
}

// The left edge of tag 0 measured in the image by the area of its strips
// (sum over whole pixels of a row = exact area for an area-sampled image)
// against the exact projection. Flat lighting: ink and paper levels are known.
double LeftEdgeError(const cv::Mat& img, const CameraTool& cam, const TagBoard& board,
                     const RenderOptions& options) {
  const auto corners = board.CornersInBoard(0);
  const Eigen::Vector2d bottom = Project(cam, Rigid3(), board.ref_from_board * corners[0]);
  const Eigen::Vector2d top = Project(cam, Rigid3(), board.ref_from_board * corners[3]);
  double sum_err = 0;
  int n = 0;
  for (int v = static_cast<int>(top.y()) + 6; v < bottom.y() - 6; ++v) {
    const double t = (v - top.y()) / (bottom.y() - top.y());
    const double exact = top.x() + t * (bottom.x() - top.x());
    const int i0 = static_cast<int>(std::floor(exact)) - 2, i1 = i0 + 5;  // 2-3 px either side
    double area = 0;  // of the ink part of the strip, in pixels
    for (int u = i0; u <= i1; ++u)
      area += (options.paper - img.at<float>(v, u)) / (options.paper - options.ink);
    const double measured = i1 + 0.5 - area;
    sum_err += measured - exact;
    ++n;
  }
  EXPECT_GT(n, 20);
  return sum_err / n;
}

TEST(SceneRendererTest, EdgesLieWhereOpenCvProjectsThem) {
  EnsureDisplay();
  TagBoard board = FrontBoard();
  // Off the pixel grid and turned by 1.5 degrees, so that the edge's phase in
  // the pixel grid sweeps along it: a perfectly vertical edge would repeat one
  // phase's 8-bit rounding in every row (a bias of up to ~0.01 px).
  board.ref_from_board.translation += Eigen::Vector3d(0.00123, 0.00077, 0.0);
  board.ref_from_board.rotation = Rz(0.026);
  const CameraTool cam = TestCamera(false);
  for (int supersample : {1, 2, 3}) {
    RenderOptions options;
    options.supersample = supersample;
    SceneRenderer renderer(SceneOf(board), options);
    const cv::Mat img = renderer.RenderPinhole(Rigid3(), cam);
    // Texture filtering is symmetric about the edge: the area is exact up to
    // the 8-bit rounding of the read-back, averaged along the edge.
    const double err = LeftEdgeError(img, cam, board, options);
    std::printf("supersample %d: mean edge error %.4f px\n", supersample, err);
    EXPECT_NEAR(err, 0.0, 0.005) << "supersample " << supersample;
  }
}

TEST(SceneRendererTest, RenderWithoutDistortionIsThePinholeImage) {
  EnsureDisplay();
  const TagBoard board = FrontBoard();
  SceneRenderer renderer(SceneOf(board));
  const CameraTool cam = TestCamera(false);
  const cv::Mat pinhole = renderer.RenderPinhole(Rigid3(), cam);
  const cv::Mat img = renderer.Render(Rigid3(), cam);
  cv::Mat rounded;
  pinhole.convertTo(rounded, CV_8UC1);
  EXPECT_EQ(cv::norm(rounded, img, cv::NORM_INF), 0.0);
}

TEST(SceneRendererTest, DistortionMovesThePictureLikeProjectToPixel) {
  EnsureDisplay();
  TagBoard board = FrontBoard(1, 1, 2.0);
  // One tag far off-axis, where k1 moves it by pixels.
  board.ref_from_board.translation = Eigen::Vector3d(0.7, 0.5, 2.0);
  CameraTool cam = TestCamera(true);
  SceneRenderer renderer(SceneOf(board));
  const cv::Mat img = renderer.Render(Rigid3(), cam);
  // The tag's ink centroid (the black border ring and data bits) against the
  // centroid of the same tag rendered ideally and moved by the distortion of
  // its centre: within 0.3 px, where no distortion would be ~10 px off.
  CameraTool pinhole_cam = cam;
  pinhole_cam.distortion = {};
  const cv::Mat ideal = renderer.Render(Rigid3(), pinhole_cam);
  auto ink_centroid = [](const cv::Mat& m) {
    // Ink is 20, background 90, paper 235: weight only what is near ink.
    cv::Mat ink;
    cv::Mat(60 - m).convertTo(ink, CV_32F);  // saturates at 0 for brighter pixels
    const cv::Moments mo = cv::moments(ink);
    return Eigen::Vector2d(mo.m10 / mo.m00, mo.m01 / mo.m00);
  };
  const Eigen::Vector2d c_ideal = ink_centroid(ideal), c_dist = ink_centroid(img);
  // Where the distortion takes the ideal centroid's ray.
  const Eigen::Vector3d ray((c_ideal.x() - cam.intrinsics[2]) / cam.intrinsics[0],
                            (c_ideal.y() - cam.intrinsics[3]) / cam.intrinsics[1], 1.0);
  double px[2];
  ProjectToPixel(cam.intrinsics.data(), cam.distortion.data(), ray.data(), px);
  EXPECT_GT((c_dist - c_ideal).norm(), 5.0);
  EXPECT_NEAR(c_dist.x(), px[0], 0.3);
  EXPECT_NEAR(c_dist.y(), px[1], 0.3);
}

// A camera that refocuses (SPEC 4.1) changes its intrinsics from photo to
// photo, not its lens: the renderer derives each new distortion map from the
// solved map of the same lens instead of solving it again. Its photos must
// be those of a renderer that solves every map: the derived sample positions
// lie within 1e-3 px of the solved ones (checked inside), which changes an
// 8-bit grey level by one step at most, where an edge's value sits at a
// rounding boundary (a few dozen of the 1.2 million pixels differ, by one
// level; the test allows 1,228). Two lenses, one with sensor tilt
// (the derivation goes through the tilt too); the intrinsics change as from
// near to far, back to the first set, and beyond; then a 1.5 times longer
// focal length, which is another zoom's and is solved.
TEST(SceneRendererTest, RefocusedCameraRendersAsIfItsMapWereSolved) {
  EnsureDisplay();
  TagBoard board = FrontBoard(3, 4, 2.0);
  board.ref_from_board.translation += Eigen::Vector3d(0.3, 0.2, 0.0);  // towards a corner
  RenderOptions options;
  options.supersample = 2;
  for (const bool tilt : {false, true}) {
    CameraTool first = TestCamera(true);
    if (tilt) {
      first.distortion[kTauX] = 0.01;
      first.distortion[kTauY] = -0.005;
    }
    CameraTool near = first, far = first;
    near.intrinsics = {1001.0, 1000.9, 640.9, 479.1};
    far.intrinsics = {998.5, 998.7, 639.7, 480.4};
    SceneRenderer refocusing(SceneOf(board), options);
    int n = 0;
    for (const CameraTool& cam : {first, near, first, far}) {
      const cv::Mat img = refocusing.Render(Rigid3(), cam, 7);
      SceneRenderer solving(SceneOf(board), options);
      const cv::Mat solved = solving.Render(Rigid3(), cam, 7);
      EXPECT_EQ(solving.map_counts().derived, 0);
      EXPECT_LE(cv::norm(img, solved, cv::NORM_INF), 1.0) << "tilt " << tilt << ", photo " << n;
      cv::Mat differs;
      cv::compare(img, solved, differs, cv::CMP_NE);
      EXPECT_LT(cv::countNonZero(differs), img.total() / 1000)
          << "tilt " << tilt << ", photo " << n;
      ++n;
    }
    // The first set's map solved once and reused, the two others derived.
    EXPECT_EQ(refocusing.map_counts().solved, 1) << "tilt " << tilt;
    EXPECT_EQ(refocusing.map_counts().derived, 2) << "tilt " << tilt;
    // Another zoom with the same distortion coefficients is solved: most of
    // its image lies outside the base image.
    CameraTool zoomed = first;
    zoomed.intrinsics[0] *= 1.5;
    zoomed.intrinsics[1] *= 1.5;
    refocusing.Render(Rigid3(), zoomed, 7);
    EXPECT_EQ(refocusing.map_counts().solved, 2) << "tilt " << tilt;
  }
}

// Several scenes in one renderer (the placements of a moved board): each
// selected scene renders exactly as a renderer of that scene alone, whatever
// was drawn before it; the distortion map of the lens is solved once for all.
TEST(SceneRendererTest, SelectedSceneRendersAsItsOwnRenderer) {
  EnsureDisplay();
  const TagBoard near = FrontBoard(3, 4, 1.5);
  TagBoard left = FrontBoard(2, 3, 2.5);
  left.ref_from_board.translation.x() -= 0.2;
  const std::vector<TargetScene> scenes = {SceneOf(near), SceneOf(left)};
  RenderOptions options;
  options.noise_sigma = 2.0;
  const CameraTool cam = TestCamera(true);
  SceneRenderer both(scenes, options);
  for (const int k : {0, 1, 0}) {
    both.SelectScene(k);
    SceneRenderer alone(scenes[k], options);
    const cv::Mat a = both.Render(Rigid3(), cam, 7 + k);
    const cv::Mat b = alone.Render(Rigid3(), cam, 7 + k);
    EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0) << "scene " << k;
  }
  EXPECT_EQ(both.map_counts().solved, 1);
  EXPECT_THROW(both.SelectScene(2), std::out_of_range);
  EXPECT_THROW(SceneRenderer(std::vector<TargetScene>{}, options), std::invalid_argument);
}

TEST(SceneRendererTest, NoiseIsSeededAndSized) {
  EnsureDisplay();
  RenderOptions options;
  options.noise_sigma = 3.0;
  SceneRenderer renderer(SceneOf(FrontBoard()), options);
  const CameraTool cam = TestCamera(false);
  const cv::Mat a = renderer.Render(Rigid3(), cam, 7);
  const cv::Mat b = renderer.Render(Rigid3(), cam, 7);
  const cv::Mat c = renderer.Render(Rigid3(), cam, 8);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(a, c, cv::NORM_INF), 0.0);
  cv::Scalar mean, stddev;
  cv::meanStdDev(a(cv::Rect(0, 0, 200, 200)), mean, stddev);  // background only
  EXPECT_NEAR(mean[0], options.background, 0.5);
  EXPECT_NEAR(stddev[0], 3.0, 0.3);  // 40000 samples; rounding adds 1/12 in variance
}

TEST(SceneRendererTest, ExposureAndBlur) {
  EnsureDisplay();
  RenderOptions options;
  options.exposure = 0.5;
  options.blur_sigma = 1.5;
  SceneRenderer renderer(SceneOf(FrontBoard()), options);
  const cv::Mat img = renderer.Render(Rigid3(), TestCamera(false));
  EXPECT_NEAR(img.at<uint8_t>(10, 10), 0.5 * options.background, 1.0);
  double lo, hi;
  cv::minMaxLoc(img, &lo, &hi);
  EXPECT_LE(hi, 0.5 * options.paper + 1);
}

TEST(SceneRendererTest, LightingShadesObliqueBoards) {
  EnsureDisplay();
  TagBoard board = FrontBoard();
  // Turned by 60 degrees about its vertical centre line.
  const Eigen::Vector3d centre = board.CentreInRef();
  board.ref_from_board.rotation = Ry(M_PI / 3);
  board.ref_from_board.translation =
      centre - board.ref_from_board.rotation * Eigen::Vector3d(0.19, 0.14, 0);
  RenderOptions options;
  options.lighting = true;
  SceneRenderer lit(SceneOf(board), options);
  double lo, hi;
  cv::minMaxLoc(lit.Render(Rigid3(), TestCamera(false)), &lo, &hi);
  // Headlight: ambient 0.3 + diffuse 0.7 cos(60 deg) of the paper.
  EXPECT_NEAR(hi, 0.65 * options.paper, 0.03 * options.paper);
  options.lighting = false;
  SceneRenderer flat(SceneOf(board), options);
  cv::minMaxLoc(flat.Render(Rigid3(), TestCamera(false)), &lo, &hi);
  EXPECT_EQ(hi, options.paper);
}

TEST(SceneRendererTest, TheBackOfABoardIsBlank) {
  EnsureDisplay();
  const TagBoard board = FrontBoard();
  SceneRenderer renderer(SceneOf(board));
  const CameraTool cam = TestCamera(false);
  // From 4 m, behind the board, looking back at it.
  const Rigid3 behind = testing::AimAt(Eigen::Vector3d(0, 0, 4), board.CentreInRef(),
                                       cam.intrinsics[2], cam.intrinsics[3], 0.0, cam);
  const cv::Mat img = renderer.Render(behind, cam);
  double lo, hi;
  cv::minMaxLoc(img, &lo, &hi);
  EXPECT_GT(lo, renderer.options().ink + 30);  // no ink anywhere
  EXPECT_NE(img.at<uint8_t>(480, 640), static_cast<uint8_t>(renderer.options().background));
}

TEST(SceneRendererTest, NearerBoardsHideFartherOnes) {
  EnsureDisplay();
  TargetScene scene = SceneOf(FrontBoard(3, 4, 3.0));
  TagBoard front = FrontBoard(1, 1, 1.5);
  front.first_id = 20;
  scene.boards.push_back(front);
  SceneRenderer renderer(scene);
  const CameraTool cam = TestCamera(false);
  const cv::Mat img = renderer.Render(Rigid3(), cam);
  // At the optical axis the single near tag's black border/centre region
  // (a 0.08 m tag at 1.5 m: 53 px wide) covers the far board's centre.
  const TargetScene near_only = SceneOf(front);
  SceneRenderer near_renderer(near_only);
  const cv::Mat near_img = near_renderer.Render(Rigid3(), cam);
  EXPECT_EQ(
      cv::norm(img(cv::Rect(610, 450, 60, 60)), near_img(cv::Rect(610, 450, 60, 60)), cv::NORM_INF),
      0.0);
}

TEST(SceneRendererTest, OptionsAreChecked) {
  RenderOptions o;
  EXPECT_EQ(o.Check(), "");
  o.supersample = 0;
  EXPECT_NE(o.Check(), "");
  o = RenderOptions();
  o.ink = 200;
  o.paper = 100;
  EXPECT_NE(o.Check(), "");
  o = RenderOptions();
  o.exposure = 0;
  EXPECT_NE(o.Check(), "");
  EXPECT_THROW(SceneRenderer(TargetScene(), o), std::invalid_argument);
}

}  // namespace
}  // namespace rtscalib::render

// Rendered ChArUco and chessboards detected by OpenCV's detectors
// (detect/point_boards.h) against the exact projections of their inner
// corners (libcalib's camera model, lens distortion on): the renderer draws
// the boards as docs/photos.md defines them (render/tag_texture.h), and the
// detected corners carry the ids the board frame gives them. The detector on
// photos synthesized without the renderer: tests/detect/point_boards_test.cc.
#include "detect/point_boards.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "libcalib/camera/opencv_model.h"
#include "render/scene_renderer.h"
#include "render/tag_matching.h"
#include "tests/render/render_fixture.h"

namespace rtscalib::render {
namespace {

using detect::DetectPointBoard;
using detect::PointBoardDetection;
using testing::AimAt;
using testing::EnsureDisplay;
using testing::SceneOf;
using testing::TestCamera;

// 5 x 7 squares of 8 cm with 6 cm markers of DICT_4X4_50 (the proportions
// of docs/photos.md's example), or 6 x 9 squares of 7 cm (an odd number of
// rows plus columns: the print is not symmetric under a half turn), centred
// on the optical axis of the home pose 1 m away: 70-80 px squares at fx 1000.
TagBoard PointBoard(BoardKind kind) {
  TagBoard b;
  b.kind = kind;
  if (kind == BoardKind::kCharuco) {
    b.family = "DICT_4X4_50";
    b.first_id = 100;
    b.rows = 5;
    b.cols = 7;
    b.square_size = 0.08;
    b.marker_size = 0.06;
  } else {
    b.family = "chessboard";
    b.first_id = 200;
    b.rows = 6;
    b.cols = 9;
    b.square_size = 0.07;
  }
  b.ref_from_board.translation = Eigen::Vector3d(-b.Width() / 2, -b.Height() / 2, 1.0);
  return b;
}

struct CornerErrors {
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  double sum_sq = 0, max = 0;
  int n = 0;
  double Rms() const { return n > 0 ? std::sqrt(sum_sq / n) : 0.0; }
  Eigen::Vector2d Mean() const { return n > 0 ? Eigen::Vector2d(sum / n) : sum; }
};

// The detected inner corners against their exact projections: every one
// must be an inner corner of the board, each at most once.
void Accumulate(const PointBoardDetection& d, const TagBoard& board, const Rigid3& ref_from_cam,
                const CameraTool& cam, CornerErrors* errors) {
  const Rigid3 cam_from_board = ref_from_cam.Inverse() * board.ref_from_board;
  std::vector<bool> seen(board.NumTags(), false);
  for (const auto& [k, uv] : d.corners) {
    ASSERT_GE(k, 0);
    ASSERT_LT(k, board.NumTags());
    EXPECT_FALSE(seen[k]) << "corner " << k << " twice";
    seen[k] = true;
    const Eigen::Vector3d p = cam_from_board * board.CornersInBoard(k)[0];
    double px[2];
    ASSERT_TRUE(ProjectToPixel(cam.intrinsics.data(), cam.distortion.data(), p.data(), px));
    const Eigen::Vector2d e = uv - Eigen::Vector2d(px[0], px[1]);
    errors->sum += e;
    errors->sum_sq += e.squaredNorm();
    errors->max = std::max(errors->max, e.norm());
    ++errors->n;
  }
}

// Shots that put the board all over the image, seen from off to the side
// (tilted by up to ~15 degrees), rolled slightly; `face` 2 turns the camera
// by half a turn about its line of sight, as the transited telescope sees the
// board (the chessboard's orientation rule, point_boards.h).
std::vector<Rigid3> Poses(const TagBoard& board, const CameraTool& cam, int face) {
  std::vector<Rigid3> out;
  int i = 0;
  for (double u : {420.0, 640.0, 860.0}) {
    for (double v : {340.0, 480.0, 620.0}) {
      const Eigen::Vector3d centre(0.25 * (u - 640) / 220, -0.2 * (v - 480) / 140, 0.0);
      const double roll = 0.08 * (i++ % 3 - 1) + (face == 2 ? M_PI : 0.0);
      out.push_back(AimAt(centre, board.CentreInRef(), u, v, roll, cam));
    }
  }
  return out;
}

// Renders `board` at Poses() in `faces` and detects it; every inner corner
// is expected (ExpectTags: visible) and found.
CornerErrors RenderAndDetect(const TagBoard& board, const RenderOptions& options,
                       const std::vector<int>& faces = {1, 2}) {
  EnsureDisplay();
  const TargetScene scene = SceneOf(board);
  SceneRenderer renderer(scene, options);
  const CameraTool cam = TestCamera(true);
  CornerErrors errors;
  int image = 0;
  for (int face : faces) {
    for (const Rigid3& pose : Poses(board, cam, face)) {
      for (const ExpectedTag& t : ExpectTags(scene, pose, cam)) {
        EXPECT_EQ(t.status, TagStatus::kVisible) << "corner " << t.id << ", face " << face;
        EXPECT_EQ(t.corners, 1);
      }
      const PointBoardDetection d =
          DetectPointBoard(renderer.Render(pose, cam, image++), board, face);
      EXPECT_FALSE(d.misoriented);
      EXPECT_EQ(static_cast<int>(d.corners.size()), board.NumTags()) << "face " << face;
      Accumulate(d, board, pose, cam, &errors);
    }
  }
  return errors;
}

void Print(const char* what, const CornerErrors& e) {
  std::printf("%s: %d corners, RMS %.4f px, max %.4f px, mean (%.4f, %.4f) px\n", what, e.n,
              e.Rms(), e.max, e.Mean().x(), e.Mean().y());
}

// Limits: those of tests/detect on exactly synthesized photos, 0.1 px RMS
// and 0.3 px max (measured there: ChArUco 0.04-0.05 px RMS, chessboard
// 0.04-0.06 px); the renderer's AprilTag corners come out at 0.013 px RMS
// (docs/rendering.md), so rendering adds little. Measured here (Release, 18
// shots): ChArUco 0.064 px RMS, max 0.130 px, chessboard 0.058 px, max
// 0.122 px, mean offsets <= 0.001 px (0.062 and 0.060 px RMS with noise).
// A wrong id would be a square (70-80 px) off, a half-pixel convention error
// 0.7 px, a board drawn mirrored or turned would swap ids; an offset of the
// drawn squares would show in the mean.
TEST(PointBoardsRenderTest, CharucoCornersMatchExactProjections) {
  const CornerErrors e = RenderAndDetect(PointBoard(BoardKind::kCharuco), {});
  Print("rendered charuco", e);
  EXPECT_EQ(e.n, 18 * 24);
  EXPECT_LT(e.Rms(), 0.1);
  EXPECT_LT(e.max, 0.3);
  EXPECT_LT(e.Mean().norm(), 0.03);  // no convention offset (measured 0.0008 px)
}

TEST(PointBoardsRenderTest, ChessboardCornersMatchExactProjections) {
  const CornerErrors e = RenderAndDetect(PointBoard(BoardKind::kChessboard), {});
  Print("rendered chessboard", e);
  EXPECT_EQ(e.n, 18 * 40);
  EXPECT_LT(e.Rms(), 0.1);
  EXPECT_LT(e.max, 0.3);
  EXPECT_LT(e.Mean().norm(), 0.03);
}

// The demo's sensor noise (configs/zoom3.yaml: 1 grey level); face 1 only
// (the faces are the tests above).
TEST(PointBoardsRenderTest, SensorNoiseKeepsSubPixelAccuracy) {
  RenderOptions options;
  options.noise_sigma = 1.0;
  const CornerErrors charuco = RenderAndDetect(PointBoard(BoardKind::kCharuco), options, {1});
  const CornerErrors chessboard = RenderAndDetect(PointBoard(BoardKind::kChessboard), options, {1});
  Print("rendered charuco, noise 1", charuco);
  Print("rendered chessboard, noise 1", chessboard);
  EXPECT_LT(charuco.Rms(), 0.1);
  EXPECT_LT(chessboard.Rms(), 0.1);
}

}  // namespace
}  // namespace rtscalib::render

// The focus of the telescope camera (SPEC 4.1, libcalib/model/focus.h):
// the formula, the D of a photo and of a camera record, and predictions
// with and without the effect.
#include "libcalib/model/focus.h"

#include <gtest/gtest.h>

#include "libcalib/camera/opencv_model.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/kinematics.h"
#include "libcalib/model/observations.h"

namespace rtscalib {
namespace {

CameraTool Camera() {
  CameraTool cam;
  cam.intrinsics = {1500.0, 1500.3, 641.5, 478.5};
  cam.distortion[kK1] = -0.05;
  cam.focus = {0.02, 6.0, -4.0};  // kf 20 mm, au 6 px m, av -4 px m
  return cam;
}

InstrumentModel WithFocus() {
  InstrumentModel m = IdealModel(Kinematics::kSpherical, 1, Camera());
  m.effects.Add(Effect::kFocus);
  return m;
}

// SPEC 4.1 term by term (exact in double: one product and one quotient each).
TEST(Focus, IntrinsicsAtDistance) {
  const CameraTool cam = Camera();
  double k[4];
  ASSERT_TRUE(FocusedIntrinsics(cam.intrinsics.data(), cam.focus.data(), 4.0, k));
  EXPECT_DOUBLE_EQ(k[0], 1500.0 * (1 + 0.02 / 4.0));
  EXPECT_DOUBLE_EQ(k[1], 1500.3 * (1 + 0.02 / 4.0));
  EXPECT_DOUBLE_EQ(k[2], 641.5 + 6.0 / 4.0);
  EXPECT_DOUBLE_EQ(k[3], 478.5 - 4.0 / 4.0);
  // Without the effect (null terms) D plays no role; D <= 0 has no focus.
  ASSERT_TRUE(FocusedIntrinsics(cam.intrinsics.data(), static_cast<const double*>(nullptr), 4.0, k));
  EXPECT_EQ(k[0], 1500.0);
  EXPECT_FALSE(FocusedIntrinsics(cam.intrinsics.data(), cam.focus.data(), 0.0, k));
}

// A pixel is the projection with the intrinsics at the given D, by default
// at the point's own distance; without the effect D changes nothing.
TEST(Focus, PixelUsesTheFocusedIntrinsics) {
  const InstrumentModel m = WithFocus();
  const double phi = 0.3, theta = 1.4;
  const Rigid3 ref_from_cam = RefFromCam(m, 0, phi, theta);
  const Eigen::Vector3d x_cam(0.4, -0.3, 5.0);
  const Eigen::Vector3d x_ref = ref_from_cam * x_cam;
  double k[4], expected[2];
  Eigen::Vector2d uv;
  for (double d : {2.0, 30.0}) {
    ASSERT_TRUE(FocusedIntrinsics(m.cams[0].intrinsics.data(), m.cams[0].focus.data(), d, k));
    ASSERT_TRUE(ProjectToPixel(k, m.cams[0].distortion.data(), x_cam.data(), expected));
    ASSERT_TRUE(PredictPixel(m, 0, phi, theta, x_ref, &uv, d));
    // 1e-9 px: the same arithmetic through the chain's rotations (~1e-15 relative).
    EXPECT_NEAR(uv.x(), expected[0], 1e-9);
    EXPECT_NEAR(uv.y(), expected[1], 1e-9);
  }
  ASSERT_TRUE(FocusedIntrinsics(m.cams[0].intrinsics.data(), m.cams[0].focus.data(),
                                x_cam.norm(), k));
  ASSERT_TRUE(ProjectToPixel(k, m.cams[0].distortion.data(), x_cam.data(), expected));
  ASSERT_TRUE(PredictPixel(m, 0, phi, theta, x_ref, &uv));
  EXPECT_NEAR(uv.x(), expected[0], 1e-9);
  InstrumentModel off = m;
  off.effects.Remove(Effect::kFocus);
  Eigen::Vector2d a, b;
  ASSERT_TRUE(PredictPixel(off, 0, phi, theta, x_ref, &a, 2.0));
  ASSERT_TRUE(PredictPixel(off, 0, phi, theta, x_ref, &b, 30.0));
  EXPECT_EQ(a, b);
}

// F_CAM focuses at its ray length d: the point it returns projects back onto
// its pixel with the camera focused at d (1e-6 px: the undistortion's
// iteration converges to ~1e-10 of the normalised radius).
TEST(Focus, CameraRecordFocusesAtItsRayLength) {
  const InstrumentModel m = WithFocus();
  for (double d : {1.0, 7.0}) {
    const Eigen::Vector3d x = PredictCam(m, 0, 0.2, 1.3, 900.0, 200.0, d);
    Eigen::Vector2d uv;
    ASSERT_TRUE(PredictPixel(m, 0, 0.2, 1.3, x, &uv, d));
    EXPECT_NEAR(uv.x(), 900.0, 1e-6);
    EXPECT_NEAR(uv.y(), 200.0, 1e-6);
  }
}

// D of a photo: its focus_distance when given, else the distance from the
// camera to the centroid of its points (known X, or the corners of an
// estimated board); one D for all rows of a photo.
TEST(Focus, PhotoDistanceIsGivenOrTheCentroid) {
  InstrumentModel m = WithFocus();
  const Rigid3 ref_from_cam = RefFromCam(m, 0, 0.0, M_PI / 2);
  std::vector<PixelObservation> pixels;
  auto add = [&](const std::string& shot, const Eigen::Vector3d& x_cam, double given) {
    PixelObservation p;
    p.shot = shot;
    p.phi = 0.0;
    p.theta = M_PI / 2;
    p.X = ref_from_cam * x_cam;
    p.focus_distance = given;
    pixels.push_back(p);
  };
  add("a", {1.0, 0.0, 4.0}, 0.0);
  add("a", {-1.0, 0.0, 4.0}, 0.0);
  add("a", {0.0, 0.0, 7.0}, 0.0);
  add("b", {0.0, 0.0, 9.0}, 12.5);
  add("b", {0.0, 1.0, 9.0}, 0.0);  // a row without the column: the photo's D
  const std::vector<double> d = PhotoFocusDistances(m, pixels);
  ASSERT_EQ(d.size(), 5u);
  EXPECT_NEAR(d[0], 5.0, 1e-12);  // centroid (0, 0, 5)
  EXPECT_EQ(d[0], d[2]);
  EXPECT_EQ(d[3], 12.5);
  EXPECT_EQ(d[4], 12.5);
  const std::vector<double> target = PhotoFocusDistances(m, pixels, nullptr, false);
  EXPECT_NEAR(target[3], std::hypot(0.5, 9.0), 1e-12);
  // A board of estimated pose places its corners.
  TagBoard board;
  board.first_id = 10;
  board.rows = 1;
  board.cols = 1;
  board.tag_size = 0.2;
  EstimatedBoard eb;
  eb.board = board;
  eb.pose = PoseBlock::FromRigid(ref_from_cam * Rigid3{Eigen::Matrix3d::Identity(),
                                                       Eigen::Vector3d(-0.1, -0.1, 6.0)});
  m.boards.push_back(eb);
  std::vector<PixelObservation> on_board(4);
  for (int c = 0; c < 4; ++c) {
    on_board[c].shot = "c";
    on_board[c].theta = M_PI / 2;
    on_board[c].X_known = false;
    on_board[c].target = 10;
    on_board[c].corner = c;
  }
  EXPECT_NEAR(PhotoFocusDistances(m, on_board)[0], 6.0, 1e-12);  // the tag's centre
  // Predictions need D only with the effect.
  m.effects.Remove(Effect::kFocus);
  EXPECT_EQ(PredictionFocusDistances(m, pixels), std::vector<double>(5, 0.0));
}

}  // namespace
}  // namespace rtscalib

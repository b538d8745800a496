// Projection uncertainty maps (libcalib/api/uncertainty_map.h): each cell is
// the worst-direction 1-sigma of PixelWithUncertainty at the point the model
// sees there at the stated range, cells outside the valid region are marked,
// and the summary numbers are the cells'.
#include "libcalib/api/uncertainty_map.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "libcalib/sim/simulator.h"

namespace rtscalib {
namespace {

// A model with the sigmas of a real fit's size (as api_test.cc's) and a
// correlated full covariance (random, positive definite).
InstrumentModel Model() {
  InstrumentModel m = PaperTruth(2);
  for (CameraTool& c : m.cams) {
    c.width = 640;
    c.height = 480;
    c.intrinsics = {900, 901, 322, 238};
    c.distortion[kK1] = -0.08;
    c.distortion[kK2] = 0.03;
    // Points fell only in the image's left half.
    c.valid_region = {{0, 0}, {319, 0}, {319, 479}, {0, 479}};
  }
  m.effects.Add(Effect::kRadialDistortion);
  return m;
}

TEST(UncertaintyMap, CellsArePixelUncertaintiesAtTheRangeAndMarkTheValidRegion) {
  const InstrumentModel m = Model();
  CalibratedInstrument inst(m);
  const int n = inst.NumParameters();
  Eigen::MatrixXd a = Eigen::MatrixXd::Random(n, n) * 1e-4;
  inst.SetParameterCovariance(a * a.transpose());
  UncertaintyMapOptions o;
  o.range_m = 7.5;
  o.cols = 8;
  o.rows = 6;
  o.phi = 0.4;
  o.theta = 1.4;
  const std::vector<UncertaintyMap> maps = ProjectionUncertaintyMaps(inst, o);
  ASSERT_EQ(maps.size(), 2u);
  for (const UncertaintyMap& map : maps) {
    ASSERT_EQ(map.sigma_px.size(), 48u);
    std::vector<double> values;
    for (int r = 0; r < o.rows; ++r) {
      for (int c = 0; c < o.cols; ++c) {
        const double u = map.CellU(c), v = map.CellV(r);
        const Eigen::Vector3d x = inst.CameraPoint(map.zoom, o.phi, o.theta, u, v, o.range_m);
        const Eigen::Matrix2d s = inst.PixelWithUncertainty(map.zoom, o.phi, o.theta, x).covariance;
        const double expected =
            std::sqrt(Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(s).eigenvalues()[1]);
        EXPECT_EQ(map.Cell(c, r), expected);  // the same computation, bit for bit
        EXPECT_EQ(map.inside[r * o.cols + c], c < o.cols / 2 ? 1 : 0) << c << " " << r;
        values.push_back(expected);
      }
    }
    EXPECT_EQ(map.cells_outside, 24);
    EXPECT_EQ(map.min_px, *std::min_element(values.begin(), values.end()));
    EXPECT_EQ(map.max_px, *std::max_element(values.begin(), values.end()));
    EXPECT_GT(map.max_px, 0.0);
    EXPECT_FALSE(map.up_to_rotation);
    EXPECT_EQ(MapSubject(map, o), "a point at 7.5 m, pointing phi 0.4, theta 1.4 rad");
  }
}

// A camera on its own, 1000 px lens, no distortion, and a covariance of one
// parameter at a time, 1 px (the block's tangent coordinates are the
// intrinsics themselves: fx, fy, cx, cy).
std::vector<UncertaintyMap> CameraOnItsOwn(int parameter) {
  CameraTool cam;
  cam.width = 640;
  cam.height = 480;
  cam.intrinsics = {1000, 1000, 320, 240};
  cam.valid_region = {{0, 0}, {639, 0}, {639, 479}, {0, 479}};
  CalibratedInstrument inst(IdealModel(Kinematics::kNone, 1, cam));
  const int at = inst.Block("cam[0].intrinsics").offset + parameter;
  Eigen::MatrixXd p = Eigen::MatrixXd::Zero(inst.NumParameters(), inst.NumParameters());
  p(at, at) = 1.0;
  inst.SetParameterCovariance(p);
  UncertaintyMapOptions o;
  o.cols = 8;
  o.rows = 6;
  return ProjectionUncertaintyMaps(inst, o);
}

// The principal point moves every pixel alike, as a turn of the camera
// does up to the second order of the angle off the axis ((u - cx)^2 / f^2
// <= 0.1 here): up to the camera's rotation it moves next to nothing, where
// it would be its 1 px sigma in every cell. A focal length scales the image
// about the principal point, which no turn undoes: |u - cx| / f px per px
// of fx at the cells farthest from the centre, up to what the fitted turn
// takes off an image that is not symmetric about its cells (5 %).
TEST(UncertaintyMap, ACameraOnItsOwnIsMappedUpToItsRotation) {
  const UncertaintyMap cx = CameraOnItsOwn(2).at(0);
  EXPECT_TRUE(cx.up_to_rotation);
  EXPECT_LT(cx.max_px, 0.1);
  const UncertaintyMap fx = CameraOnItsOwn(0).at(0);
  const double corner = std::abs(fx.CellU(0) - 320) / 1000;
  EXPECT_NEAR(fx.Cell(0, 0), corner, 0.05 * corner);
  EXPECT_NEAR(fx.Cell(7, 5), corner, 0.05 * corner);
  EXPECT_EQ(MapSubject(fx, {}), "a direction (up to the camera's rotation)");
}

TEST(UncertaintyMap, RefusesBadOptionsAndModelsWithoutCovariance) {
  const CalibratedInstrument none(Model());  // sigmas.valid false
  EXPECT_THROW(ProjectionUncertaintyMaps(none, {}), std::logic_error);
  UncertaintyMapOptions o;
  o.range_m = 0;
  EXPECT_THROW(ProjectionUncertaintyMaps(none, o), std::invalid_argument);
}

}  // namespace
}  // namespace rtscalib

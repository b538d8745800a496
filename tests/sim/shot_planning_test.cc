// Shot planning of the simulator (libcalib/sim/simulator.h): with ZoomScene's
// boards, every zoom level and both faces get shots, the shots are full of
// tags and together cover the image, and every pixel row is the exact
// projection (plus noise) of its corner.
#include <gtest/gtest.h>

#include <map>
#include <set>
#include <string>
#include <tuple>

#include "libcalib/model/kinematics.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib {
namespace {

InstrumentModel SevenZoomTruth() {
  InstrumentModel m = PaperTruth(7);
  for (int z = 0; z < 7; ++z) {
    m.cams[z].width = 640;
    m.cams[z].height = 480;
    const double f = 800.0 * std::pow(1.4, z);
    m.cams[z].intrinsics = {f, f, 320, 240};
  }
  return m;
}

SimulationOptions Options(const InstrumentModel& truth) {
  SimulationOptions o;
  o.truth = truth;
  o.targets = ZoomScene(truth, 5, 5, 4.0);
  o.shots.shots_per_board = 4;
  o.plan.faces = {1, 2};
  o.plan.zooms = {0, 1, 2, 3, 4, 5, 6};
  return o;
}

TEST(ShotPlanning, EveryZoomAndFaceGetsFullShotsCoveringTheImage) {
  const InstrumentModel truth = SevenZoomTruth();
  const SimulatedData data = Simulate(Options(truth));
  struct Extent {
    double umin = 1e9, umax = -1e9, vmin = 1e9, vmax = -1e9;
    std::map<std::string, int> corners_per_shot;
  };
  std::map<std::pair<int, int>, Extent> by_zoom_face;
  for (const PixelObservation& p : data.obs.pixels) {
    Extent& e = by_zoom_face[{p.zoom, p.face}];
    e.umin = std::min(e.umin, p.uv.x());
    e.umax = std::max(e.umax, p.uv.x());
    e.vmin = std::min(e.vmin, p.uv.y());
    e.vmax = std::max(e.vmax, p.uv.y());
    ++e.corners_per_shot[p.shot];
  }
  for (int z = 0; z < 7; ++z) {
    for (int face : {1, 2}) {
      ASSERT_TRUE(by_zoom_face.count({z, face})) << "zoom " << z << " face " << face;
      const Extent& e = by_zoom_face[{z, face}];
      // Several shots, each with many corners (a 5 x 5 board has 100).
      EXPECT_GE(e.corners_per_shot.size(), 8u) << "zoom " << z << " face " << face;
      int total = 0;
      for (const auto& [shot, n] : e.corners_per_shot) {
        EXPECT_GE(n, 8) << shot;
        total += n;
      }
      EXPECT_GE(total / static_cast<int>(e.corners_per_shot.size()), 50) << "zoom " << z;
      // Together the shots reach within 25 % of every image border (measured
      // worst: 16 % in u at the zooms where a board is about as large as the
      // view; docs/refinement.md, "Simulated shots").
      EXPECT_LT(e.umin, 0.25 * 640) << "zoom " << z << " face " << face;
      EXPECT_GT(e.umax, 0.75 * 640) << "zoom " << z << " face " << face;
      EXPECT_LT(e.vmin, 0.25 * 480) << "zoom " << z << " face " << face;
      EXPECT_GT(e.vmax, 0.75 * 480) << "zoom " << z << " face " << face;
    }
  }
}

TEST(ShotPlanning, PixelsAreExactProjectionsAndFacesAreConsistent) {
  const InstrumentModel truth = SevenZoomTruth();
  SimulationOptions o = Options(truth);
  o.plan.zooms = {0, 3};
  const SimulatedData data = Simulate(o);
  ASSERT_EQ(data.obs.pixels.size(), data.exact_pixels.size());
  for (size_t i = 0; i < data.obs.pixels.size(); ++i) {
    const PixelObservation& p = data.obs.pixels[i];
    Eigen::Vector2d uv;
    ASSERT_TRUE(PredictPixel(truth, p.zoom, p.phi, p.theta, p.X, &uv));
    EXPECT_NEAR((uv - p.uv).norm(), 0.0, 1e-9);  // noise-free: the projection itself
    EXPECT_EQ(FaceOf(p.theta), p.face);
  }
}

TEST(ShotPlanning, NoiseHasTheConfiguredSigma) {
  const InstrumentModel truth = SevenZoomTruth();
  SimulationOptions o = Options(truth);
  o.plan.zooms = {1};
  o.noise.pixel_px = 0.5;
  const SimulatedData data = Simulate(o);
  double s2 = 0;
  for (size_t i = 0; i < data.obs.pixels.size(); ++i) {
    s2 += (data.obs.pixels[i].uv - data.exact_pixels[i]).squaredNorm();
  }
  const double sigma = std::sqrt(s2 / (2.0 * data.obs.pixels.size()));
  // ~2,000 normal draws: the sample sigma is within 5 % of 0.5 px.
  EXPECT_NEAR(sigma, 0.5, 0.025);
}

}  // namespace
}  // namespace rtscalib

namespace rtscalib {
namespace {

// Under strong barrel distortion, corners beyond the lens's trusted radius
// project back into the image (the distortion map folds); a real lens never
// shows them, so the simulator must not report them. Every simulated pixel
// must back-project to its own corner's direction.
TEST(ShotPlanning, NoCornerBeyondTheTrustedRadius) {
  InstrumentModel truth = PaperTruth(1);
  truth.cams[0].width = 640;
  truth.cams[0].height = 480;
  truth.cams[0].intrinsics = {300, 300, 320, 240};  // wide view: corners far off axis
  truth.cams[0].distortion[kK1] = -0.3;
  SimulationOptions o;
  o.truth = truth;
  o.targets = ZoomScene(truth, 4, 4, 3.0);
  o.plan.zooms = {0};
  const SimulatedData data = Simulate(o);
  ASSERT_FALSE(data.obs.pixels.empty());
  for (const PixelObservation& p : data.obs.pixels) {
    const Rigid3 ref_from_cam = RefFromCam(truth, 0, p.phi, p.theta);
    const Eigen::Vector3d ray = (ref_from_cam.Inverse() * p.X).normalized();
    const Eigen::Vector3d back =
        ref_from_cam.Inverse().rotation *
        (PredictCam(truth, 0, p.phi, p.theta, p.uv.x(), p.uv.y(), 1.0) - ref_from_cam.translation);
    // 1e-9: exact projection and Newton back-projection agree to round-off.
    EXPECT_LT((back.normalized() - ray).norm(), 1e-9) << p.shot << " target " << p.target;
  }
}

}  // namespace
}  // namespace rtscalib

namespace rtscalib {
namespace {

// The distortion is determined only where points fall: every zoom and face
// must put points into each ninth of the image (3 x 3 cells), the four corner
// cells included, or the distortion polynomial is extrapolated there.
void ExpectEveryNinthCovered(const SimulationOptions& o, int width, int height) {
  const SimulatedData data = Simulate(o);
  std::map<std::pair<int, int>, std::set<int>> cells;  // (zoom, face) -> cells hit
  for (const PixelObservation& p : data.obs.pixels) {
    const int i = std::min(2, static_cast<int>(3 * (p.uv.x() + 0.5) / width));
    const int j = std::min(2, static_cast<int>(3 * (p.uv.y() + 0.5) / height));
    cells[{p.zoom, p.face}].insert(3 * j + i);
  }
  for (int z : o.plan.zooms) {
    for (int face : o.plan.faces) {
      const std::set<int>& hit = cells[{z, face}];
      for (int c = 0; c < 9; ++c) {
        EXPECT_TRUE(hit.count(c)) << "zoom " << z << " face " << face << ": no point in image cell "
                                  << "(u " << c % 3 << ", v " << c / 3 << ") of 3 x 3";
      }
    }
  }
}

TEST(ShotPlanning, EveryZoomAndFacePutsPointsIntoEveryNinthOfTheImage) {
  // Boards a quarter of the view wide (ZoomScene): the pattern needs three
  // positions per axis.
  ExpectEveryNinthCovered(Options(SevenZoomTruth()), 640, 480);
}

TEST(ShotPlanning, ZoomThreeDemoSceneCoversTheImageCorners) {
  // The main demo's instrument and boards (configs/zoom3.yaml): before the
  // corner-reaching pattern, zoom 0's points stayed within u 312-921,
  // v 225-725 of 1280 x 960.
  InstrumentModel truth = PaperTruth(3);
  const double f[3] = {1500, 3000, 6000};
  for (int z = 0; z < 3; ++z) {
    truth.cams[z].width = 1280;
    truth.cams[z].height = 960;
    truth.cams[z].intrinsics = {f[z], f[z], 639.5, 479.5};
  }
  SimulationOptions o;
  o.truth = truth;
  o.plan.faces = {1, 2};
  o.plan.zooms = {0, 1, 2};
  o.shots.shots_per_board = 4;
  const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> poses = {
      {{-1.570796, 0.0, -0.261799}, {-0.2825, 3.0465, 0.6350}},
      {{-1.570796, 0.0, -1.308997}, {3.4910, -0.0295, -0.1588}},
      {{-1.570796, 0.0, 2.617994}, {-0.7876, -3.0061, 1.2064}},
      {{-1.570796, 0.0, 1.431170}, {-3.9275, 1.1250, -0.5118}}};
  for (size_t b = 0; b < poses.size(); ++b) {
    TagBoard board;
    board.first_id = 48 * static_cast<int>(b);
    board.rows = 6;
    board.cols = 8;
    board.tag_size = 0.06;
    board.spacing = 0.015;
    board.ref_from_board = Rigid3::FromEuler(poses[b].first, poses[b].second);
    o.targets.boards.push_back(board);
  }
  ExpectEveryNinthCovered(o, 1280, 960);
}

// ShotPlan::given (a planned session, libcalib/plan): photos at given
// pointings show exactly the corners, at exactly the pixels, that the
// pattern's own photos at those pointings show.
TEST(ShotPlanning, GivenPointingsReproduceThePatternsPhotos) {
  SimulationOptions o = Options(SevenZoomTruth());
  o.plan.sweeps = false;
  const SimulatedData pattern = Simulate(o);
  std::map<std::string, PlannedShot> pointing;
  for (const PixelObservation& p : pattern.obs.pixels) {
    pointing[p.shot] = PlannedShot{p.face, p.zoom, p.phi, p.theta, p.placement, p.shot};
  }
  ASSERT_GT(pointing.size(), 20u);
  SimulationOptions g = o;
  for (const auto& [shot, pt] : pointing) g.shots.given.push_back(pt);
  const SimulatedData given = Simulate(g);
  ASSERT_EQ(given.obs.pixels.size(), pattern.obs.pixels.size());
  std::map<std::tuple<std::string, int, int>, Eigen::Vector2d> uv;
  for (size_t k = 0; k < pattern.obs.pixels.size(); ++k) {
    const PixelObservation& p = pattern.obs.pixels[k];
    uv[{p.shot, p.target, p.corner}] = pattern.exact_pixels[k];
  }
  for (size_t k = 0; k < given.obs.pixels.size(); ++k) {
    const PixelObservation& p = given.obs.pixels[k];
    const auto it = uv.find({p.shot, p.target, p.corner});
    ASSERT_NE(it, uv.end()) << p.shot << " " << p.target << " " << p.corner;
    EXPECT_EQ((it->second - given.exact_pixels[k]).norm(), 0.0);
  }
}

}  // namespace
}  // namespace rtscalib

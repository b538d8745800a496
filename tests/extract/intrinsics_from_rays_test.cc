#include "libcalib/extract/intrinsics_from_rays.h"

#include <gtest/gtest.h>

#include <cmath>

#include "libcalib/model/kinematics.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib {
namespace {

// Grid records (pixels spread over the image) of `truth` for the given zooms,
// camera rays at `lengths`, EDM at 1 m and 2 m; no sweeps.
std::vector<Record> GridRecords(const InstrumentModel& truth, std::vector<int> zooms,
                                std::vector<double> lengths) {
  AcquisitionPlan plan;
  plan.sweeps = false;
  plan.grid_phi_steps = 4;
  plan.grid_theta_steps = 3;
  plan.grid_edm_distances = {1.0, 2.0};
  plan.grid_cam_ray_lengths = lengths;
  plan.grid_pixels_per_axis = 3;
  plan.zooms = zooms;
  return PlanRecords(plan, truth);
}

void ExpectIntrinsics(const CameraTool& truth, const RayIntrinsicsEstimate& e, double tol) {
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(e.camera.intrinsics[k], truth.intrinsics[k], tol) << "intrinsic " << k;
  }
  for (double d : e.camera.distortion) EXPECT_EQ(d, 0.0);
}

TEST(IntrinsicsFromRays, TwoRayLengthsGiveTheExactPinhole) {
  // Two ray lengths per pixel give each view direction exactly (Klug Eq. 12:
  // points at ray length d), whatever the camera's offset from the EDM. The
  // DLT on 9 exact directions then recovers K to round-off, amplified by the
  // conditioning of the normalised DLT (~f^2): 1e-6 px is far above that and
  // far below any meaningful error.
  const InstrumentModel truth = PaperTruth(2);
  const std::vector<Record> rec = GridRecords(truth, {0, 1}, {1.0, 3.0});
  for (int z = 0; z < 2; ++z) {
    const auto e = EstimateIntrinsicsFromRays(rec, z);
    ASSERT_TRUE(e.has_value()) << z;
    EXPECT_EQ(e->poses, 12);
    ExpectIntrinsics(truth.cams[z], *e, 1e-6);
    EXPECT_NE(e->note.find("zoom " + std::to_string(z)), std::string::npos) << e->note;
    // The image must hold every recorded pixel.
    EXPECT_GE(e->camera.width, 0.9 * (truth.cams[z].width - 1) + 1);
    EXPECT_GE(e->camera.height, 0.9 * (truth.cams[z].height - 1) + 1);
  }
}

TEST(IntrinsicsFromRays, OneRayLengthUsesTheEdmOriginAsCentre) {
  // One ray length: the direction is taken from the EDM origin (two EDM
  // distances). Exact when the camera centre is the EDM origin: a spherical
  // model whose camera is only rotated against the EDM (a few mrad).
  CameraTool cam;
  cam.intrinsics = {1800, 1795, 655, 470};
  InstrumentModel truth = IdealModel(Kinematics::kSpherical, 1, cam);
  truth.cams[0].flange_from_cam =
      PoseBlock::FromRigid(Rigid3::FromEuler({3e-3, -2e-3, 0.5}, Eigen::Vector3d::Zero()));
  const std::vector<Record> rec = GridRecords(truth, {0}, {1.0});
  const auto e = EstimateIntrinsicsFromRays(rec, 0);
  ASSERT_TRUE(e.has_value());
  EXPECT_EQ(e->poses, 12);
  ExpectIntrinsics(truth.cams[0], *e, 1e-6);

  // Without EDM rows there is no centre and one length gives no direction.
  std::vector<Record> cam_only;
  for (const Record& r : rec) {
    if (r.tool == Tool::kCam) cam_only.push_back(r);
  }
  EXPECT_FALSE(EstimateIntrinsicsFromRays(cam_only, 0).has_value());
}

TEST(IntrinsicsFromRays, CentreOffTheEdmBiasesOneLengthOnly) {
  // The camera 5 mm off the EDM origin: with one 1 m ray length the
  // directions are off by up to ~5e-3 rad, so the estimate must move by
  // pixels; with two lengths it stays exact. This shows the two paths differ.
  CameraTool cam;
  InstrumentModel truth = IdealModel(Kinematics::kSpherical, 1, cam);
  truth.cams[0].flange_from_cam.t = {5e-3, 0.0, 0.0};
  const auto one = EstimateIntrinsicsFromRays(GridRecords(truth, {0}, {1.0}), 0);
  const auto two = EstimateIntrinsicsFromRays(GridRecords(truth, {0}, {1.0, 3.0}), 0);
  ASSERT_TRUE(one && two);
  ExpectIntrinsics(truth.cams[0], *two, 1e-6);
  EXPECT_GT(std::abs(one->camera.intrinsics[2] - cam.intrinsics[2]), 0.5);
}

TEST(IntrinsicsFromRays, TooFewPixelsOrOtherZoomGiveNothing) {
  // Klug's plan has only 3 pixels per pose (c, c + [1, 0], c + [0, 1]): a
  // homography needs 4.
  SimulationOptions o;
  o.truth = PaperTruth(1);
  const SimulatedData d = Simulate(o);
  EXPECT_FALSE(EstimateIntrinsicsFromRays(d.obs.records, 0).has_value());
  // A zoom level without camera rows.
  const std::vector<Record> rec = GridRecords(o.truth, {0}, {1.0, 3.0});
  EXPECT_TRUE(EstimateIntrinsicsFromRays(rec, 0).has_value());
  EXPECT_FALSE(EstimateIntrinsicsFromRays(rec, 1).has_value());
  EXPECT_FALSE(EstimateIntrinsicsFromRays({}, 0).has_value());
}

}  // namespace
}  // namespace rtscalib

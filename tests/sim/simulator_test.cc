#include "libcalib/sim/simulator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

#include "libcalib/model/kinematics.h"

namespace rtscalib {
namespace {

// Metre-scale points through a few rotations: round-off ~1e-16 per
// operation; 1e-12 m is generous (20 m EDM points: scaled by d).
constexpr double kExactM = 1e-12;

Eigen::Vector3d IdealEdmPoint(double phi, double theta, double d) {
  // SPEC 1: d [sin(phi) sin(theta), cos(phi) sin(theta), cos(theta)].
  return d * Eigen::Vector3d(std::sin(phi) * std::sin(theta), std::cos(phi) * std::sin(theta),
                             std::cos(theta));
}

// Sample standard deviation about a known mean of zero.
double Rms(const std::vector<double>& x) {
  double s = 0;
  for (double v : x) s += v * v;
  return std::sqrt(s / x.size());
}

// A sample rms of n N(0, sigma^2) values has relative standard deviation
// ~1 / sqrt(2 n); five of them make a test that fails only for a wrong sigma.
double RmsTolerance(double sigma, size_t n) { return 5.0 * sigma / std::sqrt(2.0 * n); }

SimulationOptions IdealOptions() {
  SimulationOptions o;
  o.truth = IdealModel(Kinematics::kSpherical, 1, CameraTool{});
  return o;
}

TEST(Simulator, SameSeedSameDataOtherSeedOtherData) {
  SimulationOptions o;
  o.truth = PaperTruth(2);
  o.plan.zooms = {0, 1};
  o.plan.faces = {1, 2};
  o.noise.angle_rad = 1e-5;
  o.noise.distance_m = 1e-4;
  o.noise.point_m = 1e-4;
  o.noise.pixel_px = 0.3;
  o.targets = ZoomScene(o.truth, 3, 4, 3.0);
  o.shots.shots_per_board = 2;
  o.seed = 42;
  const SimulatedData a = Simulate(o), b = Simulate(o);
  ASSERT_EQ(a.obs.records.size(), b.obs.records.size());
  ASSERT_EQ(a.obs.pixels.size(), b.obs.pixels.size());
  ASSERT_GT(a.obs.pixels.size(), 0u);
  for (size_t i = 0; i < a.obs.records.size(); ++i) {
    EXPECT_EQ(a.obs.records[i].x, b.obs.records[i].x) << i;  // bit-identical
  }
  for (size_t i = 0; i < a.obs.pixels.size(); ++i) {
    EXPECT_EQ(a.obs.pixels[i].uv, b.obs.pixels[i].uv) << i;
    EXPECT_EQ(a.obs.pixels[i].phi, b.obs.pixels[i].phi) << i;
  }
  o.seed = 43;
  const SimulatedData c = Simulate(o);
  ASSERT_EQ(c.obs.records.size(), a.obs.records.size());
  int differ = 0;
  for (size_t i = 0; i < a.obs.records.size(); ++i)
    differ += a.obs.records[i].x != c.obs.records[i].x;
  EXPECT_EQ(differ, static_cast<int>(a.obs.records.size())) << "every row has fresh noise";
  // The exact values do not depend on the seed.
  for (size_t i = 0; i < a.exact_points.size(); ++i)
    EXPECT_EQ(a.exact_points[i], c.exact_points[i]);
}

TEST(Simulator, PlanOfKlugSec4) {
  // Sweeps of 15 points each; per pose 2 EDM rows and 3 camera rows per zoom.
  SimulationOptions o = IdealOptions();
  const SimulatedData d = Simulate(o);
  ASSERT_EQ(d.obs.records.size(), 30u * 5);
  ASSERT_EQ(d.exact_points.size(), d.obs.records.size());
  std::map<std::string, int> per_set;
  for (const Record& r : d.obs.records) ++per_set[r.set];
  EXPECT_EQ(per_set["sweep1"], 15 * 5);
  EXPECT_EQ(per_set["sweep2"], 15 * 5);
  for (const Record& r : d.obs.records) {
    EXPECT_EQ(r.face, 1);
    if (r.set == "sweep1") {
      EXPECT_DOUBLE_EQ(r.theta, M_PI / 2);
    }
    if (r.set == "sweep2") {
      EXPECT_EQ(r.phi, 0.0);
    }
    EXPECT_GE(r.phi, 0.0);
    EXPECT_LT(r.phi, 2 * M_PI);
    EXPECT_GE(r.theta, 0.0);
    EXPECT_LE(r.theta, M_PI);
  }
  // sweep2 includes both ends (theta = 0 and pi), sweep1 excludes phi = 2 pi.
  EXPECT_EQ(d.obs.records[15 * 5].theta, 0.0);
  EXPECT_DOUBLE_EQ(d.obs.records.back().theta, M_PI);
  EXPECT_NEAR(d.obs.records[14 * 5].phi, 2 * M_PI * 14 / 15, 1e-15);
  // Grid: phi_steps x theta_steps poses, "grid" rows at the grid distances and n x n pixels.
  o.plan.sweeps = false;
  o.plan.grid_phi_steps = 3;
  o.plan.grid_theta_steps = 2;
  const SimulatedData g = Simulate(o);
  const size_t per_pose =
      o.plan.grid_edm_distances.size() + o.plan.grid_cam_ray_lengths.size() * 9;  // 3 x 3 pixels
  EXPECT_EQ(g.obs.records.size(), 6 * per_pose);
  for (const Record& r : g.obs.records) {
    EXPECT_EQ(r.set, "grid");
    EXPECT_GT(r.theta, 0.0);
    EXPECT_LT(r.theta, M_PI);
  }
}

TEST(Simulator, IdealInstrumentEdmPointsFollowSpec1) {
  SimulationOptions o = IdealOptions();
  o.plan.faces = {1, 2};
  o.plan.grid_phi_steps = 5;
  o.plan.grid_theta_steps = 4;
  const SimulatedData d = Simulate(o);
  int edm = 0;
  for (size_t i = 0; i < d.obs.records.size(); ++i) {
    const Record& r = d.obs.records[i];
    EXPECT_EQ(r.x, d.exact_points[i]) << "noise-free: the row is the exact value";
    if (r.tool != Tool::kEdm) continue;
    ++edm;
    double phi = r.phi, theta = r.theta;
    if (r.face == 2) {
      // Back to the face-1 pointing: phi + pi, 2 pi - theta; same direction.
      phi += M_PI;
      theta = 2 * M_PI - theta;
    }
    EXPECT_LT((r.x - IdealEdmPoint(phi, theta, r.d)).norm(), kExactM * r.d) << i;
    EXPECT_LT((r.x - IdealEdmPoint(r.phi, r.theta, r.d)).norm(), kExactM * r.d)
        << "the formula holds for face-2 readings as they stand: " << i;
  }
  EXPECT_GT(edm, 100);
}

TEST(Simulator, FaceTwoRowsAreTheFaceTwoReadingsOfFaceOne) {
  // SPEC 1: face 2 of (phi, theta) is (phi - pi mod 2 pi, 2 pi - theta).
  SimulationOptions o;
  o.truth = PaperTruth(1);
  o.plan.faces = {1, 2};
  const SimulatedData d = Simulate(o);
  const auto& rec = d.obs.records;
  ASSERT_EQ(rec.size() % 2, 0u);
  const size_t half = rec.size() / 2;
  std::vector<const Record*> face1;
  for (const Record& r : rec) {
    if (r.face == 1) face1.push_back(&r);
  }
  EXPECT_EQ(face1.size(), half);
  int matched = 0;
  for (const Record& r2 : rec) {
    if (r2.face != 2) continue;
    EXPECT_GT(r2.theta, M_PI - 1e-12);  // face 2: theta in [pi, 2 pi]
    EXPECT_LE(r2.theta, 2 * M_PI);
    EXPECT_GE(r2.phi, 0.0);
    EXPECT_LT(r2.phi, 2 * M_PI);
    // Invert the SPEC formula and look the face-1 twin up.
    double phi1 = std::fmod(r2.phi + M_PI, 2 * M_PI);
    const double theta1 = 2 * M_PI - r2.theta;
    for (const Record* r1 : face1) {
      if (r1->tool != r2.tool || r1->d != r2.d || r1->u != r2.u || r1->v != r2.v ||
          r1->set != r2.set)
        continue;
      // The formula in doubles: round-off of one subtraction of pi, ~1e-15.
      if (std::abs(WrapAngle(r1->phi - phi1)) < 1e-12 && std::abs(r1->theta - theta1) < 1e-12) {
        ++matched;
        break;
      }
    }
  }
  EXPECT_EQ(matched, static_cast<int>(half));
}

TEST(Simulator, PointNoiseHasTheConfiguredSigma) {
  SimulationOptions o = IdealOptions();
  o.plan.grid_phi_steps = 10;
  o.plan.grid_theta_steps = 6;
  o.noise.point_m = 2e-4;
  const SimulatedData d = Simulate(o);
  std::vector<double> dx[3];
  for (size_t i = 0; i < d.obs.records.size(); ++i) {
    const Eigen::Vector3d e = d.obs.records[i].x - d.exact_points[i];
    for (int k = 0; k < 3; ++k) dx[k].push_back(e[k]);
  }
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(Rms(dx[k]), o.noise.point_m, RmsTolerance(o.noise.point_m, dx[k].size())) << k;
  }
}

TEST(Simulator, DistanceNoiseIsAlongTheEdmRayOnly) {
  SimulationOptions o = IdealOptions();
  o.plan.sweeps = false;
  o.plan.grid_phi_steps = 12;
  o.plan.grid_theta_steps = 8;
  o.noise.distance_m = 3e-4;
  const SimulatedData d = Simulate(o);
  std::vector<double> along;
  for (size_t i = 0; i < d.obs.records.size(); ++i) {
    const Record& r = d.obs.records[i];
    const Eigen::Vector3d e = r.x - d.exact_points[i];
    if (r.tool == Tool::kCam) {
      EXPECT_EQ(e.norm(), 0.0) << "camera rays have no EDM distance";
      continue;
    }
    const Eigen::Vector3d ray = IdealEdmPoint(r.phi, r.theta, 1.0);
    EXPECT_LT((e - e.dot(ray) * ray).norm(), 1e-12) << "nothing across the ray";
    along.push_back(e.dot(ray));
  }
  ASSERT_GT(along.size(), 300u);
  EXPECT_NEAR(Rms(along), o.noise.distance_m, RmsTolerance(o.noise.distance_m, along.size()));
}

TEST(Simulator, AngleNoiseHasTheConfiguredSigma) {
  // The ideal instrument truly points at (phi + n1, theta + n2): the angles
  // read back from a noisy EDM point differ from the readings by exactly the
  // noise. Grid only (theta away from the zenith, where phi is undefined).
  SimulationOptions o = IdealOptions();
  o.plan.sweeps = false;
  o.plan.grid_phi_steps = 12;
  o.plan.grid_theta_steps = 8;
  o.noise.angle_rad = 5e-5;
  const SimulatedData d = Simulate(o);
  std::vector<double> dphi, dtheta;
  for (const Record& r : d.obs.records) {
    if (r.tool != Tool::kEdm) continue;
    dphi.push_back(WrapAngle(std::atan2(r.x.x(), r.x.y()) - r.phi));
    dtheta.push_back(std::acos(r.x.z() / r.x.norm()) - r.theta);
  }
  ASSERT_GT(dphi.size(), 300u);
  EXPECT_NEAR(Rms(dphi), o.noise.angle_rad, RmsTolerance(o.noise.angle_rad, dphi.size()));
  EXPECT_NEAR(Rms(dtheta), o.noise.angle_rad, RmsTolerance(o.noise.angle_rad, dtheta.size()));
}

TEST(Simulator, InvalidOptionsAreRejectedWithAMessage) {
  SimulationOptions o = IdealOptions();
  EXPECT_EQ(o.Check(), "");
  o.noise.point_m = -1;
  EXPECT_NE(o.Check().find("noise"), std::string::npos) << o.Check();
  EXPECT_THROW(Simulate(o), std::invalid_argument);
  o = IdealOptions();
  o.plan.faces = {3};
  EXPECT_NE(o.Check().find("plan.faces"), std::string::npos) << o.Check();
  EXPECT_NE(o.Check().find("got 3"), std::string::npos) << o.Check();
  o = IdealOptions();
  o.plan.zooms = {1};  // the ideal truth has one camera
  EXPECT_NE(o.Check().find("zoom 1"), std::string::npos) << o.Check();
  EXPECT_THROW(Simulate(o), std::invalid_argument);
  o = IdealOptions();
  o.plan.edm_distances = {1.0, 0.0};
  EXPECT_NE(o.Check().find("edm_distances"), std::string::npos) << o.Check();
  o = IdealOptions();
  o.plan.sweep_points = 3;
  EXPECT_NE(o.Check().find("sweep_points"), std::string::npos) << o.Check();
}

// The size bound counts what PlanRecords builds, exactly, without building
// it; a plan beyond it (a 1e5 x 1e5 grid: about 13 GB) is rejected before
// anything is allocated.
TEST(Simulator, PlanSizeIsCountedExactlyAndBounded) {
  const InstrumentModel truth = PaperTruth(3);
  AcquisitionPlan plan;
  EXPECT_EQ(plan.EstimatedRecords(), static_cast<double>(PlanRecords(plan, truth).size()));
  plan.grid_phi_steps = 7;
  plan.grid_theta_steps = 5;
  plan.grid_pixels_per_axis = 4;
  plan.faces = {1, 2};
  plan.zooms = {0, 2};
  EXPECT_EQ(plan.EstimatedRecords(), static_cast<double>(PlanRecords(plan, truth).size()));
  plan.sweeps = false;
  EXPECT_EQ(plan.EstimatedRecords(), static_cast<double>(PlanRecords(plan, truth).size()));
  EXPECT_EQ(plan.CheckSize(), "");

  AcquisitionPlan huge;
  huge.grid_phi_steps = 100000;
  huge.grid_theta_steps = 100000;
  EXPECT_EQ(huge.Check(),
            "the plan gives 2.2e+11 records, more than the limit of 2e+06 (grid 100000 x 100000 "
            "poses, 15 sweep points); make simulate.plan.grid.phi_steps x theta_steps, "
            "grid.pixels_per_axis or sweep_points smaller");
  SimulationOptions o = IdealOptions();
  o.plan = huge;
  EXPECT_THROW(Simulate(o), std::invalid_argument);
  AcquisitionPlan zooms;
  zooms.zooms = {0, 100};
  EXPECT_EQ(zooms.Check(),
            "simulate.plan.zooms entries must be < 100 (got 100; zoom levels are 0..N-1, SPEC 2)");
}

TEST(Simulator, PaperTruthHasOneCameraPerZoom) {
  const InstrumentModel m = PaperTruth(3);
  EXPECT_EQ(m.kinematics, Kinematics::kDh);
  ASSERT_EQ(m.NumZooms(), 3);
  for (int z = 1; z < 3; ++z) {
    // A longer focal length per zoom level (the docstring's f = 1500 * 2^z).
    EXPECT_NEAR(m.cams[z].intrinsics[0], 2 * m.cams[z - 1].intrinsics[0], 1e-9);
  }
  // Close to the ideal instrument (Klug Tables 6/7): EDM points within a
  // millimetre of SPEC 1's formula at 1 m, but not exactly on it.
  const Eigen::Vector3d p = PredictEdm(m, 0.7, 1.2, 1.0);
  const double off = (p - IdealEdmPoint(0.7, 1.2, 1.0)).norm();
  EXPECT_LT(off, 1e-3);
  EXPECT_GT(off, 1e-6);
}

TEST(Simulator, PerturbedStartMovesPosesZeroesEffectsAndIsSeeded) {
  InstrumentModel truth = PaperTruth(1);
  truth.effects.Add(Effect::kHzEccentricity);
  truth.EffectValue(Effect::kHzEccentricity) = {1e-5, 2e-5};
  const InstrumentModel a = PerturbedStart(truth, 7, 1e-3);
  const InstrumentModel b = PerturbedStart(truth, 7, 1e-3);
  const InstrumentModel c = PerturbedStart(truth, 8, 1e-3);
  EXPECT_EQ(a.base.t, b.base.t);
  EXPECT_NE(a.base.t, c.base.t);
  EXPECT_TRUE(a.effects.Has(Effect::kHzEccentricity)) << "the enabled set is kept";
  EXPECT_EQ(a.EffectValue(Effect::kHzEccentricity)[0], 0.0);
  EXPECT_EQ(a.EffectValue(Effect::kHzEccentricity)[1], 0.0);
  // Moved by about `scale`: three N(0, scale^2) components have norm below
  // 6 scale with probability > 1 - 1e-6, and above 0.01 scale likewise.
  const double dt = (a.base.ToRigid().translation - truth.base.ToRigid().translation).norm();
  EXPECT_GT(dt, 1e-5);
  EXPECT_LT(dt, 6e-3);
  const double moved = (PredictEdm(a, 0.3, 1.0, 1.0) - PredictEdm(truth, 0.3, 1.0, 1.0)).norm();
  EXPECT_GT(moved, 1e-6);
  EXPECT_LT(moved, 5e-2);
}

TEST(Simulator, FacingBoardFacesTheStation) {
  // SPEC 7 board frame: x along a row (right, as seen from the printed side),
  // y down a column, z out of the back, i.e. away from a viewer at the station.
  const Eigen::Vector3d station(1.0, -2.0, 0.5);
  const double phi = 0.8, distance = 4.0, height = 0.3;
  const TagBoard b = FacingBoard(station, 10, 3, 5, 0.05, distance, phi, height, 0.0);
  EXPECT_EQ(b.first_id, 10);
  EXPECT_EQ(b.NumTags(), 15);
  EXPECT_NEAR(b.spacing, 0.25 * 0.05, 1e-15);
  const Eigen::Vector3d centre =
      station + Eigen::Vector3d(distance * std::sin(phi), distance * std::cos(phi), height);
  EXPECT_LT((b.CentreInRef() - centre).norm(), kExactM);
  const Eigen::Matrix3d& r = b.ref_from_board.rotation;
  const Eigen::Vector3d view = (centre - station).normalized();
  EXPECT_GT(r.col(2).dot(view), 0.99) << "z points away from the station (nearly horizontal view)";
  EXPECT_NEAR(r.col(0).z(), 0.0, 1e-12) << "rows are horizontal without tilt";
  EXPECT_NEAR(r.col(1).z(), -1.0, 1e-12) << "y points down";
  // "Right" as seen from the station: x = view direction turned clockwise
  // (from above) by 90 degrees, i.e. (cos phi, -sin phi, 0).
  EXPECT_LT((r.col(0) - Eigen::Vector3d(std::cos(phi), -std::sin(phi), 0)).norm(), 1e-12);
}

}  // namespace
}  // namespace rtscalib

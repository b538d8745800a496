#include "libcalib/extract/extract.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "libcalib/sim/simulator.h"
#include "tests/extract/extract_fixture.h"

namespace rtscalib {
namespace {

using fixture::MaxHeldOutError;
using fixture::PaperPlan;
using fixture::PaperPlanRecords;
using fixture::RandomTruth;
using ::testing::HasSubstr;

// Held-out points at 5 m. The extraction is exact for an instrument without
// effects, so only double round-off remains: points of ~1 m carry ~1e-16 m,
// the circle normals ~1e-15 rad (fits of 10-15 well spread points), the
// camera rotation ~1e-16 / 1e-3 = 1e-13 rad (its points are 1 px = 1 mm apart
// at 1 m, f = 1000 px), i.e. < 1e-12 m at 5 m. 1e-9 m leaves three orders of
// magnitude and still fails for any modelling mistake (they are >= 1e-7 m).
constexpr double kExactM = 1e-9;
constexpr double kHeldOutDistance = 5.0;

TEST(ExtractDhModel, SmallOffsetTruthsPredictHeldOutPointsExactly) {
  std::mt19937 rng(21);
  for (int trial = 0; trial < 10; ++trial) {
    // PLT 300 scale: offsets of 0.1 mm, angles of 1e-3 rad (Klug Tables 6/7).
    const InstrumentModel truth = RandomTruth(rng, 1e-4, 1e-3);
    const auto records = PaperPlanRecords(truth);
    const ExtractionResult r = ExtractDhModel(records, truth.cams);
    EXPECT_EQ(r.model.kinematics, Kinematics::kDh);
    const auto e = MaxHeldOutError(truth, r.model, kHeldOutDistance);
    EXPECT_LT(e.edm, kExactM) << trial;
    EXPECT_LT(e.cam, kExactM) << trial;
    EXPECT_EQ(r.joints[0].trajectory, Trajectory::kCircle);
    EXPECT_EQ(r.joints[1].trajectory, Trajectory::kCircle);
    EXPECT_EQ(r.sweeps[0].set, "sweep1");
    EXPECT_EQ(r.sweeps[1].set, "sweep2");
    // 15 + 10 poses outside the critical regions, one of them, (0, pi/2), in both.
    EXPECT_EQ(r.edm_poses, 24);
    EXPECT_EQ(r.camera_poses[0], 24);
  }
}

// Exactness does not depend on small offsets: 5 cm links and tools, 0.3 rad
// angle errors, several zoom levels.
TEST(ExtractDhModel, LargeOffsetTruthsAreExactToo) {
  std::mt19937 rng(22);
  for (int trial = 0; trial < 5; ++trial) {
    const InstrumentModel truth = RandomTruth(rng, 0.05, 0.3, 3);
    PaperPlan plan;
    plan.zooms = {0, 1, 2};
    const ExtractionResult r = ExtractDhModel(PaperPlanRecords(truth, plan), truth.cams);
    const auto e = MaxHeldOutError(truth, r.model, kHeldOutDistance);
    EXPECT_LT(e.edm, kExactM) << trial;
    EXPECT_LT(e.cam, kExactM) << trial;
    EXPECT_EQ(r.model.NumZooms(), 3);
  }
}

// Lens distortion: the exact back-projection uses the configured distortion.
TEST(ExtractDhModel, DistortedCameraWithGivenIntrinsicsIsExact) {
  std::mt19937 rng(23);
  InstrumentModel truth = RandomTruth(rng, 1e-4, 1e-3);
  truth.cams[0].intrinsics = {1210.0, 1190.0, 655.3, 470.8};
  // k1 k2 p1 p2 k3 k4 k5 k6 s1 s2 s3 s4 taux tauy
  truth.cams[0].distortion = {-0.12, 0.03, 2e-4, -1e-4, 0, 0, 0, 0, 1e-4, 0, -1e-4, 0, 1e-3, -2e-3};
  const ExtractionResult r = ExtractDhModel(PaperPlanRecords(truth), truth.cams);
  const auto e = MaxHeldOutError(truth, r.model, kHeldOutDistance);
  EXPECT_LT(e.edm, kExactM);
  EXPECT_LT(e.cam, kExactM);
}

// No intrinsics given: the principal point is the pixel most rows share (the
// centre of each triplet) and f comes from the 1 px chords; exact for a
// pinhole camera. The same tolerance as above: the chord formula is exact,
// and f's round-off (~1e-16 / 1e-3 relative) moves a 5 m point by < 1e-12 m.
TEST(ExtractDhModel, UndistortedCameraWithoutIntrinsicsIsExact) {
  std::mt19937 rng(24);
  InstrumentModel truth = RandomTruth(rng, 1e-4, 1e-3);
  truth.cams[0].intrinsics = {1500.0, 1480.0, 640.5, 479.5};
  const ExtractionResult r = ExtractDhModel(PaperPlanRecords(truth), {});
  ASSERT_TRUE(r.principal_points[0]);
  EXPECT_TRUE(r.principal_points[0]->detected);
  EXPECT_EQ(r.principal_points[0]->pixel, Eigen::Vector2d(640.5, 479.5));
  // The chord (~1e-3 m) carries ~1e-16 m of round-off: f to ~1e-13 relative,
  // ~1e-10 px; 1e-6 px is generous.
  EXPECT_NEAR(r.model.cams[0].intrinsics[0], 1500.0, 1e-6);
  EXPECT_NEAR(r.model.cams[0].intrinsics[1], 1480.0, 1e-6);
  const auto e = MaxHeldOutError(truth, r.model, kHeldOutDistance);
  EXPECT_LT(e.edm, kExactM);
  EXPECT_LT(e.cam, kExactM);
}

// The paper's Eq. 69/70 (unit axes, ray length not corrected, Eq. 72/73):
// the normalised +1 px axes are tilted towards -z by eps = 1/(2f); the best
// rotation for both tilts turns the camera by sqrt(2) eps about (-1, 1, 0)
// (first-order analysis of Eq. 53-56), so a point at range d moves by about
// sqrt(2) eps d. At f = 1000 px and 5 m: ~3.5 mm. The EDM stays exact (its
// frame's roll is a convention and its ray comes from the EDM rows).
TEST(ExtractDhModel, PaperUnitAxesCostAboutOneOverTwoFRadians) {
  std::mt19937 rng(25);
  const InstrumentModel truth = RandomTruth(rng, 1e-4, 1e-3);
  ExtractOptions options;
  options.exact_camera_rays = false;
  const ExtractionResult r = ExtractDhModel(PaperPlanRecords(truth), truth.cams, options);
  const auto e = MaxHeldOutError(truth, r.model, kHeldOutDistance);
  const double eps = 1.0 / (2.0 * truth.cams[0].intrinsics[0]);
  EXPECT_LT(e.edm, kExactM);
  EXPECT_GT(e.cam, 0.5 * std::sqrt(2.0) * eps * kHeldOutDistance);
  EXPECT_LT(e.cam, 1.5 * std::sqrt(2.0) * eps * kHeldOutDistance);
  // The rotation error itself: angle between truth and extracted camera tools.
  const Eigen::Matrix3d dr = truth.cams[0].flange_from_cam.ToRigid().rotation.transpose() *
                             r.model.cams[0].flange_from_cam.ToRigid().rotation;
  EXPECT_NEAR(Eigen::AngleAxisd(dr).angle(), std::sqrt(2.0) * eps, 0.05 * std::sqrt(2.0) * eps);
}

// Klug Table 1: the extraction of the ideal instrument gives link 1 =
// {d 0, gamma phi - pi/2, alpha pi/2, a 0}, link 2 = 0, M_B = Rx(pi). Exact
// geometry, unit scale: 1e-12.
TEST(ExtractDhModel, IdealInstrumentGivesTable1) {
  const InstrumentModel ideal = IdealModel(Kinematics::kDh, 1, CameraTool{});
  const ExtractionResult r = ExtractDhModel(PaperPlanRecords(ideal), ideal.cams);
  const auto& l1 = r.model.links[0].p;
  EXPECT_NEAR(l1[kDhD], 0.0, 1e-12);
  EXPECT_NEAR(l1[kDhGamma], -M_PI / 2, 1e-12);
  EXPECT_NEAR(l1[kDhAlpha], M_PI / 2, 1e-12);
  EXPECT_NEAR(l1[kDhA], 0.0, 1e-12);
  for (double p : r.model.links[1].p) EXPECT_NEAR(p, 0.0, 1e-12);
  EXPECT_LT((r.model.base.ToRigid().rotation - Rx(M_PI)).norm(), 1e-12);
  EXPECT_LT(r.model.base.ToRigid().translation.norm(), 1e-12);
  EXPECT_EQ(r.joints[0].constellation, LineConstellation::kIntersecting);
  EXPECT_EQ(r.joints[1].constellation, LineConstellation::kIdentical);
  // Sign correction (Eq. 31): phi turns clockwise seen from above, so axis 1
  // points down; theta tilts the line of sight from up (+z) to +y at phi = 0,
  // a positive rotation about -x.
  EXPECT_LT((r.joints[0].axis - Eigen::Vector3d(0, 0, -1)).norm(), 1e-12);
  EXPECT_LT((r.joints[1].axis - Eigen::Vector3d(-1, 0, 0)).norm(), 1e-12);
  EXPECT_NEAR(r.joints[0].radius, 1.0, 1e-12);
  EXPECT_LT(MaxHeldOutError(ideal, r.model, kHeldOutDistance).cam, kExactM);
}

// The PLT 300 of Klug Tables 6/7 as truth: the extraction is exact, and its
// parameters are the paper's Table 1/2 pattern: link 1 alpha ~ pi/2, a ~ d ~ 0;
// the base's 0.0504 rad about the vertical moves into link 1's gamma offset
// (Rz(g) Rx(pi) = Rx(pi) Rz(-g)), giving -1.5203 - 0.0504 ~ -pi/2.
// Tolerance 1e-3 rad / 1e-3 m: the table's own link-2 and tool offsets are
// <= 2.1e-4, and the base's alpha is 3.1416 (7e-6 from pi).
TEST(ExtractDhModel, Plt300TruthIsExtracted) {
  const InstrumentModel truth = fixture::Plt300Truth();
  const ExtractionResult r = ExtractDhModel(PaperPlanRecords(truth), truth.cams);
  const auto e = MaxHeldOutError(truth, r.model, kHeldOutDistance);
  EXPECT_LT(e.edm, kExactM);
  EXPECT_LT(e.cam, kExactM);
  const auto& l1 = r.model.links[0].p;
  EXPECT_NEAR(l1[kDhAlpha], 1.570808, 1e-3);
  EXPECT_NEAR(l1[kDhGamma], -1.5203 - 0.0504, 1e-3);
  EXPECT_NEAR(l1[kDhA], 0.0, 1e-3);
  EXPECT_NEAR(l1[kDhD], 0.0, 1e-3);
  const Eigen::Vector3d base = r.model.base.Euler();
  EXPECT_NEAR(std::abs(base[0]), M_PI, 1e-3);
  EXPECT_NEAR(base[1], 0.0, 1e-3);
  EXPECT_NEAR(base[2], 0.0, 1e-3);
  EXPECT_LT(r.model.edm.ToRigid().translation.norm(), 1e-3);
}

// The set label is only a hint: without labels, with shuffled rows, the same
// sweeps are found and the model is the same.
TEST(ExtractDhModel, NoLabelsAndShuffledRowsGiveTheSameModel) {
  std::mt19937 rng(26);
  const InstrumentModel truth = RandomTruth(rng, 1e-4, 1e-3);
  PaperPlan plan;
  plan.labels = false;
  auto records = PaperPlanRecords(truth, plan);
  std::shuffle(records.begin(), records.end(), rng);
  const ExtractionResult r = ExtractDhModel(records, truth.cams);
  EXPECT_EQ(r.sweeps[0].NumPoints(), 15);
  EXPECT_NEAR(r.sweeps[0].constant_control, M_PI / 2, 1e-15);
  EXPECT_EQ(r.sweeps[1].NumPoints(), 10);  // 15 minus 5 in the critical regions
  EXPECT_NEAR(r.sweeps[1].constant_control, 0.0, 1e-15);
  const auto e = MaxHeldOutError(truth, r.model, kHeldOutDistance);
  EXPECT_LT(e.edm, kExactM);
  EXPECT_LT(e.cam, kExactM);
}

// Excluded rows are counted, never silently dropped: the plan's theta = 0 and
// theta >= 141 deg poses (5 poses x 5 rows) lie in the critical regions, and
// face-2 rows are not used.
TEST(ExtractDhModel, ExcludedRowsAreCounted) {
  std::mt19937 rng(27);
  const InstrumentModel truth = RandomTruth(rng, 1e-4, 1e-3);
  auto records = PaperPlanRecords(truth);
  const size_t n = records.size();
  for (size_t i = 0; i < 7; ++i) {
    Record r = records[i];
    r.face = 2;
    OtherFace(r.phi, r.theta, &r.phi, &r.theta);
    records.push_back(r);
  }
  const ExtractionResult r = ExtractDhModel(records, truth.cams);
  EXPECT_EQ(r.excluded.critical_zenith, 25);
  EXPECT_EQ(r.excluded.face2, 7);
  EXPECT_EQ(r.usable_rows, static_cast<int>(n) - 25);
  // Wider limits keep the theta = 0 pose out (zenith 0 < 1e-3) but take the rest.
  ExtractOptions wide;
  wide.critical_region.min_zenith_rad = 1e-3;
  wide.critical_region.max_zenith_rad = M_PI;
  const ExtractionResult r2 = ExtractDhModel(records, truth.cams, wide);
  EXPECT_EQ(r2.excluded.critical_zenith, 5);
  EXPECT_EQ(r2.sweeps[1].NumPoints(), 14);
}

// EDM only (no camera rows, no cameras): the EDM x axis falls back to the
// flange x axis; EDM points stay exact.
TEST(ExtractDhModel, EdmOnlyRecords) {
  std::mt19937 rng(28);
  const InstrumentModel truth = RandomTruth(rng, 1e-4, 1e-3);
  PaperPlan plan;
  plan.cam = false;
  const ExtractionResult r = ExtractDhModel(PaperPlanRecords(truth, plan), {});
  EXPECT_EQ(r.model.NumZooms(), 0);
  std::mt19937 rng2(1);
  std::uniform_real_distribution<double> a(0.1, 3.0);
  for (int i = 0; i < 50; ++i) {
    const double phi = 2 * a(rng2), theta = a(rng2);
    EXPECT_LT((PredictEdm(truth, phi, theta, 5.0) - PredictEdm(r.model, phi, theta, 5.0)).norm(),
              kExactM);
  }
  bool noted = false;
  for (const auto& n : r.notes) noted |= n.find("flange x (no camera)") != std::string::npos;
  EXPECT_TRUE(noted);
}

// Camera only: the joint circles come from the principal-point rows.
TEST(ExtractDhModel, CameraOnlyRecords) {
  std::mt19937 rng(29);
  const InstrumentModel truth = RandomTruth(rng, 1e-4, 1e-3);
  PaperPlan plan;
  plan.edm = false;
  const ExtractionResult r = ExtractDhModel(PaperPlanRecords(truth, plan), truth.cams);
  EXPECT_EQ(r.sweeps[0].tool, Tool::kCam);
  EXPECT_EQ(r.sweeps[0].pixel_offset, Eigen::Vector2d::Zero());
  EXPECT_LT(MaxHeldOutError(truth, r.model, kHeldOutDistance).cam, kExactM);
  EXPECT_EQ(r.edm_poses, 0);
}

// The simulator's plan (libcalib/sim): sweeps plus a grid in both faces with
// extra distances and pixels, seven zoom levels of the PLT 300-like truth,
// no labels, no intrinsics. The sweep search must still find the joint
// sweeps, the principal points and f, and the model must be exact.
TEST(ExtractDhModel, SimulatorPlanWithGridBothFacesAndSevenZooms) {
  AcquisitionPlan plan;
  plan.zooms = {0, 1, 2, 3, 4, 5, 6};
  plan.faces = {1, 2};
  plan.grid_phi_steps = 12;
  plan.grid_theta_steps = 6;
  const InstrumentModel truth = PaperTruth(7);
  auto records = PlanRecords(plan, truth);
  for (Record& r : records) r.set.clear();
  const ExtractionResult r = ExtractDhModel(records, {});
  EXPECT_GT(r.excluded.face2, 0);
  const auto e = MaxHeldOutError(truth, r.model, kHeldOutDistance);
  EXPECT_LT(e.edm, kExactM);
  // f up to 96,000 px at zoom 6: the camera rotation's round-off grows with
  // f (1 px = 1e-5 m at 1 m), ~1e-16 * f rad; 1e-9 m still holds at 5 m.
  EXPECT_LT(e.cam, kExactM);
  for (int z = 0; z < 7; ++z) {
    ASSERT_TRUE(r.principal_points[z]);
    EXPECT_EQ(r.principal_points[z]->pixel,
              Eigen::Vector2d(truth.cams[z].intrinsics[2], truth.cams[z].intrinsics[3]));
  }
}

// ----- errors ---------------------------------------------------------------

// The end effector on joint 1's axis: the joint-1 sweep recorded with the
// line of sight straight up (theta = 0, allowed by the options here) and an
// instrument whose EDM sits on the vertical axis.
TEST(ExtractDhModel, EndEffectorOnTheAxisIsAClearError) {
  const InstrumentModel ideal = IdealModel(Kinematics::kDh, 1, CameraTool{});
  PaperPlan plan;
  plan.sweep1_theta = 0.0;
  plan.cam = false;
  ExtractOptions options;
  options.critical_region.min_zenith_rad = 0.0;
  try {
    ExtractDhModel(PaperPlanRecords(ideal, plan), {}, options);
    FAIL() << "expected ExtractionError";
  } catch (const ExtractionError& e) {
    const std::string msg = e.what();
    EXPECT_THAT(msg, HasSubstr("joint-1 sweep (face 1, edm, d = 1 m, theta = 0 rad constant, "
                               "15 points"));
    EXPECT_THAT(msg, HasSubstr("lies on the joint axis"));
    EXPECT_THAT(msg, HasSubstr("fit RMS"));
    EXPECT_THAT(msg, HasSubstr("footnote 4"));
    EXPECT_THAT(msg, HasSubstr("a longer EDM distance or a pixel off the principal point"));
    EXPECT_THAT(msg, HasSubstr("another fixed theta"));
    EXPECT_THAT(msg, HasSubstr("lines 2-"));
  }
}

// Small link offsets make the "on axis" trajectory a tiny circle (radius of
// the offsets, 1e-4 m): still below min_radius_m, still the same error.
TEST(ExtractDhModel, TinyCircleAroundTheAxisIsOnAxis) {
  std::mt19937 rng(30);
  const InstrumentModel truth = RandomTruth(rng, 1e-4, 1e-5);
  PaperPlan plan;
  plan.sweep1_theta = 0.0;
  plan.cam = false;
  ExtractOptions options;
  options.critical_region.min_zenith_rad = 0.0;
  EXPECT_THROW(
      {
        try {
          ExtractDhModel(PaperPlanRecords(truth, plan), {}, options);
        } catch (const ExtractionError& e) {
          EXPECT_THAT(std::string(e.what()), HasSubstr("lies on the joint axis"));
          throw;
        }
      },
      ExtractionError);
}

// Points on neither a circle nor a line (a joint that wobbles by 5 cm).
TEST(ExtractDhModel, NeitherCircleNorLineIsAClearError) {
  const InstrumentModel ideal = IdealModel(Kinematics::kDh, 1, CameraTool{});
  PaperPlan plan;
  plan.cam = false;
  auto records = PaperPlanRecords(ideal, plan);
  for (Record& r : records) {
    if (r.set == "sweep1") r.x.z() += 0.05 * std::sin(3 * r.phi) + 0.05 * std::cos(2 * r.phi);
  }
  try {
    ExtractDhModel(records, {});
    FAIL() << "expected ExtractionError";
  } catch (const ExtractionError& e) {
    const std::string msg = e.what();
    EXPECT_THAT(msg, HasSubstr("joint-1 sweep (face 1, edm, d = 1 m, theta = 1.5708 rad constant, "
                               "15 points"));
    EXPECT_THAT(msg, HasSubstr("neither on a circle (fit RMS"));
    EXPECT_THAT(msg, HasSubstr("nor on a line (fit RMS"));
    EXPECT_THAT(msg, HasSubstr("repeat the recording with other fixed joint settings"));
    EXPECT_THAT(msg, HasSubstr("a longer EDM distance or a pixel off the principal point"));
  }
}

// A linear trajectory is a prismatic joint, which the model cannot hold.
TEST(ExtractDhModel, LinearTrajectoryIsPrismaticAndRejected) {
  const InstrumentModel ideal = IdealModel(Kinematics::kDh, 1, CameraTool{});
  PaperPlan plan;
  plan.cam = false;
  plan.sweep2_phi = 1.0;  // no pose shared with sweep 1
  plan.sweep1_theta = 1.5;
  auto records = PaperPlanRecords(ideal, plan);
  for (Record& r : records) {
    if (r.set == "sweep2") {
      r.x = Eigen::Vector3d(0.1, 0.2, 0.3) + r.theta * r.d * Eigen::Vector3d(0, 0.3, 0.4);
    }
  }
  try {
    ExtractDhModel(records, {});
    FAIL() << "expected ExtractionError";
  } catch (const ExtractionError& e) {
    EXPECT_THAT(std::string(e.what()), HasSubstr("joint-2 sweep"));
    EXPECT_THAT(std::string(e.what()), HasSubstr("prismatic joint"));
  }
}

TEST(ExtractDhModel, MissingSweepIsAClearError) {
  std::mt19937 rng(31);
  const InstrumentModel truth = RandomTruth(rng, 1e-4, 1e-3);
  std::vector<Record> records;
  std::uniform_real_distribution<double> a(0.3, 2.0);
  PaperPlan plan;
  for (int i = 0; i < 40; ++i) {
    fixture::AddPose(truth, plan, 3 * a(rng), a(rng), "random", &records);
  }
  try {
    ExtractDhModel(records, truth.cams);
    FAIL() << "expected ExtractionError";
  } catch (const ExtractionError& e) {
    EXPECT_THAT(std::string(e.what()), HasSubstr("no joint-1 sweep found"));
    EXPECT_THAT(std::string(e.what()), HasSubstr("the same theta and different phi"));
  }
}

TEST(ExtractDhModel, MissingCameraTripletIsAClearError) {
  std::mt19937 rng(32);
  const InstrumentModel truth = RandomTruth(rng, 1e-4, 1e-3);
  auto records = PaperPlanRecords(truth);
  // Keep only the camera rows in the principal point's row: no +1 px in v.
  auto no_v_step = [](const Record& r) { return r.tool == Tool::kCam && r.v != 480.0; };
  records.erase(std::remove_if(records.begin(), records.end(), no_v_step), records.end());
  // With intrinsics every row is used, but these lie on one camera-frame line.
  for (const std::vector<CameraTool>& cams : {truth.cams, std::vector<CameraTool>{}}) {
    try {
      ExtractDhModel(records, cams);
      FAIL() << "expected ExtractionError";
    } catch (const ExtractionError& e) {
      EXPECT_THAT(std::string(e.what()), HasSubstr("camera tool of zoom 0"));
      EXPECT_THAT(std::string(e.what()), HasSubstr("+1 px in u and in v"));
    }
  }
}

// Camera rows spread over the image but no pixel triplet: with the
// intrinsics known, every row is an exact correspondence.
TEST(ExtractDhModel, CameraRowsWithoutTripletsUseEveryRowGivenIntrinsics) {
  std::mt19937 rng(34);
  InstrumentModel truth = RandomTruth(rng, 1e-4, 1e-3);
  truth.cams[0].distortion[kK1] = -0.1;
  PaperPlan plan;
  plan.cam = false;
  auto records = PaperPlanRecords(truth, plan);
  std::uniform_real_distribution<double> px(50.0, 1200.0), py(50.0, 900.0), d(1.0, 3.0);
  const size_t n = records.size();
  for (size_t i = 0; i < n; ++i) {
    if (records[i].d != 1.0) continue;
    for (int k = 0; k < 2; ++k) {
      Record r = records[i];
      r.tool = Tool::kCam;
      r.u = px(rng);
      r.v = py(rng);
      r.d = d(rng);
      r.x = PredictCam(truth, 0, r.phi, r.theta, r.u, r.v, r.d);
      records.push_back(r);
    }
  }
  const ExtractionResult r = ExtractDhModel(records, truth.cams);
  EXPECT_EQ(r.camera_poses[0], 24);
  const auto e = MaxHeldOutError(truth, r.model, kHeldOutDistance);
  EXPECT_LT(e.edm, kExactM);
  EXPECT_LT(e.cam, kExactM);
}

TEST(ExtractDhModel, BadOptionsAreRejected) {
  ExtractOptions o;
  o.critical_region.min_zenith_rad = 2.0;
  o.critical_region.max_zenith_rad = 1.0;
  EXPECT_NE(o.Check(), "");
  EXPECT_THROW(ExtractDhModel({}, {}, o), std::invalid_argument);
  EXPECT_EQ(ExtractOptions().Check(), "");
}

}  // namespace
}  // namespace rtscalib

namespace rtscalib {
namespace {

// Noise: sigma = 1e-5 m on every point coordinate (an RTS's angular noise of
// ~2" at 1 m). The extraction must still classify, sign and frame everything
// (no error), and its errors follow first-order propagation:
//   EDM: circle normals ~ sigma / (r sqrt(N/2)) ~ 5e-6 rad (N = 10..15, r = 1 m;
//        the joint-2 arc spans only 125 deg, which multiplies the centre error
//        by ~3), the EDM ray ~ sigma sqrt(2) / (1 m sqrt(24)) ~ 3e-6 rad; at
//        5 m a few 1e-5 .. 1e-4 m. Bound 1e-3 m (observed worst over 20
//        truths: 3.2e-4).
//   camera: its rotation comes from points 1 px = 1 mm apart, so noise is
//        amplified by f: ~ sigma f sqrt(2) / sqrt(24 poses) ~ 3e-3 rad, ~1.5 cm
//        at 5 m. Bound 0.1 m (observed worst: 3.5 cm). The refinement
//        (libcalib/fit) removes this; the extraction only starts it.
TEST(ExtractDhModel, NoisyRecordsGiveAStartingModel) {
  std::mt19937 rng(33);
  const double sigma = 1e-5;
  std::normal_distribution<double> noise(0.0, sigma);
  for (int trial = 0; trial < 5; ++trial) {
    const InstrumentModel truth = RandomTruth(rng, 1e-4, 1e-3);
    auto records = PaperPlanRecords(truth);
    for (Record& r : records) r.x += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    const ExtractionResult r = ExtractDhModel(records, truth.cams);
    EXPECT_LT(r.joints[0].circle_rms, 3 * sigma);
    const auto e = MaxHeldOutError(truth, r.model, kHeldOutDistance);
    EXPECT_LT(e.edm, 1e-3) << trial;
    EXPECT_LT(e.cam, 0.1) << trial;
  }
}

}  // namespace
}  // namespace rtscalib

#include "libcalib/eval/error_measures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "libcalib/model/kinematics.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib {
namespace {

// Hand-computed statistics of a few millimetre-scale numbers: round-off only.
constexpr double kRoundOff = 1e-15;
// Model predictions of metre-scale points through a few rotations: round-off,
// ~1e-16 per operation; 1e-12 m is generous.
constexpr double kExactM = 1e-12;

TEST(ErrorMeasures, StatsOfIsEq92And93) {
  // d = {1, 2, 3, 4} mm: mean 2.5 mm (Eq. 92), std sqrt((2.25 + 0.25 + 0.25 +
  // 2.25) / 3) = sqrt(5/3) mm (Eq. 93, N - 1), rms sqrt(30/4) mm, max 4 mm.
  const ErrorStats s = StatsOf({1e-3, 2e-3, 3e-3, 4e-3});
  EXPECT_EQ(s.n, 4);
  EXPECT_NEAR(s.mean_m, 2.5e-3, kRoundOff);
  EXPECT_NEAR(s.std_m, std::sqrt(5.0 / 3.0) * 1e-3, kRoundOff);
  EXPECT_NEAR(s.rms_m, std::sqrt(7.5) * 1e-3, kRoundOff);
  EXPECT_EQ(s.max_m, 4e-3);
}

TEST(ErrorMeasures, StatsOfDegenerateInputs) {
  const ErrorStats empty = StatsOf({});
  EXPECT_EQ(empty.n, 0);
  EXPECT_EQ(empty.mean_m, 0.0);
  EXPECT_EQ(empty.std_m, 0.0);
  // One point: Eq. 93 divides by N - 1 = 0; the std is reported as 0.
  const ErrorStats one = StatsOf({7e-3});
  EXPECT_EQ(one.n, 1);
  EXPECT_NEAR(one.mean_m, 7e-3, kRoundOff);
  EXPECT_EQ(one.std_m, 0.0);
  EXPECT_NEAR(one.rms_m, 7e-3, kRoundOff);
  EXPECT_NEAR(one.max_m, 7e-3, kRoundOff);
}

TEST(ErrorMeasures, ScalarisedObjectiveIsEq98) {
  ErrorStats s;
  s.mean_m = 2e-3;
  s.std_m = 5e-4;
  EXPECT_NEAR(ScalarisedObjective(s), 2.5e-3, kRoundOff);
  EXPECT_NEAR(ScalarisedObjective(s, 2.0, 0.5), 4.25e-3, kRoundOff);
}

// One pose of Klug's plan (EDM at 1 m and 2 m; camera rays of 1 m at the
// principal point and 1 px off it in u and v) under `m`, noise-free.
std::vector<Record> OnePose(const InstrumentModel& m, double phi, double theta) {
  std::vector<Record> out;
  for (double d : {1.0, 2.0}) {
    Record r;
    r.phi = phi;
    r.theta = theta;
    r.tool = Tool::kEdm;
    r.d = d;
    r.x = PredictEdm(m, phi, theta, d);
    out.push_back(r);
  }
  const auto& k = m.cams[0].intrinsics;
  for (const auto& [du, dv] : {std::pair<double, double>{0, 0}, {1, 0}, {0, 1}}) {
    Record r;
    r.phi = phi;
    r.theta = theta;
    r.tool = Tool::kCam;
    r.u = k[2] + du;
    r.v = k[3] + dv;
    r.d = 1.0;
    r.x = PredictCam(m, 0, phi, theta, r.u, r.v, r.d);
    out.push_back(r);
  }
  return out;
}

TEST(ErrorMeasures, RecordResidualsAreMeasuredMinusModel) {
  const InstrumentModel m = IdealModel(Kinematics::kSpherical, 1, CameraTool{});
  std::vector<Record> rec = OnePose(m, 0.4, 1.1);
  rec[0].x += Eigen::Vector3d(3e-3, -4e-3, 0);  // 5 mm
  Record bad = rec[2];
  bad.zoom = 3;  // the model has one zoom level: cannot be evaluated
  rec.push_back(bad);
  const std::vector<RecordResidual> res = RecordResiduals(m, rec);
  ASSERT_EQ(res.size(), rec.size());
  EXPECT_EQ(res[0].index, 0);
  EXPECT_TRUE(res[0].valid);
  EXPECT_NEAR(res[0].distance, 5e-3, kExactM);
  EXPECT_LT((res[0].delta - Eigen::Vector3d(3e-3, -4e-3, 0)).norm(), kExactM);
  for (int i = 1; i < 5; ++i) {
    EXPECT_TRUE(res[i].valid);
    EXPECT_LT(res[i].distance, kExactM);
  }
  EXPECT_EQ(res[5].index, 5);
  EXPECT_FALSE(res[5].valid);
}

TEST(ErrorMeasures, MethodAUsesEdmAndPrincipalPointOnly) {
  // Hand-computed: EDM rows off by 1 mm and 3 mm, camera rows at c, c + [1, 0],
  // c + [0, 1] off by 2, 10 and 20 mm. Method A (Klug Table 3) takes the EDM
  // rows and the principal-point camera row only:
  //   edm {1, 3} mm: mean 2, std sqrt(2); cam {2} mm: mean 2, std 0;
  //   compound {1, 3, 2} mm: mean 2, std 1.
  const InstrumentModel m = IdealModel(Kinematics::kSpherical, 1, CameraTool{});
  std::vector<Record> rec = OnePose(m, 1.3, 1.4);
  const Eigen::Vector3d dir(2.0 / 3, -1.0 / 3, 2.0 / 3);  // unit vector
  const double err_mm[5] = {1, 3, 2, 10, 20};
  for (int i = 0; i < 5; ++i) rec[i].x += err_mm[i] * 1e-3 * dir;
  const ModelErrors a = EvaluateRecords(m, rec, ErrorMethod::kA);
  // Distances of perturbed metre-scale points: round-off ~1e-16 m.
  const double tol = 1e-12;
  EXPECT_EQ(a.edm.n, 2);
  EXPECT_NEAR(a.edm.mean_m, 2e-3, tol);
  EXPECT_NEAR(a.edm.std_m, std::sqrt(2.0) * 1e-3, tol);
  EXPECT_EQ(a.cam.n, 1);
  EXPECT_NEAR(a.cam.mean_m, 2e-3, tol);
  EXPECT_EQ(a.compound.n, 3);
  EXPECT_NEAR(a.compound.mean_m, 2e-3, tol);
  EXPECT_NEAR(a.compound.std_m, 1e-3, tol);
  EXPECT_NEAR(a.compound.max_m, 3e-3, tol);
}

TEST(ErrorMeasures, MethodBCountsEveryCameraRowAndTheEdmOffAxisPoint) {
  // Every camera row off by the same 2 mm vector (the measured camera x axis,
  // a difference of two camera points, is then unchanged), EDM rows exact.
  // Method B: cam {2, 2, 2} mm; EDM {0, 0} plus one off-axis point per pose
  // (Eq. 79/80), which is exact because the ideal model's EDM x axis is the
  // camera x axis.
  const InstrumentModel m = IdealModel(Kinematics::kSpherical, 1, CameraTool{});
  std::vector<Record> rec = OnePose(m, 2.2, 1.0);
  const Eigen::Vector3d shift(0, 2e-3, 0);
  for (int i = 2; i < 5; ++i) rec[i].x += shift;
  const ModelErrors b = EvaluateRecords(m, rec, ErrorMethod::kB);
  // The off-axis point's direction comes from a 1e-3 m difference of 1 m
  // points: round-off 1e-16 / 1e-3 relative on a 1 m arm, ~1e-12 m.
  const double tol = 1e-11;
  EXPECT_EQ(b.cam.n, 3);
  EXPECT_NEAR(b.cam.mean_m, 2e-3, tol);
  EXPECT_NEAR(b.cam.std_m, 0.0, tol);
  EXPECT_EQ(b.edm.n, 3);
  EXPECT_LT(b.edm.max_m, tol);
  EXPECT_EQ(b.compound.n, 6);
  EXPECT_NEAR(b.compound.mean_m, 1e-3, tol);
}

TEST(ErrorMeasures, RotationAboutTheEdmRayCountsInMethodBOnly) {
  // The model's EDM frame turned by alpha about its own ray predicts every
  // EDM point exactly (method A sees nothing), but its x axis is off the
  // measured one (the camera's) by alpha: B's off-axis point, 1 m from the
  // ray, is off by the chord 2 sin(alpha / 2).
  const InstrumentModel truth = IdealModel(Kinematics::kSpherical, 1, CameraTool{});
  std::vector<Record> rec;
  for (double phi : {0.0, 1.0, 2.5, 4.0}) {
    for (const Record& r : OnePose(truth, phi, 1.2)) rec.push_back(r);
  }
  InstrumentModel model = truth;
  const double alpha = 2e-3;
  model.edm = PoseBlock::FromRigid({Rz(alpha), Eigen::Vector3d::Zero()});
  const ModelErrors a = EvaluateRecords(model, rec, ErrorMethod::kA);
  EXPECT_EQ(a.edm.n, 8);
  EXPECT_LT(a.edm.max_m, kExactM);
  EXPECT_LT(a.compound.max_m, kExactM);
  const ModelErrors b = EvaluateRecords(model, rec, ErrorMethod::kB);
  ASSERT_EQ(b.edm.n, 12);  // 8 EDM rows + 4 off-axis points
  const double chord = 2 * std::sin(alpha / 2);
  // Mean of 8 zeros and 4 chords; tolerance as in the previous test.
  EXPECT_NEAR(b.edm.mean_m, chord * 4 / 12, 1e-11);
  EXPECT_NEAR(b.edm.max_m, chord, 1e-11);
  EXPECT_LT(b.cam.max_m, kExactM);
}

TEST(ErrorMeasures, ExactModelHasZeroErrorOnSimulatedData) {
  // The simulator's truth evaluated on its own noise-free records (both
  // faces, two zooms, sweeps and grid): every point within round-off.
  // Method B's EDM off-axis points use the model's EDM x axis, which the
  // extraction sets by Eq. 79 (camera x projected normal to the EDM ray);
  // PaperTruth's EDM frame is turned about its ray against the camera, so
  // the truth here takes zoom 0's camera rotation for its EDM (the EDM
  // origin stays where it is).
  SimulationOptions o;
  o.truth = PaperTruth(2);
  o.truth.edm.q = o.truth.cams[0].flange_from_cam.q;
  o.plan.faces = {1, 2};
  o.plan.zooms = {0, 1};
  o.plan.grid_phi_steps = 6;
  o.plan.grid_theta_steps = 4;
  const SimulatedData data = Simulate(o);
  for (ErrorMethod method : {ErrorMethod::kA, ErrorMethod::kB}) {
    const ModelErrors e = EvaluateRecords(o.truth, data.obs.records, method);
    EXPECT_GT(e.edm.n, 100);
    EXPECT_GT(e.cam.n, 50);
    // 20 m EDM points through the truth's transforms: round-off ~20 * 1e-16;
    // B's off-axis points ~1e-12 (see above). 1e-10 m is generous.
    EXPECT_LT(e.edm.max_m, 1e-10);
    EXPECT_LT(e.cam.max_m, 1e-10);
    EXPECT_EQ(e.compound.n, e.edm.n + e.cam.n);
  }
  const ModelErrors a = EvaluateRecords(o.truth, data.obs.records, ErrorMethod::kA);
  const ModelErrors b = EvaluateRecords(o.truth, data.obs.records, ErrorMethod::kB);
  EXPECT_GT(b.cam.n, a.cam.n) << "B includes the camera rows off the principal point";
  EXPECT_GT(b.edm.n, a.edm.n) << "B adds the EDM off-axis points";

  // PaperTruth as it is: method A is exact too (it never looks at the EDM x axis).
  const InstrumentModel paper = PaperTruth(2);
  const std::vector<Record> rec = PlanRecords(o.plan, paper);
  const ModelErrors pa = EvaluateRecords(paper, rec, ErrorMethod::kA);
  EXPECT_LT(pa.edm.max_m, 1e-10);
  EXPECT_LT(pa.cam.max_m, 1e-10);
}

TEST(ErrorMeasures, PointNoiseGivesChiDistributedDistances) {
  // Isotropic point noise sigma per coordinate: each distance is sigma times
  // a chi variable with 3 degrees of freedom, mean sigma sqrt(8 / pi), rms
  // sigma sqrt(3), std sigma sqrt(3 - 8 / pi) = 0.673 sigma.
  SimulationOptions o;
  o.truth = PaperTruth(1);
  o.plan.grid_phi_steps = 12;
  o.plan.grid_theta_steps = 8;
  o.noise.point_m = 1e-4;
  const SimulatedData data = Simulate(o);
  const ModelErrors e = EvaluateRecords(o.truth, data.obs.records, ErrorMethod::kA);
  const double sigma = o.noise.point_m;
  const int n = e.edm.n;
  ASSERT_GT(n, 300);
  // Standard error of the mean: 0.673 sigma / sqrt(n); 5 standard errors.
  EXPECT_NEAR(e.edm.mean_m, sigma * std::sqrt(8 / M_PI), 5 * 0.673 * sigma / std::sqrt(n));
  // rms^2 is sigma^2 chi^2_3 / 3 per row: relative sd of rms ~ sqrt(2/3) / (2 sqrt(n)); 5 of them.
  EXPECT_NEAR(e.edm.rms_m, sigma * std::sqrt(3.0),
              5 * sigma * std::sqrt(3.0) * 0.41 / std::sqrt(n));
  EXPECT_NEAR(e.edm.std_m, sigma * std::sqrt(3 - 8 / M_PI), 0.1 * sigma);
}

TEST(ErrorMeasures, PixelResidualsAndStats) {
  const InstrumentModel m = IdealModel(Kinematics::kSpherical, 2, CameraTool{});
  const auto& k = m.cams[0].intrinsics;
  const double phi = 0.6, theta = 1.3;
  const Eigen::Vector3d ahead = PredictEdm(m, phi, theta, 4.0);  // on the optical axis
  std::vector<PixelObservation> px(4);
  for (auto& p : px) {
    p.phi = phi;
    p.theta = theta;
    p.X = ahead;
  }
  px[0].uv = Eigen::Vector2d(k[2] + 3, k[3] + 4);  // 5 px off
  px[1].uv = Eigen::Vector2d(k[2], k[3]);          // exact
  px[2].X = -ahead;                                // behind the camera
  px[3].zoom = 5;                                  // no such zoom
  const std::vector<PixelResidual> res = PixelResiduals(m, px);
  ASSERT_EQ(res.size(), 4u);
  // The principal point of a point on the optical axis: round-off in pixels
  // (f = 1000 px times ~1e-16 rad).
  const double tol = 1e-9;
  EXPECT_TRUE(res[0].valid);
  EXPECT_LT((res[0].delta - Eigen::Vector2d(3, 4)).norm(), tol);
  EXPECT_TRUE(res[1].valid);
  EXPECT_LT(res[1].delta.norm(), tol);
  EXPECT_FALSE(res[2].valid);
  EXPECT_FALSE(res[3].valid);
  const PixelStats s = EvaluatePixels(m, px);
  EXPECT_EQ(s.n, 2);
  EXPECT_EQ(s.failed, 2);
  // SPEC 6: rms_px = sqrt(mean(du^2 + dv^2)) = sqrt(25 / 2); mean |.| = 2.5.
  EXPECT_NEAR(s.rms_px, std::sqrt(12.5), tol);
  EXPECT_NEAR(s.mean_px, 2.5, tol);
  EXPECT_NEAR(s.max_px, 5.0, tol);
}

}  // namespace
}  // namespace rtscalib

// The public API (libcalib/api/rtscalib.h) on a model written to model.yaml
// and read back: its answers are the model's own functions' and `rtscalib
// predict`'s, it refuses what the model cannot predict, and its first-order
// uncertainty matches a Monte Carlo over the model's stated sigmas.
#include "libcalib/api/rtscalib.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <filesystem>
#include <random>

#include "app/commands.h"
#include "libcalib/fit/manifolds.h"
#include "libcalib/text/errors.h"
#include "libcalib/io/model_io.h"
#include "libcalib/io/records.h"
#include "libcalib/model/kinematics.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib {
namespace {

namespace fs = std::filesystem;

fs::path TestDir(const std::string& name) {
  const fs::path dir = fs::path(RTSCALIB_BINARY_DIR) / "test_tmp" / "api" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// Sigmas of the size a real fit reports (model.yaml of configs/zoom3.yaml:
// ~1e-4 rad and m for poses, ~0.3 px for intrinsics); large enough for a
// Monte Carlo to see, small enough for first order to hold.
void SetSigmas(InstrumentModel* m) {
  ModelSigmas& s = m->sigmas;
  s.valid = true;
  s.base.rotation = {8e-5, 6e-5, 1e-4};
  s.base.t = {2e-4, 1.5e-4, 3e-4};
  s.links[0] = {0, 0, 5e-5, 1e-4};
  s.links[1] = {0, 0, 0, 0};
  s.edm.rotation = {4e-5, 7e-5, 0};
  s.edm.t = {1e-4, 2e-4, 1.5e-4};
  const int n = m->NumZooms();
  s.cam_tools.assign(n, {});
  s.intrinsics.assign(n, {});
  s.distortion.assign(n, {});
  for (int z = 0; z < n; ++z) {
    s.cam_tools[z].rotation = {5e-5, 9e-5, 3e-5};
    s.cam_tools[z].t = {1e-4, 1.2e-4, 8e-5};
    s.intrinsics[z] = {0.4, 0.5, 0.3, 0.35};
    s.distortion[z][kK1] = 2e-3;
    s.distortion[z][kK2] = 4e-3;
    s.distortion[z][kP1] = 1e-4;
    s.distortion[z][kP2] = 1.5e-4;
  }
  for (Effect e : m->effects.List()) {
    if (!IsKinematic(e)) continue;
    // A correlated 2x2 block for polar effects: rho = 0.6.
    const double a = 2e-5, b = 3e-5;
    s.effect_cov[static_cast<int>(e)] = {a * a, 0.6 * a * b, 0.6 * a * b, b * b};
  }
}

InstrumentModel DhModel() {
  InstrumentModel m = PaperTruth(2);
  for (CameraTool& c : m.cams) {
    c.distortion[kK1] = -0.08;
    c.distortion[kK2] = 0.03;
    c.distortion[kP1] = 3e-4;
    c.distortion[kP2] = -2e-4;
  }
  m.effects.Add(Effect::kRadialDistortion);
  m.effects.Add(Effect::kTangentialDistortion);
  m.effects.Add(Effect::kHzEccentricity);
  m.EffectValue(Effect::kHzEccentricity) = {3e-5, -2e-5};
  m.effects.Add(Effect::kEdmScale);
  m.EffectValue(Effect::kEdmScale) = {4e-6, 0};
  SetSigmas(&m);
  return m;
}

InstrumentModel SphericalModel() {
  CameraTool cam;
  cam.width = 640;
  cam.height = 480;
  cam.intrinsics = {900, 901, 322, 238};
  cam.distortion[kK1] = -0.12;
  cam.distortion[kK2] = 0.05;
  InstrumentModel m = IdealModel(Kinematics::kSpherical, 2, cam);
  m.base.t = {0.01, -0.02, 1.5};
  m.edm.t = {0, 0.002, 0};
  m.cams[1].flange_from_cam.t = {0.001, 0.03, 0.0};
  m.effects.Add(Effect::kRadialDistortion);
  for (Effect e : {Effect::kCollimation, Effect::kTiltingAxis, Effect::kVEccentricity,
                   Effect::kEdmOffset, Effect::kAxisWobble}) {
    m.effects.Add(e);
  }
  m.EffectValue(Effect::kCollimation) = {4e-5, 0};
  m.EffectValue(Effect::kTiltingAxis) = {-3e-5, 0};
  m.EffectValue(Effect::kVEccentricity) = {2e-5, 1e-5};
  m.EffectValue(Effect::kEdmOffset) = {1.2e-3, 0};
  m.EffectValue(Effect::kAxisWobble) = {1e-5, -2e-5};
  SetSigmas(&m);
  return m;
}

// Readings of both faces: (phi, theta).
const std::vector<std::array<double, 2>> kReadings = {{0.3, 1.2}, {2.5, 1.7}, {4.0, 0.9},
                                                      {5.9, 2.1}, {1.1, 5.0}, {3.6, 4.4}};

class ApiTest : public ::testing::TestWithParam<int> {
 protected:
  InstrumentModel Model() const { return GetParam() == 0 ? DhModel() : SphericalModel(); }
  std::string Name() const { return GetParam() == 0 ? "dh" : "spherical"; }
};

// A model read back from model.yaml predicts bit for bit (model_io.h), so
// the API's answers must be the model functions' exactly (tolerance 0), and
// the ray's origin + d direction F_CAM up to rounding.
TEST_P(ApiTest, AnswersAreTheModelsOwnFunctions) {
  const fs::path dir = TestDir("functions_" + Name());
  const InstrumentModel truth = Model();
  WriteModelYaml((dir / "model.yaml").string(), truth);
  const CalibratedInstrument inst = CalibratedInstrument::Load((dir / "model.yaml").string());
  const InstrumentModel& m = inst.Model();
  ASSERT_EQ(inst.NumZooms(), 2);
  for (const auto& [phi, theta] : kReadings) {
    for (double d : {2.0, 17.5}) {
      EXPECT_EQ(inst.EdmPoint(phi, theta, d), PredictEdm(truth, phi, theta, d));
      for (int z = 0; z < 2; ++z) {
        const double w = m.cams[z].width, h = m.cams[z].height;
        for (const Eigen::Vector2d& uv :
             {Eigen::Vector2d(w / 2, h / 2), Eigen::Vector2d(0.1 * w, 0.8 * h),
              Eigen::Vector2d(w - 1, 0)}) {
          const Eigen::Vector3d x = PredictCam(truth, z, phi, theta, uv[0], uv[1], d);
          EXPECT_EQ(inst.CameraPoint(z, phi, theta, uv[0], uv[1], d), x);
          const Ray ray = inst.CameraRay(z, phi, theta, uv[0], uv[1]);
          // Rounding of a rotation and a sum at |x| <= 20 m: 1e-13 m.
          EXPECT_NEAR((ray.At(d) - x).norm(), 0.0, 1e-13);
          EXPECT_NEAR(ray.direction.norm(), 1.0, 1e-15);
          EXPECT_LT((ray.origin - RefFromCam(truth, z, phi, theta).translation).norm(), 1e-15);
          Eigen::Vector2d expected;
          ASSERT_TRUE(PredictPixel(truth, z, phi, theta, x, &expected));
          EXPECT_EQ(inst.Pixel(z, phi, theta, x), expected);
          // And the pixel is where the point was taken from (the model's own
          // round trip: Newton undistortion to ~1e-9 px).
          EXPECT_LT((expected - uv).norm(), 1e-7);
        }
      }
    }
  }
}

// `rtscalib predict` on records and pixels writes exactly what the API says
// (CSV keeps 17 significant digits, so doubles survive the round trip).
TEST_P(ApiTest, AnswersAreRtscalibPredicts) {
  const fs::path dir = TestDir("predict_" + Name());
  const InstrumentModel truth = Model();
  WriteModelYaml((dir / "model.yaml").string(), truth);
  const CalibratedInstrument inst = CalibratedInstrument::Load((dir / "model.yaml").string());
  std::vector<Record> records;
  std::vector<PixelObservation> pixels;
  for (const auto& [phi, theta] : kReadings) {
    Record r;
    r.face = FaceOf(theta);
    r.phi = phi;
    r.theta = theta;
    r.d = 12.25;
    r.tool = Tool::kEdm;
    records.push_back(r);
    for (int z = 0; z < 2; ++z) {
      r.tool = Tool::kCam;
      r.zoom = z;
      r.u = 0.3 * truth.cams[z].width;
      r.v = 0.6 * truth.cams[z].height;
      r.d = 9.5;
      records.push_back(r);
      PixelObservation p;
      p.face = r.face;
      p.zoom = z;
      p.phi = phi;
      p.theta = theta;
      p.shot = "s";
      p.X = PredictCam(truth, z, phi, theta, r.u, r.v, 9.5);
      pixels.push_back(p);
    }
  }
  WriteRecords((dir / "records.csv").string(), records);
  WritePixels((dir / "pixels.csv").string(), pixels);
  app::PredictArgs args;
  args.model = (dir / "model.yaml").string();
  args.records = (dir / "records.csv").string();
  args.out = (dir / "records_pred.csv").string();
  ASSERT_EQ(app::RunPredict(args), 0);
  args.records.clear();
  args.pixels = (dir / "pixels.csv").string();
  args.out = (dir / "pixels_pred.csv").string();
  ASSERT_EQ(app::RunPredict(args), 0);

  const RecordsFile rp = ReadRecords((dir / "records_pred.csv").string());
  ASSERT_EQ(rp.records.size(), records.size());
  for (const Record& r : rp.records) {
    const Eigen::Vector3d api = r.tool == Tool::kEdm
                                    ? inst.EdmPoint(r.phi, r.theta, r.d)
                                    : inst.CameraPoint(r.zoom, r.phi, r.theta, r.u, r.v, r.d);
    EXPECT_EQ(r.x, api) << "line " << r.line;
  }
  const PixelsFile pp = ReadPixels((dir / "pixels_pred.csv").string());
  ASSERT_EQ(pp.pixels.size(), pixels.size());
  for (const PixelObservation& p : pp.pixels) {
    EXPECT_EQ(p.uv, inst.Pixel(p.zoom, p.phi, p.theta, p.X)) << "line " << p.line;
  }
}

// An independent sample of the model: every block moved by a normal draw of
// its stored sigma in the fit's tangent coordinates (refine.cc: base and
// camera rotations on Ceres' EigenQuaternionManifold, the EDM rotation on
// QuaternionNoRollManifold, the rest additive; each effect by its 2x2
// covariance).
InstrumentModel Sample(const InstrumentModel& m, std::mt19937_64* rng) {
  std::normal_distribution<double> n01;
  InstrumentModel out = m;
  const ModelSigmas& s = m.sigmas;
  auto add = [&](double* p, const double* sigma, int size) {
    for (int i = 0; i < size; ++i) p[i] += sigma[i] * n01(*rng);
  };
  auto rotate = [&](const ceres::Manifold& manifold, double* q, const double* sigma) {
    double delta[3];
    for (int i = 0; i < manifold.TangentSize(); ++i) delta[i] = sigma[i] * n01(*rng);
    const double q0[4] = {q[0], q[1], q[2], q[3]};
    manifold.Plus(q0, delta, q);
  };
  rotate(ceres::EigenQuaternionManifold(), out.base.q.data(), s.base.rotation.data());
  add(out.base.t.data(), s.base.t.data(), 3);
  if (m.kinematics == Kinematics::kDh) {
    for (int k = 0; k < 2; ++k) add(out.links[k].p.data(), s.links[k].data(), 4);
  }
  rotate(QuaternionNoRollManifold(), out.edm.q.data(), s.edm.rotation.data());
  add(out.edm.t.data(), s.edm.t.data(), 3);
  for (Effect e : m.effects.List()) {
    if (!IsKinematic(e)) continue;
    const std::array<double, 4>& c = s.effect_cov[static_cast<int>(e)];
    const int np = Info(e).num_params;
    Eigen::Matrix2d cov;
    cov << c[0], c[1], c[2], c[3];
    if (np == 1) cov(1, 1) = 1;  // unused second row; keeps the factor defined
    const Eigen::Matrix2d l = cov.llt().matrixL();
    const Eigen::Vector2d draw = l * Eigen::Vector2d(n01(*rng), n01(*rng));
    for (int i = 0; i < np; ++i) out.EffectValue(e)[i] += draw[i];
  }
  for (int z = 0; z < m.NumZooms(); ++z) {
    CameraTool& c = out.cams[z];
    rotate(ceres::EigenQuaternionManifold(), c.flange_from_cam.q.data(),
           s.cam_tools[z].rotation.data());
    add(c.flange_from_cam.t.data(), s.cam_tools[z].t.data(), 3);
    add(c.intrinsics.data(), s.intrinsics[z].data(), kNumIntrinsics);
    add(c.distortion.data(), s.distortion[z].data(), kNumDistortion);
  }
  return out;
}

template <int N>
Eigen::Matrix<double, N, N> SampleCovariance(const std::vector<Eigen::Matrix<double, N, 1>>& xs) {
  Eigen::Matrix<double, N, 1> mean = Eigen::Matrix<double, N, 1>::Zero();
  for (const auto& x : xs) mean += x;
  mean /= static_cast<double>(xs.size());
  Eigen::Matrix<double, N, N> c = Eigen::Matrix<double, N, N>::Zero();
  for (const auto& x : xs) c += (x - mean) * (x - mean).transpose();
  return c / static_cast<double>(xs.size() - 1);
}

// With N samples the relative standard error of a sample sigma is
// 1/sqrt(2N) = 1.1% for N = 4000 and that of a correlation <= 1/sqrt(N) =
// 1.6%; first order at these sigmas (1e-4 relative) adds far less. Bounds:
// 6% on sigmas, 0.06 on correlations (> 3.5 standard errors each).
constexpr int kSamples = 4000;
constexpr double kSigmaTolerance = 0.06;
constexpr double kCorrelationTolerance = 0.06;

template <int N>
void ExpectSameCovariance(const Eigen::Matrix<double, N, N>& api,
                          const Eigen::Matrix<double, N, N>& mc, const std::string& what,
                          int skip_from = N) {
  for (int i = 0; i < skip_from; ++i) {
    const double s_api = std::sqrt(api(i, i)), s_mc = std::sqrt(mc(i, i));
    EXPECT_NEAR(s_api / s_mc, 1.0, kSigmaTolerance) << what << " component " << i;
    for (int j = 0; j < i; ++j) {
      const double r_api = api(i, j) / std::sqrt(api(i, i) * api(j, j));
      const double r_mc = mc(i, j) / std::sqrt(mc(i, i) * mc(j, j));
      EXPECT_NEAR(r_api, r_mc, kCorrelationTolerance) << what << " components " << i << ", " << j;
    }
  }
}

TEST_P(ApiTest, UncertaintyMatchesMonteCarloOverTheStatedSigmas) {
  const fs::path dir = TestDir("uncertainty_" + Name());
  WriteModelYaml((dir / "model.yaml").string(), Model());
  const CalibratedInstrument inst = CalibratedInstrument::Load((dir / "model.yaml").string());
  const InstrumentModel& m = inst.Model();
  std::mt19937_64 rng(7);
  std::vector<InstrumentModel> samples;
  for (int i = 0; i < kSamples; ++i) samples.push_back(Sample(m, &rng));

  const double phi = 2.2, theta = 4.6, d = 25.0;  // face 2
  const int z = 1;
  const double u = 0.15 * m.cams[z].width, v = 0.8 * m.cams[z].height;
  const Eigen::Vector3d x = inst.CameraPoint(z, phi, theta, u, v, d);

  std::vector<Eigen::Vector3d> edm;
  std::vector<Eigen::Matrix<double, 6, 1>> ray;
  std::vector<Eigen::Vector2d> px;
  for (const InstrumentModel& s : samples) {
    edm.push_back(PredictEdm(s, phi, theta, d));
    // The ray from F_CAM itself: origin at length 0, direction = unit step.
    const Eigen::Vector3d o = PredictCam(s, z, phi, theta, u, v, 0.0);
    Eigen::Matrix<double, 6, 1> r;
    r << o, PredictCam(s, z, phi, theta, u, v, 1.0) - o;
    ray.push_back(r);
    Eigen::Vector2d uv;
    ASSERT_TRUE(PredictPixel(s, z, phi, theta, x, &uv));
    px.push_back(uv);
  }
  const Uncertain<3> e = inst.EdmPointWithUncertainty(phi, theta, d);
  EXPECT_EQ(e.value, inst.EdmPoint(phi, theta, d));
  ExpectSameCovariance<3>(e.covariance, SampleCovariance<3>(edm), "EDM point");
  const Uncertain<6> r = inst.CameraRayWithUncertainty(z, phi, theta, u, v);
  ExpectSameCovariance<6>(r.covariance, SampleCovariance<6>(ray), "camera ray");
  const Uncertain<2> p = inst.PixelWithUncertainty(z, phi, theta, x);
  ExpectSameCovariance<2>(p.covariance, SampleCovariance<2>(px), "pixel");
  // Sizes a user can sanity-check: the EDM point at 25 m moves by about
  // base/edm translations (~3e-4 m) plus 25 m times ~1e-4 rad.
  EXPECT_GT(e.Sigma().norm(), 1e-4);
  EXPECT_LT(e.Sigma().norm(), 1e-2);
}

INSTANTIATE_TEST_SUITE_P(Kinematics, ApiTest, ::testing::Values(0, 1));

// A full parameter covariance plugs in: with P non-zero only on base.t (a
// full 3x3 block), the EDM point's covariance is exactly that block, since
// d x / d base.t = I. Central differences of a linear map: exact to rounding
// (1e-9 relative).
TEST(ApiCovariance, AFullParameterCovariancePlugsIn) {
  CalibratedInstrument inst(DhModel());
  const ParameterBlock& bt = inst.Block("base.t");
  Eigen::Matrix3d c;
  c << 4e-8, 1e-8, -2e-8, 1e-8, 9e-8, 3e-8, -2e-8, 3e-8, 1.6e-7;
  Eigen::MatrixXd P = Eigen::MatrixXd::Zero(inst.NumParameters(), inst.NumParameters());
  P.block<3, 3>(bt.offset, bt.offset) = c;
  inst.SetParameterCovariance(P);
  const Eigen::Matrix3d got = inst.EdmPointWithUncertainty(0.4, 1.3, 8.0).covariance;
  EXPECT_LT((got - c).cwiseAbs().maxCoeff(), 1e-9 * c.cwiseAbs().maxCoeff()) << got;
  EXPECT_THROW(inst.SetParameterCovariance(Eigen::MatrixXd::Identity(3, 3)), std::invalid_argument);
  P(0, 1) = 1.0;  // not symmetric
  EXPECT_THROW(inst.SetParameterCovariance(P), std::invalid_argument);
}

TEST(ApiCovariance, TheStoredSigmasAreTheDiagonalAndEffectBlocks) {
  const InstrumentModel m = SphericalModel();
  const CalibratedInstrument inst(m);
  const Eigen::MatrixXd& P = inst.ParameterCovariance();
  const ParameterBlock& k = inst.Block("cam[1].intrinsics");
  EXPECT_EQ(k.size, 4);
  EXPECT_DOUBLE_EQ(P(k.offset + 2, k.offset + 2), 0.3 * 0.3);
  const ParameterBlock& w = inst.Block("axis_wobble");
  const auto& c = m.sigmas.effect_cov[static_cast<int>(Effect::kAxisWobble)];
  EXPECT_DOUBLE_EQ(P(w.offset, w.offset + 1), c[1]);
  EXPECT_DOUBLE_EQ(P(w.offset + 1, w.offset + 1), c[3]);
  // Outside the effect blocks model.yaml stores no correlation.
  const Eigen::MatrixXd off = P - Eigen::MatrixXd(P.diagonal().asDiagonal());
  EXPECT_DOUBLE_EQ(
      off.cwiseAbs().sum(),
      2 * std::abs(c[1]) +
          2 * std::abs(m.sigmas.effect_cov[static_cast<int>(Effect::kVEccentricity)][1]));
  EXPECT_THROW(inst.Block("links"), std::out_of_range);
  EXPECT_EQ(inst.NumParameters(),
            inst.ParameterBlocks().back().offset + inst.ParameterBlocks().back().size);
}

PredictionFailure FailureOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const PredictionError& e) {
    EXPECT_FALSE(e.expected.empty());
    EXPECT_FALSE(e.got.empty());
    return e.failure;
  }
  ADD_FAILURE() << "no PredictionError";
  return PredictionFailure::kNonFinite;
}

// SPEC 7: a corner of a board the model estimated is predicted from the
// board's pose; a tag on no estimated board is refused.
TEST(ApiBoards, PredictsTheCornersOfEstimatedBoards) {
  InstrumentModel m = PaperTruth(1);
  EstimatedBoard b;
  b.board.first_id = 48;
  b.board.rows = 2;
  b.board.cols = 3;
  // 4 m along the line of sight of (phi, theta) = (0.3, 1.5), facing the camera.
  const Rigid3 ref_from_cam = RefFromCam(m, 0, 0.3, 1.5);
  b.pose = PoseBlock::FromRigid(ref_from_cam * Rigid3::FromEuler({0.1, 0, 0}, {-0.1, -0.05, 4}));
  m.boards.push_back(b);
  const CalibratedInstrument inst(m);
  const Eigen::Vector3d corner = inst.BoardCorner(50, 2);
  EXPECT_EQ(corner, b.pose.ToRigid() * b.board.CornersInBoard(2)[2]);
  // The same pixel as projecting the corner (same arithmetic: bit-equal).
  EXPECT_EQ(inst.BoardCornerPixel(0, 0.3, 1.5, 50, 2), inst.Pixel(0, 0.3, 1.5, corner));
  EXPECT_EQ(FailureOf([&] { inst.BoardCorner(47, 0); }), PredictionFailure::kNoSuchBoard);
  EXPECT_EQ(FailureOf([&] { inst.BoardCorner(48, 4); }), PredictionFailure::kNoSuchBoard);
}

TEST(ApiErrors, RefusesWhatTheModelCannotPredict) {
  const CalibratedInstrument inst(DhModel());
  const double phi = 0.3, theta = 1.2;
  EXPECT_EQ(FailureOf([&] { inst.CameraRay(2, phi, theta, 10, 10); }),
            PredictionFailure::kNoSuchZoom);
  EXPECT_EQ(FailureOf([&] { inst.ImageWidth(-1); }), PredictionFailure::kNoSuchZoom);
  // 1280 x 960 image, 10% margin: u up to 1279.5 + 128 = 1407.5.
  EXPECT_NO_THROW(inst.CameraRay(0, phi, theta, 1400, 10));
  EXPECT_EQ(FailureOf([&] { inst.CameraRay(0, phi, theta, 1410, 10); }),
            PredictionFailure::kOutsideImage);
  EXPECT_EQ(FailureOf([&] { inst.CameraRay(0, phi, theta, 10, -97); }),
            PredictionFailure::kOutsideImage);
  EXPECT_EQ(FailureOf([&] { inst.EdmPoint(phi, std::nan(""), 3); }), PredictionFailure::kNonFinite);
  const Eigen::Vector3d ahead = inst.CameraPoint(0, phi, theta, 640, 480, 10);
  const Eigen::Vector3d behind = 2 * inst.CameraRay(0, phi, theta, 640, 480).origin - ahead;
  EXPECT_NO_THROW(inst.Pixel(0, phi, theta, ahead));
  EXPECT_EQ(FailureOf([&] { inst.Pixel(0, phi, theta, behind); }),
            PredictionFailure::kBehindCamera);
  // 45 degrees off the axis of a 1500 px lens (k1 = -0.08, k2 = 0.03 keep
  // g(r) = r (1 + k1 r^2 + k2 r^4) increasing everywhere): ~1425 px off centre.
  const Rigid3 ref_from_cam = RefFromCam(inst.Model(), 0, phi, theta);
  EXPECT_EQ(FailureOf([&] { inst.Pixel(0, phi, theta, ref_from_cam * Eigen::Vector3d(1, 0, 1)); }),
            PredictionFailure::kOutsideImage);
}

// With k1 = -0.3 alone g(r) = r (1 - 0.3 r^2) turns at r = 1.054 and folds
// back: a point at tan = 2 off the axis to the right projects to g = -0.4,
// 600 px LEFT of centre, inside the image, where it is not seen. Refused.
TEST(ApiErrors, RefusesAPointWhoseProjectionTheDistortionFolds) {
  InstrumentModel m = DhModel();
  m.cams[0].distortion.fill(0.0);
  m.cams[0].distortion[kK1] = -0.3;
  const CalibratedInstrument inst(m);
  const double phi = 0.3, theta = 1.2;
  const Eigen::Vector3d x = RefFromCam(m, 0, phi, theta) * Eigen::Vector3d(2.0, 0, 1);
  Eigen::Vector2d folded;
  ASSERT_TRUE(PredictPixel(m, 0, phi, theta, x, &folded));
  // The model alone answers a pixel in the image, on the wrong side.
  ASSERT_GT(folded[0], 0.0);
  ASSERT_LT(folded[0], m.cams[0].intrinsics[2]);
  EXPECT_EQ(FailureOf([&] { inst.Pixel(0, phi, theta, x); }), PredictionFailure::kUntrustedPoint);
  // Inside the turning point it predicts.
  EXPECT_NO_THROW(
      inst.Pixel(0, phi, theta, RefFromCam(m, 0, phi, theta) * Eigen::Vector3d(0.3, 0, 1)));
}

TEST(ApiErrors, LoadNamesTheFileAndUncertaintyNeedsSigmas) {
  try {
    CalibratedInstrument::Load("/nonexistent/model.yaml");
    ADD_FAILURE() << "loaded a missing file";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/model.yaml"), std::string::npos);
  }
  InstrumentModel m = DhModel();
  m.sigmas = ModelSigmas{};
  const CalibratedInstrument inst(m);
  EXPECT_FALSE(inst.HasParameterCovariance());
  EXPECT_NO_THROW(inst.EdmPoint(0.1, 1.0, 5));
  EXPECT_THROW(inst.EdmPointWithUncertainty(0.1, 1.0, 5), std::logic_error);
}

}  // namespace
}  // namespace rtscalib

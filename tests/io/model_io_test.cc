#include "libcalib/io/model_io.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <random>

#include "libcalib/model/kinematics.h"
#include "tests/io/io_test_util.h"

namespace rtscalib {
namespace {

using ::testing::HasSubstr;
using testing_io::CatchInputError;
using testing_io::TempDir;

// A non-trivial model: the ideal instrument of kinematics `k`, every block
// perturbed, all effects that `k` can hold switched on, distortion in two
// groups and (optionally) uncertainties everywhere.
InstrumentModel RandomModel(Kinematics k, int zooms, bool with_sigmas, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unif(-1, 1);
  auto small_rotation = [&](double size) {
    return Rigid3::FromEuler(Eigen::Vector3d(unif(rng), unif(rng), unif(rng)) * size,
                             Eigen::Vector3d(unif(rng), unif(rng), unif(rng)) * 1e-3);
  };
  CameraTool cam;
  cam.width = 640;
  cam.height = 480;
  cam.intrinsics = {1000.0 / 3.0 * 3.1, 1005.0 / 7.0 * 7.0, 320.3, 239.7};
  InstrumentModel m = IdealModel(k, zooms, cam);
  m.base = PoseBlock::FromRigid(m.base.ToRigid() * small_rotation(1e-3));
  m.edm = PoseBlock::FromRigid(m.edm.ToRigid() * small_rotation(1e-3));
  for (CameraTool& c : m.cams) {
    c.flange_from_cam = PoseBlock::FromRigid(c.flange_from_cam.ToRigid() * small_rotation(1e-2));
    for (double& x : c.intrinsics) x += unif(rng);
    c.distortion[kK1] = 0.05 * unif(rng);
    c.distortion[kK2] = 0.01 * unif(rng);
    c.distortion[kP1] = 1e-3 * unif(rng);
    c.distortion[kP2] = 1e-3 * unif(rng);
    c.distortion[kK3] = 1e-3 * unif(rng);
    c.focus = {0.01 * unif(rng), 5.0 * unif(rng), 5.0 * unif(rng)};  // SPEC 4.1 [m, px m]
  }
  if (k == Kinematics::kDh) {
    for (DhLink& link : m.links) {
      for (double& p : link.p) p += 1e-4 * unif(rng);
    }
  }
  for (const EffectInfo& info : EffectCatalogue()) {
    if (k == Kinematics::kDh && info.redundant_in_dh) continue;
    if (info.effect == Effect::kRationalDistortion || info.effect == Effect::kThinPrism ||
        info.effect == Effect::kSensorTilt) {
      continue;
    }
    m.effects.Add(info.effect);
    if (IsKinematic(info.effect)) {
      m.EffectValue(info.effect) = {1e-5 * unif(rng), 1e-5 * unif(rng)};
      if (info.num_params == 1) m.EffectValue(info.effect)[1] = 0;
    }
  }
  m.edm_cyclic_unit_length = 1.5 / 7.0;
  if (with_sigmas) {
    ModelSigmas& s = m.sigmas;
    s.valid = true;
    auto pose_sigma = [&] {
      PoseSigma p;
      for (int i = 0; i < 3; ++i) {
        p.rotation[i] = std::abs(unif(rng)) * 1e-6;
        p.euler[i] = std::abs(unif(rng)) * 1e-6;
        p.t[i] = std::abs(unif(rng)) * 1e-6;
      }
      return p;
    };
    s.base = pose_sigma();
    s.edm = pose_sigma();
    for (auto& link : s.links) {
      for (double& x : link) x = std::abs(unif(rng)) * 1e-6;
    }
    for (int z = 0; z < zooms; ++z) {
      s.cam_tools.push_back(pose_sigma());
      s.intrinsics.push_back({0.1, 0.2, 0.3, 0.4});
      s.distortion.emplace_back();
      for (double& x : s.distortion.back()) x = std::abs(unif(rng)) * 1e-4;
      s.focus.push_back({1e-4, 0.05, 0.06});
    }
    // Coefficients the fit did not free have no uncertainty: `held` in the
    // file, 0 in memory (what Refine gives them).
    for (auto& sd : s.distortion) {
      for (int i = 0; i < kNumDistortion; ++i) {
        if (!m.effects.Has(DistortionGroupOf(i))) sd[i] = 0.0;
      }
    }
    // Uncertainty that could not be computed is NaN and must survive.
    s.distortion.back()[kK3] = std::nan("");
    for (Effect e : m.effects.List()) {
      if (!IsKinematic(e)) continue;
      const double a = 1e-12 * (1.5 + unif(rng)), b = 1e-12 * (1.5 + unif(rng));
      const double c = 1e-13 * unif(rng);  // |c| < sqrt(a b): a valid covariance
      s.effect_cov[static_cast<int>(e)] = Info(e).num_params == 1
                                              ? std::array<double, 4>{a, 0, 0, 0}
                                              : std::array<double, 4>{a, c, c, b};
    }
  }
  return m;
}

// Bitwise equality that also holds for NaN.
void ExpectSameBits(double a, double b, const std::string& what) {
  EXPECT_TRUE(a == b || (std::isnan(a) && std::isnan(b))) << what << ": " << a << " vs " << b;
}

template <size_t N>
void ExpectSameBits(const std::array<double, N>& a, const std::array<double, N>& b,
                    const std::string& what) {
  for (size_t i = 0; i < N; ++i) ExpectSameBits(a[i], b[i], what + "[" + std::to_string(i) + "]");
}

void ExpectSameSigma(const PoseSigma& a, const PoseSigma& b, const std::string& what) {
  ExpectSameBits(a.rotation, b.rotation, what + ".rotation");
  ExpectSameBits(a.euler, b.euler, what + ".euler");
  ExpectSameBits(a.t, b.t, what + ".t");
}

// Every parameter block and uncertainty comes back bit for bit, and so do
// the predictions of every tool (the contract of model.yaml, SPEC 5).
void ExpectRoundTrip(const InstrumentModel& m) {
  TempDir dir;
  const std::string path = dir.Path("model.yaml");
  WriteModelYaml(path, m, {{"program", "rtscalib test"}, {"note", "a: b, c"}});
  ModelMetadata metadata;
  const InstrumentModel r = ReadModelYaml(path, &metadata);

  EXPECT_EQ(metadata, (ModelMetadata{{"program", "rtscalib test"}, {"note", "a: b, c"}}));
  EXPECT_EQ(r.kinematics, m.kinematics);
  EXPECT_EQ(r.effects, m.effects);
  EXPECT_EQ(r.edm_cyclic_unit_length, m.edm_cyclic_unit_length);
  EXPECT_EQ(r.base.q, m.base.q);
  EXPECT_EQ(r.base.t, m.base.t);
  EXPECT_EQ(r.edm.q, m.edm.q);
  EXPECT_EQ(r.edm.t, m.edm.t);
  if (m.kinematics == Kinematics::kDh) {
    for (int i = 0; i < 2; ++i) EXPECT_EQ(r.links[i].p, m.links[i].p);
  }
  ASSERT_EQ(r.NumZooms(), m.NumZooms());
  for (int z = 0; z < m.NumZooms(); ++z) {
    EXPECT_EQ(r.cams[z].width, m.cams[z].width);
    EXPECT_EQ(r.cams[z].height, m.cams[z].height);
    EXPECT_EQ(r.cams[z].flange_from_cam.q, m.cams[z].flange_from_cam.q);
    EXPECT_EQ(r.cams[z].flange_from_cam.t, m.cams[z].flange_from_cam.t);
    EXPECT_EQ(r.cams[z].intrinsics, m.cams[z].intrinsics);
    EXPECT_EQ(r.cams[z].distortion, m.cams[z].distortion);
    if (m.effects.Has(Effect::kFocus)) {
      EXPECT_EQ(r.cams[z].focus, m.cams[z].focus);
    }
  }
  for (Effect e : m.effects.List()) {
    if (IsKinematic(e)) {
      EXPECT_EQ(r.EffectValue(e), m.EffectValue(e)) << Info(e).name;
    }
  }

  EXPECT_EQ(r.sigmas.valid, m.sigmas.valid);
  if (m.sigmas.valid) {
    ExpectSameSigma(r.sigmas.base, m.sigmas.base, "base");
    ExpectSameSigma(r.sigmas.edm, m.sigmas.edm, "edm");
    if (m.kinematics == Kinematics::kDh) {
      for (int i = 0; i < 2; ++i) ExpectSameBits(r.sigmas.links[i], m.sigmas.links[i], "links");
    }
    ASSERT_EQ(r.sigmas.cam_tools.size(), m.sigmas.cam_tools.size());
    for (int z = 0; z < m.NumZooms(); ++z) {
      ExpectSameSigma(r.sigmas.cam_tools[z], m.sigmas.cam_tools[z], "cam_tools");
      ExpectSameBits(r.sigmas.intrinsics[z], m.sigmas.intrinsics[z], "intrinsics");
      ExpectSameBits(r.sigmas.distortion[z], m.sigmas.distortion[z], "distortion");
      if (m.effects.Has(Effect::kFocus)) {
        ExpectSameBits(r.sigmas.focus[z], m.sigmas.focus[z], "focus");
      }
    }
    for (Effect e : m.effects.List()) {
      if (!IsKinematic(e)) continue;
      ExpectSameBits(r.sigmas.effect_cov[static_cast<int>(e)],
                     m.sigmas.effect_cov[static_cast<int>(e)], Info(e).name);
    }
  }

  std::mt19937 rng(5);
  std::uniform_real_distribution<double> phi(0, 2 * M_PI), theta(0.1, 2 * M_PI - 0.1), d(0.5, 50),
      u(50, 590), v(50, 430);
  for (int i = 0; i < 200; ++i) {
    const double p = phi(rng), t = theta(rng), dist = d(rng);
    EXPECT_EQ(PredictEdm(r, p, t, dist), PredictEdm(m, p, t, dist));
    for (int z = 0; z < m.NumZooms(); ++z) {
      const double pu = u(rng), pv = v(rng);
      EXPECT_EQ(PredictCam(r, z, p, t, pu, pv, dist), PredictCam(m, z, p, t, pu, pv, dist));
      const Eigen::Vector3d x = PredictCam(m, z, p, t, pu, pv, dist);
      Eigen::Vector2d pixel_m, pixel_r;
      ASSERT_TRUE(PredictPixel(m, z, p, t, x, &pixel_m));
      ASSERT_TRUE(PredictPixel(r, z, p, t, x, &pixel_r));
      EXPECT_EQ(pixel_r, pixel_m);
      ASSERT_TRUE(PredictPixel(m, z, p, t, x, &pixel_m, 3.0));  // a photo focused at 3 m
      ASSERT_TRUE(PredictPixel(r, z, p, t, x, &pixel_r, 3.0));
      EXPECT_EQ(pixel_r, pixel_m);
    }
  }
}

TEST(ModelIo, DhRoundTripPredictsBitExactly) {
  ExpectRoundTrip(RandomModel(Kinematics::kDh, 3, /*with_sigmas=*/true, 1));
}

TEST(ModelIo, SphericalRoundTripPredictsBitExactly) {
  ExpectRoundTrip(RandomModel(Kinematics::kSpherical, 2, /*with_sigmas=*/true, 2));
}

TEST(ModelIo, RoundTripWithoutUncertainties) {
  ExpectRoundTrip(RandomModel(Kinematics::kDh, 1, /*with_sigmas=*/false, 3));
  ExpectRoundTrip(IdealModel(Kinematics::kSpherical, 1, CameraTool{}));
}

TEST(ModelIo, FileStatesReportUnitsAndEuler) {
  TempDir dir;
  InstrumentModel m = RandomModel(Kinematics::kDh, 1, true, 4);
  m.EffectValue(Effect::kEdmScale)[0] = 2.5e-6;
  WriteModelYaml(dir.Path("model.yaml"), m);
  const YAML::Node n = YAML::LoadFile(dir.Path("model.yaml"));
  EXPECT_EQ(n["format"].as<std::string>(), "rtscalib-model");
  EXPECT_EQ(n["kinematics"].as<std::string>(), "dh");
  EXPECT_EQ(n["base"]["euler"].size(), 3u);
  bool found = false;
  for (const YAML::Node& e : n["effects"]) {
    if (e["name"].as<std::string>() != "edm_scale") continue;
    found = true;
    EXPECT_NEAR(e["report"]["m"]["value"].as<double>(), 2.5, 1e-12);
    EXPECT_EQ(e["report"]["m"]["unit"].as<std::string>(), "ppm");
    EXPECT_TRUE(e["report"]["m"]["sigma"].IsDefined());
  }
  EXPECT_TRUE(found);
  EXPECT_EQ(n["cameras"][0]["distortion"]["tauy"].as<double>(), 0.0);
  EXPECT_TRUE(n["cameras"][0]["distortion_sigma"].IsDefined());
}

// A tool the data did not determine: `determined: false` and no sigma keys
// (never a sigma of 0); read back as not determined with NaN sigmas; predict's
// check refuses it naming the row.
TEST(ModelIo, UndeterminedToolsHaveNoSigmaAndReadBackAsUndetermined) {
  TempDir dir;
  InstrumentModel m = RandomModel(Kinematics::kDh, 2, true, 8);
  m.edm_determined = false;
  m.cams[1].determined = false;
  WriteModelYaml(dir.Path("model.yaml"), m);
  const YAML::Node n = YAML::LoadFile(dir.Path("model.yaml"));
  EXPECT_FALSE(n["edm"]["determined"].as<bool>());
  EXPECT_FALSE(n["edm"]["sigma"].IsDefined());
  EXPECT_TRUE(n["base"]["sigma"].IsDefined());
  EXPECT_FALSE(n["base"]["determined"].IsDefined());
  EXPECT_FALSE(n["cameras"][0]["determined"].IsDefined());
  EXPECT_TRUE(n["cameras"][0]["intrinsics_sigma"].IsDefined());
  EXPECT_FALSE(n["cameras"][1]["determined"].as<bool>());
  EXPECT_FALSE(n["cameras"][1]["flange_from_cam"]["sigma"].IsDefined());
  EXPECT_FALSE(n["cameras"][1]["intrinsics_sigma"].IsDefined());
  EXPECT_FALSE(n["cameras"][1]["distortion_sigma"].IsDefined());

  const InstrumentModel r = ReadModelYaml(dir.Path("model.yaml"));
  EXPECT_FALSE(r.edm_determined);
  EXPECT_TRUE(r.cams[0].determined);
  EXPECT_FALSE(r.cams[1].determined);
  EXPECT_TRUE(std::isnan(r.sigmas.edm.t[0]));
  EXPECT_TRUE(std::isnan(r.sigmas.intrinsics[1][0]));
  EXPECT_EQ(r.edm.t, m.edm.t);  // the start value is kept as written
}

// Files written before `determined` existed read as fully determined.
TEST(ModelIo, FilesWithoutDeterminedKeysReadAsDetermined) {
  TempDir dir;
  WriteModelYaml(dir.Path("model.yaml"), RandomModel(Kinematics::kDh, 1, true, 9));
  ASSERT_EQ(std::string::npos, [&] {
    std::ifstream in(dir.Path("model.yaml"));
    return std::string(std::istreambuf_iterator<char>(in), {}).find("determined");
  }());
  const InstrumentModel r = ReadModelYaml(dir.Path("model.yaml"));
  EXPECT_TRUE(r.edm_determined);
  EXPECT_TRUE(r.cams[0].determined);
}

// Writes a model, lets `edit` change its YAML, and returns the read error.
template <typename Edit>
InputError EditedModelError(const TempDir& dir, Edit edit) {
  const std::string path = dir.Path("model.yaml");
  WriteModelYaml(path, RandomModel(Kinematics::kDh, 2, true, 6));
  YAML::Node n = YAML::LoadFile(path);
  edit(n);
  std::ofstream(path) << YAML::Dump(n);
  return CatchInputError([&] { ReadModelYaml(path); });
}

// Found by fuzz/model_fuzzer: a metadata text ending in a carriage return
// was written plain and came back without it.
TEST(ModelIo, MetadataWithControlCharactersRoundTrips) {
  TempDir dir;
  const std::string path = dir.Path("model.yaml");
  const ModelMetadata metadata = {
      {"run", "a\r"}, {"key\r", "x"}, {"lines", "one\r\ntwo\n"}, {"tab", "\tx\x1b"}};
  WriteModelYaml(path, IdealModel(Kinematics::kDh, 1, CameraTool{}), metadata);
  ModelMetadata read;
  ReadModelYaml(path, &read);
  EXPECT_EQ(read, metadata);
}

TEST(ModelIo, UnknownKeyIsAnError) {
  TempDir dir;
  const InputError e = EditedModelError(dir, [](YAML::Node& n) { n["cameras"][1]["fov"] = 40; });
  EXPECT_EQ(e.key, "cameras[1].fov");
  EXPECT_EQ(e.file, dir.Path("model.yaml"));
  EXPECT_GT(e.line, 0);
}

TEST(ModelIo, EditedEulerMustAgreeWithQuaternion) {
  TempDir dir;
  const InputError e =
      EditedModelError(dir, [](YAML::Node& n) { n["base"]["euler"] = YAML::Load("[0.1, 0, 0]"); });
  EXPECT_EQ(e.key, "base.euler");
  EXPECT_THAT(e.expected, HasSubstr("predictions use q"));
}

TEST(ModelIo, QuaternionMustBeUnit) {
  TempDir dir;
  const InputError e = EditedModelError(dir, [](YAML::Node& n) { n["edm"]["q"][0] = 0.9; });
  EXPECT_EQ(e.key, "edm.q");
}

TEST(ModelIo, EditedReportValueMustAgreeWithSi) {
  TempDir dir;
  const InputError e = EditedModelError(dir, [](YAML::Node& n) {
    for (YAML::Node effect : n["effects"]) {
      if (effect["name"].as<std::string>() == "hz_scale") effect["report"]["s"]["value"] = 99;
    }
  });
  EXPECT_THAT(e.key, HasSubstr("].report"));
  EXPECT_THAT(e.expected, HasSubstr("predictions use si"));
}

TEST(ModelIo, StructuralErrors) {
  TempDir dir;
  EXPECT_EQ(EditedModelError(dir, [](YAML::Node& n) { n["format"] = "other"; }).key, "format");
  EXPECT_EQ(EditedModelError(dir, [](YAML::Node& n) { n["cameras"][1]["zoom"] = 5; }).key,
            "cameras[1].zoom");
  EXPECT_EQ(EditedModelError(dir, [](YAML::Node& n) { n.remove("edm"); }).key, "edm");
  EXPECT_EQ(EditedModelError(dir, [](YAML::Node& n) { n["effects"][0]["name"] = "wobble"; }).key,
            "effects[0].name");
  EXPECT_EQ(EditedModelError(dir, [](YAML::Node& n) { n["cameras"][0]["width"] = 0; }).key,
            "cameras[0].width");
  EXPECT_EQ(EditedModelError(dir, [](YAML::Node& n) { n["links"][0]["alpha"] = "x"; }).key,
            "links[0].alpha");
  // Sigmas present although the file says there are none.
  EXPECT_EQ(EditedModelError(dir, [](YAML::Node& n) { n["uncertainties"] = false; }).key,
            "base.sigma");
  // A negative standard deviation would make every uncertainty that uses it
  // wrong without a sign of it.
  const InputError sigma = EditedModelError(
      dir, [](YAML::Node& n) { n["cameras"][0]["intrinsics_sigma"]["fx"] = -5; });
  EXPECT_EQ(sigma.key, "cameras[0].intrinsics_sigma.fx");
  EXPECT_THAT(sigma.expected, HasSubstr("standard deviation >= 0"));
  EXPECT_EQ(EditedModelError(dir, [](YAML::Node& n) { n["base"]["sigma"]["t"][1] = -1e-3; }).key,
            "base.sigma.t[1]");
  EXPECT_EQ(
      EditedModelError(dir, [](YAML::Node& n) { n["effects"][0]["covariance"][1] = 1.0; }).key,
      "effects[0].covariance");
}

// A covariance that the solver's inverse left asymmetric in its last digits
// (as an independent photo session wrote it: 7.9010951887060517e-13 against
// ...0487e-13) is read, and made exactly symmetric; a real asymmetry is not.
TEST(ModelIo, CovarianceAsymmetricByRoundOffIsRead) {
  TempDir dir;
  const std::string path = dir.Path("model.yaml");
  WriteModelYaml(path, RandomModel(Kinematics::kDh, 2, true, 6));
  YAML::Node n = YAML::LoadFile(path);
  const double c01 = n["effects"][0]["covariance"][1].as<double>();
  n["effects"][0]["covariance"][2] = c01 * (1 + 4e-15);
  std::ofstream(path) << YAML::Dump(n);
  const InstrumentModel m = ReadModelYaml(path);
  const Effect e = m.effects.List().front();
  const auto& cov = m.sigmas.effect_cov[static_cast<int>(e)];
  EXPECT_EQ(cov[1], cov[2]);
  EXPECT_NEAR(cov[1], c01, 1e-14 * std::abs(c01));
}

}  // namespace
}  // namespace rtscalib

namespace rtscalib {
namespace {

// SPEC 7: the estimated boards and points, with their uncertainties, are
// written and read back exactly; a model without them writes neither key.
TEST(ModelIoBoards, BoardsAndPointsRoundTrip) {
  testing_io::TempDir dir;
  InstrumentModel m = IdealModel(Kinematics::kSpherical, 1, CameraTool());
  EXPECT_EQ(m.boards.size(), 0u);
  WriteModelYaml(dir.Path("plain.yaml"), m, {});
  EXPECT_EQ(dir.Read("plain.yaml").find("boards"), std::string::npos);
  EXPECT_EQ(dir.Read("plain.yaml").find("points"), std::string::npos);

  EstimatedBoard b;
  b.board.first_id = 48;
  b.board.rows = 6;
  b.board.cols = 8;
  b.board.tag_size = 0.06;
  b.board.spacing = 0.015;
  b.board.border_bits = 2;  // Kalibr's AprilGrid (SPEC 7.2)
  b.board.ids_from = IdOrigin::kBottomLeft;
  b.pose = PoseBlock::FromRigid(Rigid3::FromEuler({0.1, -0.2, 1.3}, {2.0 / 3.0, -4.0, 1.5}));
  b.sigma.rotation = {1e-4, 2e-4, 3e-4};
  b.sigma.euler = {1e-4, 2e-4, 3e-4};
  b.sigma.t = {1e-3, 2e-3, 3e-3};
  m.boards.push_back(b);
  EstimatedPoint p;
  p.name = "prism 1";
  p.x = {1.0 / 3.0, 12.5, -0.25};
  p.sigma = {1e-4, 2e-4, 5e-4};
  m.points.push_back(p);
  m.sigmas.valid = true;
  m.sigmas.cam_tools.resize(1);
  m.sigmas.intrinsics.resize(1);
  m.sigmas.distortion.resize(1);
  WriteModelYaml(dir.Path("model.yaml"), m, {});
  const InstrumentModel r = ReadModelYaml(dir.Path("model.yaml"), nullptr);
  ASSERT_EQ(r.boards.size(), 1u);
  EXPECT_EQ(r.boards[0].board.first_id, 48);
  EXPECT_EQ(r.boards[0].board.rows, 6);
  EXPECT_EQ(r.boards[0].board.cols, 8);
  EXPECT_EQ(r.boards[0].board.tag_size, 0.06);
  EXPECT_EQ(r.boards[0].board.spacing, 0.015);
  EXPECT_EQ(r.boards[0].board.border_bits, 2);
  EXPECT_EQ(r.boards[0].board.ids_from, IdOrigin::kBottomLeft);
  EXPECT_FALSE(r.boards[0].board.pose_known);
  EXPECT_EQ(r.boards[0].pose.q, b.pose.q);
  EXPECT_EQ(r.boards[0].pose.t, b.pose.t);
  EXPECT_EQ(r.boards[0].sigma.t, b.sigma.t);
  ASSERT_EQ(r.points.size(), 1u);
  EXPECT_EQ(r.points[0].name, "prism 1");
  EXPECT_EQ(r.points[0].x, p.x);
  EXPECT_EQ(r.points[0].sigma, p.sigma);
}

// SPEC 7.1: one pose per placement, and a camera-only model (kinematics
// none): its cameras and per-zoom board poses (cam_from_board) are written
// and read back; no base, EDM or camera tool is written as if estimated.
TEST(ModelIoBoards, PlacementsAndCameraOnlyModelRoundTrip) {
  testing_io::TempDir dir;
  InstrumentModel m = IdealModel(Kinematics::kNone, 2, CameraTool());
  m.effects.Add(Effect::kRadialDistortion);
  m.cams[1].distortion[kK1] = -0.25;
  for (const auto& [placement, zoom] :
       std::vector<std::pair<std::string, int>>{{"p1", 0}, {"p1", 1}, {"left 02", 0}}) {
    EstimatedBoard b;
    b.board.kind = BoardKind::kChessboard;
    b.board.family = "chessboard";
    b.board.rows = 7;
    b.board.cols = 10;
    b.board.square_size = 0.025;
    b.placement = placement;
    b.zoom = zoom;
    b.pose = PoseBlock::FromRigid(Rigid3::FromEuler({0.1 * zoom, -0.2, 1.3}, {0.1, -0.2, 0.5}));
    m.boards.push_back(b);
  }
  WriteModelYaml(dir.Path("model.yaml"), m, {});
  const std::string text = dir.Read("model.yaml");
  EXPECT_EQ(text.find("flange_from_cam"), std::string::npos);
  EXPECT_EQ(text.find("base:"), std::string::npos);
  EXPECT_EQ(text.find("edm:"), std::string::npos);
  EXPECT_EQ(text.find("ref_from_board"), std::string::npos);
  EXPECT_NE(text.find("cam_from_board"), std::string::npos);
  const InstrumentModel r = ReadModelYaml(dir.Path("model.yaml"), nullptr);
  EXPECT_EQ(r.kinematics, Kinematics::kNone);
  ASSERT_EQ(r.NumZooms(), 2);
  EXPECT_EQ(r.cams[1].distortion[kK1], -0.25);
  EXPECT_FALSE(r.edm_determined);
  ASSERT_EQ(r.boards.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(r.boards[i].placement, m.boards[i].placement);
    EXPECT_EQ(r.boards[i].zoom, m.boards[i].zoom);
    EXPECT_EQ(r.boards[i].pose.q, m.boards[i].pose.q);
  }
  EXPECT_EQ(r.BoardOf(5, "p1", 1), &r.boards[1]);
  EXPECT_EQ(r.BoardOf(5, "p2", 1), nullptr);
  // A board of a zoom the model has no camera for names the key.
  InstrumentModel bad = m;
  bad.boards[1].zoom = 4;
  WriteModelYaml(dir.Path("bad.yaml"), bad, {});
  const InputError e = CatchInputError([&] { ReadModelYaml(dir.Path("bad.yaml"), nullptr); });
  EXPECT_THAT(e.what(), HasSubstr("zoom"));
}

// board_warp: one warp per board (shared by its placements), written with
// its covariance under the effect and read back bit for bit; every pose of
// the board carries it (its corners are warped: predictions use it). A warp
// of no board in the file, or a board without a warp, names the key.
TEST(ModelIoBoards, BoardWarpRoundTripsWithItsSigma) {
  testing_io::TempDir dir;
  InstrumentModel m = IdealModel(Kinematics::kNone, 1, CameraTool());
  m.effects.Add(Effect::kRadialDistortion);
  m.effects.Add(Effect::kBoardWarp);
  for (const std::string placement : {"p1", "p2"}) {
    EstimatedBoard b;
    b.board.kind = BoardKind::kChessboard;
    b.board.family = "chessboard";
    b.board.rows = 11;
    b.board.cols = 11;
    b.board.square_size = 0.077;
    b.placement = placement;
    b.zoom = 0;
    b.pose = PoseBlock::FromRigid(Rigid3::FromEuler({0.1, -0.2, 1.3}, {0.1, -0.2, 0.5}));
    m.boards.push_back(b);
  }
  SyncBoardWarps(&m);
  ASSERT_EQ(m.board_warps.size(), 1u);
  m.board_warps[0].w = {-1.0367429980730084e-3, 5.4051798868024392e-4};
  m.board_warps[0].cov = {9.3e-11, 2.3e-11, 2.3e-11, 4.27e-11};
  m.sigmas.valid = true;
  m.sigmas.intrinsics.assign(1, {1, 1, 1, 1});
  m.sigmas.distortion.assign(1, {});
  m.sigmas.cam_tools.assign(1, {});
  SyncBoardWarps(&m);
  WriteModelYaml(dir.Path("model.yaml"), m, {});
  const std::string text = dir.Read("model.yaml");
  EXPECT_THAT(text, HasSubstr("name: board_warp"));
  EXPECT_THAT(text, HasSubstr("unit: mm"));
  const InstrumentModel r = ReadModelYaml(dir.Path("model.yaml"), nullptr);
  ASSERT_TRUE(r.effects.Has(Effect::kBoardWarp));
  ASSERT_EQ(r.board_warps.size(), 1u);
  EXPECT_EQ(r.board_warps[0].first_id, 0);
  EXPECT_EQ(r.board_warps[0].w, m.board_warps[0].w);
  EXPECT_EQ(r.board_warps[0].cov, m.board_warps[0].cov);
  for (const EstimatedBoard& b : r.boards) {
    EXPECT_EQ(b.board.warp, m.board_warps[0].w) << b.Name();
    // The board's centre corner is warped by wx + wy (1 - 0 each) * ... its shape.
    const Eigen::Vector3d corner = b.board.CornersInBoard(44)[0];
    EXPECT_NE(corner.z(), 0.0);
  }
  // A warp of a board the file does not hold.
  InstrumentModel stray = m;
  stray.board_warps[0].first_id = 7;
  WriteModelYaml(dir.Path("stray.yaml"), stray, {});
  const InputError e = CatchInputError([&] { ReadModelYaml(dir.Path("stray.yaml"), nullptr); });
  EXPECT_THAT(e.what(), HasSubstr("board"));
}

}  // namespace
}  // namespace rtscalib

namespace rtscalib {
namespace {

// model.<group>.coefficients: the held coefficients are listed per camera
// (`distortion_held`) and their sigma is `held` (never a number such as 0);
// read back, the model holds the same coefficients.
TEST(ModelIo, HeldDistortionCoefficientsAreNamedAndHaveNoSigma) {
  TempDir dir;
  InstrumentModel m = RandomModel(Kinematics::kDh, 2, true, 5);
  m.cams[0].distortion_held[kK3] = true;
  m.cams[0].distortion[kK3] = 0.0;
  m.sigmas.distortion[0][kK3] = 0.0;
  m.cams[1].distortion_held[kP2] = true;
  m.sigmas.distortion[1][kP2] = 0.0;
  // Held flags of a group not in the model mean nothing and are not written.
  m.cams[1].distortion_held[kK4] = true;
  WriteModelYaml(dir.Path("model.yaml"), m);
  const YAML::Node n = YAML::LoadFile(dir.Path("model.yaml"));
  EXPECT_EQ(n["cameras"][0]["distortion_held"].as<std::vector<std::string>>(),
            (std::vector<std::string>{"k3"}));
  EXPECT_EQ(n["cameras"][1]["distortion_held"].as<std::vector<std::string>>(),
            (std::vector<std::string>{"p2"}));
  EXPECT_EQ(n["cameras"][0]["distortion_sigma"]["k3"].as<std::string>(), "held");
  EXPECT_EQ(n["cameras"][0]["distortion_sigma"]["k4"].as<std::string>(), "held");  // not in model
  EXPECT_EQ(n["cameras"][0]["distortion_sigma"]["k1"].as<double>(), m.sigmas.distortion[0][kK1]);
  EXPECT_EQ(n["cameras"][1]["distortion_sigma"]["p2"].as<std::string>(), "held");

  const InstrumentModel r = ReadModelYaml(dir.Path("model.yaml"));
  EXPECT_TRUE(r.cams[0].distortion_held[kK3]);
  EXPECT_FALSE(r.cams[0].distortion_held[kK1]);
  EXPECT_TRUE(r.cams[1].distortion_held[kP2]);
  EXPECT_FALSE(r.cams[1].distortion_held[kK4]);
  EXPECT_EQ(r.sigmas.distortion[0][kK3], 0.0);
  EXPECT_EQ(r.sigmas.distortion[0][kK1], m.sigmas.distortion[0][kK1]);
}

}  // namespace
}  // namespace rtscalib

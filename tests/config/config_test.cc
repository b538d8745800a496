#include "libcalib/config/config.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <thread>

#include "render/settings.h"
#include "tests/io/io_test_util.h"

namespace rtscalib {
namespace {

using ::testing::HasSubstr;
using testing_io::CatchInputError;
using testing_io::TempDir;

constexpr double kRadPerArcsec = M_PI / (180.0 * 3600.0);

// A config with one simulate section, so that it is complete without data.
constexpr const char* kSimulateOnly = "simulate: {seed: 3}\n";

// Writes `text` as run.yaml and returns the error that loading it must give.
InputError ConfigError(const TempDir& dir, const std::string& text) {
  const std::string path = dir.Write("run.yaml", text);
  return CatchInputError([&] { LoadConfig(path); });
}

// A config loaded as the rtscalib binary loads it: with the render module's
// section (render/settings.h).
RunConfig LoadWithRender(const std::string& path, render::RenderSettings* render) {
  return LoadConfig(path, {render::RenderConfigSection(render)});
}

InputError ConfigErrorWithRender(const TempDir& dir, const std::string& text) {
  const std::string path = dir.Write("run.yaml", text);
  render::RenderSettings render;
  return CatchInputError([&] { LoadWithRender(path, &render); });
}

// The first ```yaml block after `heading` in docs/config.md.
std::string DocsExample(const std::string& heading) {
  std::ifstream in(std::string(RTSCALIB_SOURCE_DIR) + "/docs/config.md");
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  const size_t at = text.find(heading);
  EXPECT_NE(at, std::string::npos) << heading;
  const size_t begin = text.find("```yaml\n", at) + 8;
  return text.substr(begin, text.find("```", begin) - begin);
}

TEST(Config, SpecMinimalExampleResolvesPathsAgainstTheConfigFolder) {
  TempDir dir;
  dir.Write("cfg/records.csv", "x\n");
  dir.Write("cfg/pixels.csv", "x\n");
  const std::string path = dir.Write("cfg/run.yaml", DocsExample("## Minimal example"));
  const RunConfig c = LoadConfig(path);
  EXPECT_EQ(c.config_path, dir.Path("cfg/run.yaml"));
  EXPECT_EQ(c.config_dir, dir.Path("cfg"));
  EXPECT_EQ(c.records_path, dir.Path("cfg/records.csv"));
  EXPECT_EQ(c.pixels_path, dir.Path("cfg/pixels.csv"));
  EXPECT_EQ(c.output_dir, dir.Path("cfg/out"));
  EXPECT_EQ(c.calibration.model.kinematics, Kinematics::kDh);
  EXPECT_EQ(c.calibration.model.effects.Names(),
            (std::vector<std::string>{"hz_eccentricity", "radial_distortion"}));
  EXPECT_EQ(c.calibration.model.edm_cyclic_unit_length, 1.5);
  EXPECT_FALSE(c.simulate.has_value());
  EXPECT_TRUE(c.notes.empty());
  // Untouched sections keep the structs' defaults.
  EXPECT_EQ(c.calibration.fit.max_iterations, FitOptions().max_iterations);
  EXPECT_EQ(c.calibration.model.faces, FaceMode::kJoint);
  EXPECT_EQ(c.calibration.model.intrinsics, IntrinsicsMode::kAuto);
  EXPECT_TRUE(c.calibration.diagnose.enabled);
}

TEST(Config, DocsFullExampleLoadsWithEveryKey) {
  TempDir dir;
  dir.Write("records.csv", "x\n");
  dir.Write("pixels.csv", "x\n");
  render::RenderSettings render;
  const RunConfig c =
      LoadWithRender(dir.Write("run.yaml", DocsExample("## Full example")), &render);
  ASSERT_EQ(c.calibration.model.cameras.size(), 2u);
  EXPECT_EQ(c.calibration.model.cameras[1].intrinsics[0], 2000);
  EXPECT_EQ(c.calibration.model.cameras[1].distortion[0], -0.05);
  EXPECT_EQ(c.calibration.model.cameras[1].distortion[13], 0.0);
  EXPECT_EQ(c.angle_unit, AngleUnit::kRad);
  ASSERT_EQ(c.calibration.model.distortion_choices.size(), 1u);
  const DistortionChoice& radial = c.calibration.model.distortion_choices[0];
  EXPECT_EQ(radial.group, Effect::kRadialDistortion);
  EXPECT_EQ(radial.coefficients, (std::vector<int>{kK1, kK2}));
  EXPECT_EQ(radial.At(0), (std::vector<int>{kK1, kK2}));
  EXPECT_EQ(radial.At(1), (std::vector<int>{kK1, kK2, kK3}));
  EXPECT_EQ(c.calibration.fit.loss, RobustLoss::kHuber);
  EXPECT_DOUBLE_EQ(c.calibration.fit.critical_region.max_zenith_rad, 135 * M_PI / 180);
  EXPECT_EQ(c.calibration.checks.max_sigma0, 100);
  EXPECT_FALSE(c.calibration.fit.fit_intrinsics);  // auto: the pipeline decides
  ASSERT_TRUE(c.simulate.has_value());
  EXPECT_FALSE(c.truth_from_paper);
  const SimulationOptions& sim = *c.simulate;
  EXPECT_EQ(sim.seed, 1u);
  EXPECT_DOUBLE_EQ(sim.noise.angle_rad, 1 * kRadPerArcsec);
  EXPECT_EQ(sim.plan.grid_phi_steps, 24);
  EXPECT_EQ(sim.plan.faces, (std::vector<int>{1, 2}));
  ASSERT_EQ(sim.targets.boards.size(), 1u);
  EXPECT_EQ(sim.targets.boards[0].ref_from_board.translation, Eigen::Vector3d(-0.19, 2.0, -0.14));
  const InstrumentModel& truth = sim.truth;
  EXPECT_EQ(truth.NumZooms(), 2);
  EXPECT_EQ(truth.cams[0].intrinsics[2], 321.5);
  EXPECT_EQ(truth.cams[0].distortion[0], -0.1);
  EXPECT_TRUE(truth.effects.Has(Effect::kRadialDistortion));  // from the coefficients
  EXPECT_FALSE(truth.effects.Has(Effect::kThinPrism));
  EXPECT_EQ(truth.links[0].p[kDhAlpha], 1.5708);
  const auto hz = truth.EffectValue(Effect::kHzEccentricity);
  EXPECT_NEAR(std::hypot(hz[0], hz[1]), 5 * kRadPerArcsec, 1e-18);
  EXPECT_NEAR(std::atan2(hz[1], hz[0]), 30 * M_PI / 180, 1e-12);
  EXPECT_NEAR(truth.EffectValue(Effect::kEdmScale)[0], 3e-6, 1e-20);
  EXPECT_NEAR(truth.base.Euler()[1], 0.0002, 1e-12);
  EXPECT_TRUE(render.enabled);
  EXPECT_EQ(render.jobs, 2);
  EXPECT_EQ(render.supersample, 3);
  EXPECT_EQ(render.blur_sigma, 0.5);
  // Data files win over the simulate section, and the log says so.
  ASSERT_EQ(c.notes.size(), 1u);
  EXPECT_THAT(c.notes[0], HasSubstr("simulate section is not used"));
}

TEST(Config, UnknownKeyNamesPathFileAndLine) {
  TempDir dir;
  const InputError e = ConfigError(dir, std::string(kSimulateOnly) +
                                            "model:\n"
                                            "  kinematics: dh\n"
                                            "  efects: [hz_eccentricity]\n");
  EXPECT_EQ(e.key, "model.efects");
  EXPECT_EQ(e.file, dir.Path("run.yaml"));
  EXPECT_EQ(e.line, 4);
  EXPECT_EQ(e.position, 3);
  EXPECT_THAT(e.what(), HasSubstr(dir.Path("run.yaml") + ":4:3: key 'model.efects'"));
  EXPECT_THAT(e.what(), HasSubstr("did you mean 'effects'?"));
}

TEST(Config, UnknownKeysEverywhereAreAllReported) {
  TempDir dir;
  const InputError e = ConfigError(dir,
                                   "simulate:\n"
                                   "  targets:\n"
                                   "    - {t: [0, 2, 0], colour: red}\n"
                                   "  plan: {zoom: [0]}\n"
                                   "outptu: results\n");
  EXPECT_EQ(e.key, "simulate.targets[0].colour");
  EXPECT_EQ(e.line, 3);
  EXPECT_THAT(e.what(), HasSubstr("key 'simulate.plan.zoom'"));
  EXPECT_THAT(e.what(), HasSubstr(":5:1: key 'outptu'"));
  EXPECT_THAT(e.what(), HasSubstr("did you mean 'output'?"));
}

// `render` belongs to the render module: without its reader it is an unknown
// top-level key like any other.
TEST(Config, RenderSectionWithoutItsReaderIsUnknown) {
  TempDir dir;
  const InputError e = ConfigError(dir, std::string(kSimulateOnly) + "render: {jobs: 2}\n");
  EXPECT_EQ(e.key, "render");
  EXPECT_EQ(e.line, 2);
}

// With its reader, a typo inside `render:` is an error with key path, file
// and line, also when data files are given and nothing is rendered.
TEST(Config, UnknownKeyInsideRenderIsAnErrorEvenWithDataFiles) {
  TempDir dir;
  dir.Write("records.csv", "x\n");
  const InputError e = ConfigErrorWithRender(dir,
                                             "data: {records: records.csv}\n"
                                             "render:\n"
                                             "  jobs: 2\n"
                                             "  jobz: 3\n");
  EXPECT_EQ(e.key, "render.jobz");
  EXPECT_EQ(e.file, dir.Path("run.yaml"));
  EXPECT_EQ(e.line, 4);
  EXPECT_THAT(e.what(), HasSubstr("did you mean 'jobs'?"));
}

TEST(Config, RenderValuesAreCheckedWhereTheyAreRead) {
  TempDir dir;
  const InputError e = ConfigErrorWithRender(
      dir, std::string(kSimulateOnly) + "render:\n  enabled: true\n  supersample: 0\n");
  EXPECT_EQ(e.key, "render.supersample");
  EXPECT_EQ(e.line, 4);
  EXPECT_EQ(ConfigErrorWithRender(dir, std::string(kSimulateOnly) + "render: {exposure: 0}\n").key,
            "render.exposure");
  render::RenderSettings render;
  LoadWithRender(dir.Write("run.yaml", std::string(kSimulateOnly) + "render: {jobs: 1}\n"),
                 &render);
  EXPECT_TRUE(render.enabled);  // a render section switches rendering on
  EXPECT_EQ(render.jobs, 1);
  EXPECT_EQ(render.noise_sigma, render::RenderSettings().noise_sigma);
  render.exposure = -1;
  EXPECT_THAT(render.Check(), HasSubstr("render.exposure"));
  render::RenderSettings absent;
  LoadWithRender(dir.Write("run.yaml", kSimulateOnly), &absent);
  EXPECT_FALSE(absent.enabled);
}

TEST(Config, UnknownEffectListsValidNames) {
  TempDir dir;
  const InputError e = ConfigError(
      dir, std::string(kSimulateOnly) + "model:\n  effects: [hz_eccentricity, hz_excentricity]\n");
  EXPECT_EQ(e.key, "model.effects[1]");
  EXPECT_EQ(e.line, 3);
  EXPECT_EQ(e.got, "hz_excentricity");
  for (const EffectInfo& info : EffectCatalogue()) EXPECT_THAT(e.expected, HasSubstr(info.name));
  EXPECT_THAT(e.expected, HasSubstr("did you mean 'hz_eccentricity'?"));
}

TEST(Config, EffectsAlreadyInDhAreRejected) {
  TempDir dir;
  const InputError e = ConfigError(
      dir, std::string(kSimulateOnly) + "model: {kinematics: dh, effects: [collimation]}\n");
  EXPECT_EQ(e.key, "model.effects[0]");
  EXPECT_THAT(e.expected, HasSubstr("spherical"));
  // ... but fine in the spherical kinematics.
  const RunConfig c = LoadConfig(dir.Write(
      "ok.yaml",
      std::string(kSimulateOnly) + "model: {kinematics: spherical, effects: [collimation]}\n"));
  EXPECT_TRUE(c.calibration.model.effects.Has(Effect::kCollimation));
}

TEST(Config, DuplicateEffect) {
  TempDir dir;
  const InputError e =
      ConfigError(dir, std::string(kSimulateOnly) + "model: {effects: [edm_scale, edm_scale]}\n");
  EXPECT_EQ(e.key, "model.effects[1]");
}

TEST(Config, WrongTypesNameKeyLineExpectedAndGot) {
  TempDir dir;
  const InputError e =
      ConfigError(dir, std::string(kSimulateOnly) + "fit:\n  max_iterations: lots\n");
  EXPECT_EQ(e.key, "fit.max_iterations");
  EXPECT_EQ(e.line, 3);
  EXPECT_THAT(e.what(), HasSubstr("expected an integer, got 'lots'"));

  const InputError kin =
      ConfigError(dir, std::string(kSimulateOnly) + "model: {kinematics: denavit}\n");
  EXPECT_EQ(kin.key, "model.kinematics");
  EXPECT_EQ(kin.expected, "one of dh, spherical, none");

  const InputError list =
      ConfigError(dir, std::string(kSimulateOnly) + "model: {effects: edm_scale}\n");
  EXPECT_EQ(list.key, "model.effects");
  EXPECT_EQ(list.expected, "a list");
}

TEST(Config, NegativeSigma) {
  TempDir dir;
  const InputError e = ConfigError(
      dir, std::string(kSimulateOnly) + "fit:\n  sigmas: {edm_m: 1e-5, cam_m: -1e-5}\n");
  EXPECT_EQ(e.key, "fit.sigmas.cam_m");
  EXPECT_EQ(e.got, "-1e-5");
  EXPECT_THAT(e.expected, HasSubstr("> 0"));
  const InputError noise = ConfigError(dir, "simulate: {noise: {pixel_px: -0.1}}\n");
  EXPECT_EQ(noise.key, "simulate.noise.pixel_px");
}

// fit.max_sigma0 reaches the calibration's checks; a factor <= 1 would fail
// every fit with noise and is refused.
TEST(Config, MaxSigma0) {
  TempDir dir;
  const RunConfig c =
      LoadConfig(dir.Write("run.yaml", std::string(kSimulateOnly) + "fit:\n  max_sigma0: 30\n"));
  EXPECT_EQ(c.calibration.checks.max_sigma0, 30);
  EXPECT_THAT(DumpConfig(c), HasSubstr("max_sigma0: 30"));
  const InputError e = ConfigError(dir, std::string(kSimulateOnly) + "fit:\n  max_sigma0: 1\n");
  EXPECT_EQ(e.key, "fit.max_sigma0");
  EXPECT_THAT(e.expected, HasSubstr("> 1"));
}

TEST(Config, ZenithLimitsMustBeInOrder) {
  TempDir dir;
  const InputError e =
      ConfigError(dir, std::string(kSimulateOnly) +
                           "fit:\n  critical_region: {min_zenith_deg: 100, max_zenith_deg: 90}\n");
  EXPECT_EQ(e.key, "fit.critical_region.max_zenith_deg");
  EXPECT_EQ(e.line, 3);
  const InputError range = ConfigError(
      dir, std::string(kSimulateOnly) + "fit:\n  critical_region: {min_zenith_deg: -5}\n");
  EXPECT_EQ(range.key, "fit.critical_region.min_zenith_deg");
}

TEST(Config, DistortionAtMost14) {
  TempDir dir;
  const InputError e =
      ConfigError(dir, std::string(kSimulateOnly) +
                           "model:\n  cameras:\n"
                           "    - {width: 640, height: 480, fx: 1, fy: 1, cx: 0, cy: 0,"
                           " distortion: [0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]}\n");
  EXPECT_EQ(e.key, "model.cameras[0].distortion");
  EXPECT_EQ(e.line, 4);
  EXPECT_THAT(e.expected, HasSubstr("at most 14"));
}

TEST(Config, CameraSizeMustBePositive) {
  TempDir dir;
  const InputError e = ConfigError(
      dir, std::string(kSimulateOnly) +
               "model:\n  cameras:\n    - {width: 640, height: 480, fx: 1, fy: 1, cx: 0, cy: 0}\n"
               "    - {width: 0, height: 480, fx: 1, fy: 1, cx: 0, cy: 0}\n");
  EXPECT_EQ(e.key, "model.cameras[1].width");
  EXPECT_EQ(e.line, 5);
  const InputError height =
      ConfigError(dir, "simulate:\n  truth:\n    cameras: [{height: -480}]\n");
  EXPECT_EQ(height.key, "simulate.truth.cameras[0].height");
  const InputError missing = ConfigError(
      dir, std::string(kSimulateOnly) + "model:\n  cameras: [{width: 640, height: 480, fx: 1}]\n");
  EXPECT_EQ(missing.key, "model.cameras[0].fy");
}

TEST(Config, DataFilesMustExist) {
  TempDir dir;
  const InputError e = ConfigError(dir, "data: {records: nothere.csv}\n");
  EXPECT_EQ(e.key, "data.records");
  EXPECT_EQ(e.got, "nothere.csv");
  EXPECT_THAT(e.expected, HasSubstr("relative paths start at the config's folder"));
}

TEST(Config, NeedsDataOrSimulation) {
  TempDir dir;
  const InputError e = ConfigError(dir, "model: {kinematics: dh}\n");
  EXPECT_EQ(e.key, "data");
  EXPECT_EQ(e.file, dir.Path("run.yaml"));
}

TEST(Config, SimulateWithoutTruthAsksForPaperTruth) {
  TempDir dir;
  const RunConfig c = LoadConfig(dir.Write(
      "run.yaml", "simulate: {plan: {zooms: [0, 2]}, noise: {angle_arcsec: 2}}\noutput: /tmp/x\n"));
  ASSERT_TRUE(c.simulate.has_value());
  EXPECT_TRUE(c.truth_from_paper);
  EXPECT_EQ(PlanNumZooms(c.simulate->plan), 3);
  EXPECT_EQ(c.output_dir, "/tmp/x");
}

TEST(Config, TruthCamerasMustCoverThePlanZooms) {
  TempDir dir;
  const InputError e =
      ConfigError(dir, "simulate:\n  plan: {zooms: [0, 1]}\n  truth: {cameras: [{fx: 900}]}\n");
  EXPECT_EQ(e.key, "simulate.plan.zooms");
  EXPECT_EQ(e.line, 2);
}

TEST(Config, TruthEffectsInReportUnits) {
  TempDir dir;
  const RunConfig c = LoadConfig(
      dir.Write("run.yaml",
                "simulate:\n  truth:\n    kinematics: spherical\n"
                "    effects: {collimation: 10, edm_offset: [-1.5], axis_wobble: [3, 90]}\n"));
  const InstrumentModel& truth = c.simulate->truth;
  EXPECT_EQ(truth.kinematics, Kinematics::kSpherical);
  EXPECT_NEAR(truth.EffectValue(Effect::kCollimation)[0], 10 * kRadPerArcsec, 1e-18);
  EXPECT_NEAR(truth.EffectValue(Effect::kEdmOffset)[0], -1.5e-3, 1e-18);
  EXPECT_NEAR(truth.EffectValue(Effect::kAxisWobble)[1], 3 * kRadPerArcsec, 1e-18);
  EXPECT_EQ(truth.effects.List().size(), 3u);

  const InputError count =
      ConfigError(dir, "simulate:\n  truth:\n    effects: {hz_eccentricity: [5]}\n");
  EXPECT_EQ(count.key, "simulate.truth.effects.hz_eccentricity");
  EXPECT_THAT(count.expected, HasSubstr("e (arcsec), phi_e (deg)"));
  const InputError name = ConfigError(dir, "simulate:\n  truth:\n    effects: {hz_ecc: [5, 1]}\n");
  EXPECT_EQ(name.key, "simulate.truth.effects.hz_ecc");
  EXPECT_EQ(name.got, "hz_ecc");
  EXPECT_EQ(name.line, 3);
  const InputError distortion =
      ConfigError(dir, "simulate:\n  truth:\n    effects: {radial_distortion: [1]}\n");
  EXPECT_THAT(distortion.expected, HasSubstr("cameras[zoom].distortion"));
  const InputError links =
      ConfigError(dir, "simulate:\n  truth: {kinematics: spherical, links: [[0, 0, 0, 0]]}\n");
  EXPECT_EQ(links.key, "simulate.truth.links");
}

TEST(Config, IntrinsicsFitIsReadIntoTheModelSettings) {
  TempDir dir;
  const RunConfig c =
      LoadConfig(dir.Write("run.yaml", std::string(kSimulateOnly) + "model: {intrinsics: fit}\n"));
  EXPECT_EQ(c.calibration.model.intrinsics, IntrinsicsMode::kFit);
  EXPECT_FALSE(c.calibration.fit.fit_intrinsics)
      << "Calibrate decides it (FitIntrinsics, libcalib/calibrate/intrinsics.h), not the config";
}

TEST(Config, BadPlanValues) {
  TempDir dir;
  EXPECT_EQ(ConfigError(dir, "simulate: {plan: {faces: [1, 3]}}\n").key, "simulate.plan.faces[1]");
  EXPECT_EQ(ConfigError(dir, "simulate: {plan: {zooms: []}}\n").key, "simulate.plan.zooms");
  EXPECT_EQ(ConfigError(dir, "simulate: {plan: {edm_distances: [1, 0]}}\n").key,
            "simulate.plan.edm_distances[1]");
  EXPECT_EQ(ConfigError(dir, "simulate: {plan: {grid: {phi_steps: 4}}}\n").key,
            "simulate.plan.grid.theta_steps");
  EXPECT_EQ(ConfigError(dir, "simulate: {targets: [{rows: 2}]}\n").key, "simulate.targets[0].t");
  EXPECT_EQ(ConfigError(dir, "simulate: {shots: {fill: 1.5}}\n").key, "simulate.shots.fill");
  EXPECT_EQ(ConfigError(dir, "simulate: {seed: -1}\n").key, "simulate.seed");
  EXPECT_EQ(ConfigError(dir, std::string(kSimulateOnly) + "diagnose: {significance: 1}\n").key,
            "diagnose.significance");
}

// Sizes that would exhaust memory (a 1e5 x 1e5 grid: 12.6 GB; 100000
// threads: 2.2 GB) are errors at their key before anything is allocated.
TEST(Config, SizeBoundsNameTheKey) {
  TempDir dir;
  const InputError grid =
      ConfigError(dir, "simulate: {plan: {grid: {phi_steps: 100000, theta_steps: 100000}}}\n");
  EXPECT_EQ(grid.key, "simulate.plan");
  EXPECT_EQ(grid.expected,
            "a plan within the simulation's bounds: the plan gives 2.2e+11 records, more than the "
            "limit of 2e+06 (grid 100000 x 100000 poses, 15 sweep points); make "
            "simulate.plan.grid.phi_steps x theta_steps, grid.pixels_per_axis or sweep_points "
            "smaller");
  const InputError zoom = ConfigError(dir, "simulate: {plan: {zooms: [0, 1000000]}}\n");
  EXPECT_EQ(zoom.expected,
            "a plan within the simulation's bounds: simulate.plan.zooms entries must be < 100 "
            "(got 1000000; zoom levels are 0..N-1, SPEC 2)");
  const InputError threads =
      ConfigError(dir, std::string(kSimulateOnly) + "fit: {threads: 100000}\n");
  EXPECT_EQ(threads.key, "fit.threads");
  const int max_threads = 4 * static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  EXPECT_EQ(threads.expected, "a thread count 1.." + std::to_string(max_threads) +
                                  " (at most 4 x this machine's " +
                                  std::to_string(max_threads / 4) + " hardware threads)");
  EXPECT_EQ(ConfigError(dir, std::string(kSimulateOnly) + "fit: {threads: 0}\n").key,
            "fit.threads");
}

// A runaway file (a 10-million-element list under a mistyped key) is
// refused by its size before yaml-cpp builds it (it would cost ~50 times
// the file's size); an empty output folder would be the config's own.
TEST(Config, HugeFileAndEmptyOutputAreRefusedByName) {
  TempDir dir;
  std::string big = std::string(kSimulateOnly) + "simulat: [";
  big.reserve(5u << 20);
  while (big.size() < (5u << 20)) big += "1234567, ";
  big += "0]\n";
  const InputError size = ConfigError(dir, big);
  EXPECT_EQ(size.file, dir.Path("run.yaml"));
  EXPECT_EQ(size.subject, "file size");
  EXPECT_EQ(size.expected, "a config of at most 4 MiB");
  const InputError output = ConfigError(dir, std::string(kSimulateOnly) + "output: \"\"\n");
  EXPECT_EQ(output.key, "output");
  EXPECT_EQ(output.line, 2);
}

TEST(Config, ScreenSection) {
  TempDir dir;
  const RunConfig c = LoadConfig(dir.Write(
      "run.yaml", std::string(kSimulateOnly) +
                      "screen: {pixel_margin_px: 10, max_extent_m: 500, max_missing_zooms: 2}\n"));
  EXPECT_EQ(c.calibration.screen.pixel_margin_px, 10.0);
  EXPECT_EQ(c.calibration.screen.max_extent_m, 500.0);
  EXPECT_EQ(c.calibration.screen.max_missing_zooms, 2);
  EXPECT_EQ(ConfigError(dir, std::string(kSimulateOnly) + "screen: {max_extent_m: 0}\n").key,
            "screen.max_extent_m");
  const InputError many =
      ConfigError(dir, std::string(kSimulateOnly) + "screen: {max_missing_zooms: 5000}\n");
  EXPECT_EQ(many.key, "screen");
  EXPECT_EQ(many.expected, "screen.max_missing_zooms must be in 0..1000 (got 5000)");
  EXPECT_EQ(ConfigError(dir, std::string(kSimulateOnly) + "screen: {margin: 3}\n").key,
            "screen.margin");
}

// The dump is a config that loads to the same run, and dumping that again
// gives the same text (paths are absolute, numbers exact).
TEST(Config, DumpLoadsBackToTheSameConfig) {
  TempDir dir;
  dir.Write("records.csv", "x\n");
  dir.Write("pixels.csv", "x\n");
  render::RenderSettings render_a, render_b;
  const RunConfig a =
      LoadWithRender(dir.Write("run.yaml", DocsExample("## Full example")), &render_a);
  const std::string dump_a = DumpConfig(a, {render::RenderConfigSection(&render_a)});
  const RunConfig b = LoadWithRender(dir.Write("elsewhere/dump.yaml", dump_a), &render_b);
  const std::string dump_b = DumpConfig(b, {render::RenderConfigSection(&render_b)});
  EXPECT_EQ(b.records_path, a.records_path);
  EXPECT_EQ(b.pixels_path, a.pixels_path);
  EXPECT_EQ(b.output_dir, a.output_dir);
  EXPECT_EQ(b.calibration.model.effects, a.calibration.model.effects);
  EXPECT_EQ(b.calibration.model.cameras.size(), a.calibration.model.cameras.size());
  EXPECT_EQ(b.calibration.model.cameras[1].distortion, a.calibration.model.cameras[1].distortion);
  EXPECT_EQ(b.calibration.fit.sigma_edm_m, a.calibration.fit.sigma_edm_m);
  EXPECT_EQ(b.calibration.fit.loss, a.calibration.fit.loss);
  EXPECT_EQ(b.calibration.fit.critical_region.min_zenith_rad,
            a.calibration.fit.critical_region.min_zenith_rad);
  EXPECT_EQ(b.simulate->noise.angle_rad, a.simulate->noise.angle_rad);
  EXPECT_EQ(b.simulate->plan.grid_edm_distances, a.simulate->plan.grid_edm_distances);
  EXPECT_EQ(b.simulate->truth.effects, a.simulate->truth.effects);
  EXPECT_EQ(b.simulate->truth.base.q, a.simulate->truth.base.q);
  EXPECT_EQ(b.simulate->truth.cams[0].flange_from_cam.q,
            a.simulate->truth.cams[0].flange_from_cam.q);
  EXPECT_EQ(b.simulate->truth.links[0].p, a.simulate->truth.links[0].p);
  // Polar effects go through amplitude/phase in report units and back;
  // 1e-15 relative is that conversion's rounding.
  const auto cyclic_a = a.simulate->truth.EffectValue(Effect::kEdmCyclic);
  const auto cyclic_b = b.simulate->truth.EffectValue(Effect::kEdmCyclic);
  for (int i = 0; i < 2; ++i) EXPECT_NEAR(cyclic_b[i], cyclic_a[i], 1e-15 * std::abs(cyclic_a[i]));
  EXPECT_EQ(render_b.enabled, render_a.enabled);
  EXPECT_EQ(render_b.supersample, render_a.supersample);
  EXPECT_EQ(render_b.blur_sigma, render_a.blur_sigma);
  EXPECT_EQ(render_b.family, render_a.family);
  EXPECT_EQ(b.calibration.diagnose.significance, a.calibration.diagnose.significance);
  EXPECT_EQ(b.calibration.screen.pixel_margin_px, a.calibration.screen.pixel_margin_px);
  EXPECT_EQ(b.calibration.screen.max_extent_m, a.calibration.screen.max_extent_m);
  EXPECT_EQ(b.calibration.screen.max_missing_zooms, a.calibration.screen.max_missing_zooms);
  EXPECT_EQ(b.truth_from_paper, a.truth_from_paper);
  EXPECT_EQ(b.simulate->targets.boards[0].ref_from_board.translation,
            a.simulate->targets.boards[0].ref_from_board.translation);
  EXPECT_EQ(dump_b, dump_a);
}

TEST(Config, TruthPoseAsQuaternion) {
  TempDir dir;
  const RunConfig c = LoadConfig(
      dir.Write("run.yaml", "simulate:\n  truth: {base: {q: [0, 0, 0.6, 0.8], t: [1, 2, 3]}}\n"));
  EXPECT_EQ(c.simulate->truth.base.q, (std::array<double, 4>{0, 0, 0.6, 0.8}));
  EXPECT_EQ(ConfigError(dir, "simulate:\n  truth: {base: {q: [0, 0, 0.6, 0.9]}}\n").key,
            "simulate.truth.base.q");
  EXPECT_EQ(
      ConfigError(dir, "simulate:\n  truth: {base: {q: [0, 0, 0, 1], euler: [0, 0, 0]}}\n").key,
      "simulate.truth.base.q");
}

// Found by fuzz/config_fuzzer.cc: a data path too long for the file system
// is an input error naming the key, not a std::filesystem_error.
TEST(Config, DataPathTooLongForTheFileSystemIsAnInputError) {
  TempDir dir;
  const InputError e = ConfigError(dir, "data: {records: " + std::string(300, 'r') + ".csv}\n");
  EXPECT_EQ(e.key, "data.records");
  EXPECT_THAT(e.what(), HasSubstr("an existing file"));
}

// Found by fuzz/config_fuzzer.cc: texts with control characters are written
// quoted, so the effective config loads back to the same values.
TEST(Config, DumpedTextWithCarriageReturnLoadsBackUnchanged) {
  TempDir dir;
  const RunConfig c = LoadConfig(dir.Write("run.yaml", "simulate: {seed: 3}\noutput: \"o\\r\"\n"));
  ASSERT_EQ(c.output_dir.back(), '\r');
  const RunConfig again = LoadConfig(dir.Write("again.yaml", DumpConfig(c)));
  EXPECT_EQ(again.output_dir, c.output_dir);
}

}  // namespace
}  // namespace rtscalib

namespace rtscalib {
namespace {

// SPEC 7: a photo session in the config, paths relative to the config file.
TEST(Config, ShotsAndTargetsAreReadRelativeToTheConfig) {
  TempDir dir;
  dir.Write("shots.csv", "face,zoom,phi,theta,image\n");
  dir.Write("targets.yaml", "boards: []\n");
  const std::string path =
      dir.Write("run.yaml", "data: {shots: shots.csv, targets: targets.yaml}\ndetect: {jobs: 3}\n");
  const RunConfig c = LoadConfig(path);
  EXPECT_EQ(c.shots_path, dir.Path("shots.csv"));
  EXPECT_EQ(c.targets_path, dir.Path("targets.yaml"));
  EXPECT_EQ(c.detect_jobs, 3);
  EXPECT_FALSE(c.simulate.has_value());
  // The effective config reads back to the same paths.
  const std::string dumped = dir.Write("dumped.yaml", DumpConfig(c));
  const RunConfig again = LoadConfig(dumped);
  EXPECT_EQ(again.shots_path, c.shots_path);
  EXPECT_EQ(again.targets_path, c.targets_path);
  EXPECT_EQ(again.detect_jobs, 3);
}

TEST(Config, ShotsWithoutTargetsNameTheMissingKey) {
  TempDir dir;
  dir.Write("shots.csv", "face,zoom,phi,theta,image\n");
  const InputError e = ConfigError(dir, "data: {shots: shots.csv}\n");
  EXPECT_EQ(e.key, "data.shots");
  EXPECT_THAT(e.what(), HasSubstr("data.targets next to data.shots"));
}

// SPEC 7: pixels.csv rows with empty X, Y, Z are corners of the boards of
// data.targets (what `rtscalib detect` writes): pixels and targets without
// photos are a whole data set; targets alone are not.
TEST(Config, TargetsGoWithShotsOrPixels) {
  TempDir dir;
  dir.Write("pixels.csv", "face,zoom,phi,theta,shot,target,corner,X,Y,Z,u,v\n");
  dir.Write("records.csv", "face,zoom,phi,theta,tool,u,v,d,x,y,z\n");
  dir.Write("targets.yaml", "boards: []\n");
  const RunConfig c = LoadConfig(dir.Write("run.yaml",
                                           "data: {pixels: pixels.csv, targets: targets.yaml}\n"));
  EXPECT_EQ(c.targets_path, dir.Path("targets.yaml"));
  EXPECT_TRUE(c.shots_path.empty());
  const InputError e = ConfigError(dir, "data: {records: records.csv, targets: targets.yaml}\n");
  EXPECT_EQ(e.key, "data.targets");
  EXPECT_THAT(e.what(), HasSubstr("data.shots or data.pixels next to data.targets (the boards "
                                  "are seen in photos, or in pixels.csv rows with empty X, Y, Z)"));
}

TEST(Config, BoardPosesMustBeKnownOrUnknown) {
  TempDir dir;
  render::RenderSettings render;
  const std::string path =
      dir.Write("run.yaml", std::string(kSimulateOnly) + "render: {board_poses: surveyed}\n");
  const InputError e = CatchInputError([&] { LoadWithRender(path, &render); });
  EXPECT_EQ(e.key, "render.board_poses");
  const std::string ok =
      dir.Write("ok.yaml", std::string(kSimulateOnly) + "render: {board_poses: unknown}\n");
  LoadWithRender(ok, &render);
  EXPECT_FALSE(render.board_poses_known);
}

}  // namespace
}  // namespace rtscalib

namespace rtscalib {
namespace {

TEST(ConfigAngleUnit, DefaultIsRadiansAndEachNameIsRead) {
  TempDir dir;
  dir.Write("records.csv", "x\n");
  EXPECT_EQ(LoadConfig(dir.Write("a.yaml", "data: {records: records.csv}\n")).angle_unit,
            AngleUnit::kRad);
  for (AngleUnit unit : {AngleUnit::kRad, AngleUnit::kDeg, AngleUnit::kGon}) {
    const std::string text =
        std::string("data: {records: records.csv, angle_unit: ") + AngleUnitName(unit) + "}\n";
    const RunConfig c = LoadConfig(dir.Write("b.yaml", text));
    EXPECT_EQ(c.angle_unit, unit);
    // --write-config spells it out and reads back the same.
    const RunConfig again = LoadConfig(dir.Write("c.yaml", DumpConfig(c)));
    EXPECT_EQ(again.angle_unit, unit);
  }
}

TEST(ConfigAngleUnit, UnknownUnitNamesKeyExpectedValuesAndWhatCame) {
  TempDir dir;
  dir.Write("records.csv", "x\n");
  const InputError e = ConfigError(dir, "data:\n  records: records.csv\n  angle_unit: degrees\n");
  EXPECT_EQ(e.file, dir.Path("run.yaml"));
  EXPECT_EQ(e.key, "data.angle_unit");
  EXPECT_EQ(e.line, 3);
  EXPECT_EQ(e.got, "degrees");
  for (const char* name : {"rad", "deg", "gon"}) EXPECT_THAT(e.expected, HasSubstr(name));
  EXPECT_THAT(e.what(), HasSubstr("run.yaml:3"));
  EXPECT_THAT(e.what(), HasSubstr("data.angle_unit"));
  EXPECT_THAT(e.what(), HasSubstr("'degrees'"));
}

}  // namespace
}  // namespace rtscalib

namespace rtscalib {
namespace {

TEST(ConfigDistortionChoice, ReadsAndDumpsTheCoefficientsToFit) {
  TempDir dir;
  const RunConfig c = LoadConfig(dir.Write(
      "a.yaml", std::string(kSimulateOnly) +
                    "model:\n  effects: [radial_distortion, tangential_distortion]\n"
                    "  radial_distortion: {coefficients: [k2, k1], zooms: {2: [k1], 3: []}}\n"
                    "  tangential_distortion: {zooms: {0: [p2]}}\n"));
  ASSERT_EQ(c.calibration.model.distortion_choices.size(), 2u);
  const DistortionChoice& radial = c.calibration.model.distortion_choices[0];
  EXPECT_EQ(radial.coefficients, (std::vector<int>{kK1, kK2}));  // sorted
  EXPECT_EQ(radial.At(2), (std::vector<int>{kK1}));
  EXPECT_TRUE(radial.At(3).empty());
  const DistortionChoice& tangential = c.calibration.model.distortion_choices[1];
  EXPECT_EQ(tangential.coefficients, (std::vector<int>{kP1, kP2}));  // default: all
  EXPECT_EQ(tangential.At(0), (std::vector<int>{kP2}));
  // --write-config writes them and reads back the same.
  const RunConfig again = LoadConfig(dir.Write("b.yaml", DumpConfig(c)));
  ASSERT_EQ(again.calibration.model.distortion_choices.size(), 2u);
  EXPECT_EQ(again.calibration.model.distortion_choices[0].zooms, radial.zooms);
  EXPECT_EQ(again.calibration.model.distortion_choices[0].coefficients, radial.coefficients);
  EXPECT_EQ(again.calibration.model.distortion_choices[1].zooms, tangential.zooms);
}

TEST(ConfigDistortionChoice, ErrorsNameTheKeyExpectedAndGot) {
  TempDir dir;
  // A coefficient of another group.
  InputError e = ConfigError(dir, std::string(kSimulateOnly) +
                                      "model:\n  effects: [radial_distortion]\n"
                                      "  radial_distortion: {coefficients: [k1, p1]}\n");
  EXPECT_EQ(e.key, "model.radial_distortion.coefficients[1]");
  EXPECT_EQ(e.got, "p1");
  EXPECT_THAT(e.expected, HasSubstr("k3"));
  // The group is not in the model: the choice would be silently ignored.
  e = ConfigError(dir, std::string(kSimulateOnly) +
                           "model:\n  effects: [hz_eccentricity]\n"
                           "  radial_distortion: {coefficients: [k1]}\n");
  EXPECT_EQ(e.key, "model.radial_distortion");
  EXPECT_THAT(e.expected, HasSubstr("radial_distortion in model.effects"));
  // Twice the same coefficient, an unknown key, a negative zoom.
  e = ConfigError(dir, std::string(kSimulateOnly) +
                           "model:\n  effects: [radial_distortion]\n"
                           "  radial_distortion: {coefficients: [k1, k1]}\n");
  EXPECT_THAT(e.expected, HasSubstr("each coefficient once"));
  e = ConfigError(dir, std::string(kSimulateOnly) +
                           "model:\n  effects: [radial_distortion]\n"
                           "  radial_distortion: {coefficient: [k1]}\n");
  EXPECT_EQ(e.key, "model.radial_distortion.coefficient");
  e = ConfigError(dir, std::string(kSimulateOnly) +
                           "model:\n  effects: [radial_distortion]\n"
                           "  radial_distortion: {zooms: {-1: [k1]}}\n");
  EXPECT_THAT(e.expected, HasSubstr("zoom level >= 0"));
}

}  // namespace
}  // namespace rtscalib

namespace rtscalib {
namespace {

// board_warp is turned on with one line, in a camera-only model too; the
// simulated truth hides a warp per board (simulate.targets[i].warp [m]),
// which the effective config writes and reads back; a warp is no kinematic
// value of the truth.
TEST(Config, BoardWarpOnOneLineAndHiddenInTheSimulatedBoards) {
  TempDir dir;
  const RunConfig c = LoadConfig(dir.Write(
      "run.yaml",
      "simulate:\n"
      "  seed: 3\n"
      "  targets: [{first_id: 0, rows: 3, cols: 4, tag_size: 0.08, spacing: 0.02,\n"
      "             t: [0, 5, 0], warp: [0.001, -0.0005]}]\n"
      "model: {kinematics: none, effects: [radial_distortion, board_warp]}\n"));
  EXPECT_TRUE(c.calibration.model.effects.Has(Effect::kBoardWarp));
  ASSERT_TRUE(c.simulate.has_value());
  ASSERT_EQ(c.simulate->targets.boards.size(), 1u);
  EXPECT_EQ(c.simulate->targets.boards[0].warp, (std::array<double, 2>{0.001, -0.0005}));
  const RunConfig again = LoadConfig(dir.Write("again.yaml", DumpConfig(c)));
  EXPECT_EQ(again.simulate->targets.boards[0].warp, c.simulate->targets.boards[0].warp);
  const InputError e = ConfigError(dir, "simulate: {seed: 3, truth: {effects: {board_warp: 1}}}\n");
  EXPECT_THAT(e.what(), HasSubstr("simulate.targets[i].warp"));
}

}  // namespace
}  // namespace rtscalib

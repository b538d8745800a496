// The calibration as a library call (libcalib/calibrate): simulated
// observations (libcalib/sim) -> Calibrate -> every stage's outcome, checked
// against the simulated truth. No file is read or written and nothing of the
// rtscalib binary is used.
#include "libcalib/calibrate/calibrate.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "libcalib/eval/error_measures.h"
#include "libcalib/model/critical_region.h"
#include "libcalib/sim/simulator.h"
#include "libcalib/text/errors.h"

namespace rtscalib {
namespace {

using ::testing::Contains;
using ::testing::HasSubstr;

// Klug's sweeps plus a grid whose camera rows span the image, so that the
// automatic intrinsics decision fits the intrinsics.
AcquisitionPlan TrainingPlan() {
  AcquisitionPlan plan;
  plan.grid_phi_steps = 10;
  plan.grid_theta_steps = 6;
  return plan;
}

// Klug's instrument (PaperTruth, one zoom) observed with the training plan.
SimulationOptions PaperSession(std::uint64_t seed) {
  SimulationOptions sim;
  sim.seed = seed;
  sim.truth = PaperTruth(1);
  sim.plan = TrainingPlan();
  return sim;
}

// Held-out records: other angles, distances up to 47 m and other pixels than
// the training plan, outside the default critical regions.
std::vector<Record> HeldOut(const InstrumentModel& truth) {
  AcquisitionPlan plan;
  plan.sweeps = false;
  plan.grid_phi_steps = 7;
  plan.grid_theta_steps = 5;
  plan.grid_edm_distances = {3.3, 47.0};
  plan.grid_cam_ray_lengths = {2.2, 9.0};
  plan.grid_pixels_per_axis = 4;
  std::vector<Record> out;
  for (const Record& r : PlanRecords(plan, truth)) {
    if (!CriticalRegion().Contains(r.theta)) out.push_back(r);
  }
  return out;
}

// What a user configures: the camera the device API reports (image size and
// principal point); the focal length only roughly, no camera pose.
CalibrationOptions ApiOptions(const InstrumentModel& truth) {
  CalibrationOptions o;
  o.model.cameras = truth.cams;
  for (CameraTool& c : o.model.cameras) {
    c.flange_from_cam = PoseBlock();
    c.intrinsics[0] = c.intrinsics[1] = 1500.0;
  }
  o.diagnose.enabled = false;
  return o;
}

double WorstHeldOutError(const InstrumentModel& model, const InstrumentModel& truth) {
  double worst = 0;
  for (const RecordResidual& r : RecordResiduals(model, HeldOut(truth))) {
    EXPECT_TRUE(r.valid);
    worst = std::max(worst, r.distance);
  }
  return worst;
}

// Remembers every step the calibration announces.
class RecordingProgress : public CalibrationProgress {
 public:
  void Step(const std::string& name) override { steps.push_back(name); }
  void Note(const std::string&) override {}
  void Done() override { ++done; }
  std::vector<std::string> steps;
  int done = 0;
};

TEST(Calibrate, NoiseFreeRunRecoversTheTruthAndFillsEveryStage) {
  SimulationOptions sim = PaperSession(7);
  const SimulatedData data = Simulate(sim);
  RecordingProgress progress;
  const CalibrationResult r = Calibrate(data.obs, ApiOptions(sim.truth), &progress);

  ASSERT_TRUE(r.extraction.has_value());
  ASSERT_TRUE(r.simplified.has_value());
  EXPECT_FALSE(r.closed_form.empty());
  ASSERT_TRUE(r.table4.has_value());
  // The grid spans the image: model.intrinsics auto fits the intrinsics.
  EXPECT_TRUE(r.intrinsics_fitted);
  EXPECT_TRUE(r.fit_options.fit_intrinsics);
  EXPECT_TRUE(r.refined.fit.converged) << r.refined.fit.message;
  EXPECT_TRUE(r.table5.has_cross);
  EXPECT_LT(r.table5.reduced_rows, r.table5.full_rows);
  EXPECT_EQ(r.table5.full_rows, static_cast<int>(data.obs.records.size()));
  EXPECT_FALSE(r.faces.has_value());  // faces: joint
  EXPECT_FALSE(r.diagnosis.has_value());
  EXPECT_TRUE(r.ladder.empty());
  EXPECT_FALSE(r.LadderExtendedModel());

  // Exact data leave round-off only (~1e-15 m per metre); 1e-9 m at up to
  // 47 m is the bound tests/fit/extract_then_refine_test.cc uses.
  EXPECT_LT(WorstHeldOutError(r.model, sim.truth), 1e-9);
  EXPECT_LT(r.final_errors.edm.max_m, 1e-9);
  EXPECT_LT(r.final_errors.cam.max_m, 1e-9);
  // Table 5 (method B) on the camera rows is exact as well. Its EDM points
  // 1 m off the ray hang on the EDM x axis that the measurements define
  // (Eq. 79), which even the truth does not reproduce exactly: not checked.
  EXPECT_LT(r.table5.full.cam.max_m, 1e-9);
  // Intrinsics from a 1500 px guess to the truth's 1000 px: exact data,
  // so round-off of the fit only (1e-6 px is 1e-9 relative).
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(r.model.cams[0].intrinsics[i], sim.truth.cams[0].intrinsics[i], 1e-6) << i;
  }
  // Without the ladder, the run's model is the configured refined model.
  EXPECT_EQ(r.model.cams[0].intrinsics, r.refined.model.cams[0].intrinsics);
  EXPECT_EQ(r.model.links[0].p, r.refined.model.links[0].p);

  EXPECT_THAT(progress.steps, Contains("extracting the DH model (Klug Sec. 3)"));
  EXPECT_THAT(progress.steps, Contains("simplifying (Klug Sec. 4.1)"));
  EXPECT_EQ(progress.done, 1);
}

// The calibration stands without its diagnosis: when the diagnosis throws,
// DiagnoseCalibration returns no diagnosis and one note saying why, and
// AddDiagnosis puts that note into the result and leaves its model alone.
// The throw is a real one of Diagnose: a result whose every row was set
// aside as gross leaves it nothing to linearize.
TEST(Calibrate, AFailedDiagnosisIsANoteAndTheModelStands) {
  SimulationOptions sim = PaperSession(7);
  const SimulatedData data = Simulate(sim);
  CalibrationOptions options = ApiOptions(sim.truth);
  options.diagnose.enabled = true;
  ASSERT_TRUE(DiagnosisPending(options));
  CalibrationResult r = CalibrateModel(data.obs, options);
  ASSERT_FALSE(r.diagnosis.has_value());
  ASSERT_TRUE(r.refined.fit.converged) << r.refined.fit.message;

  // The same result diagnosed as it is: a diagnosis and no note.
  const CalibrationDiagnosis fine = DiagnoseCalibration(data.obs, options, r);
  EXPECT_TRUE(fine.diagnosis.has_value());
  EXPECT_TRUE(fine.notes.empty());

  for (size_t i = 0; i < data.obs.records.size(); ++i) {
    ExcludedRow row;
    row.index = static_cast<int>(i);
    row.line = static_cast<int>(i) + 2;
    row.reason = "set aside by the test";
    r.gross_rows.push_back(row);
  }
  ASSERT_TRUE(data.obs.pixels.empty());
  RecordingProgress progress;
  const CalibrationDiagnosis failed = DiagnoseCalibration(data.obs, options, r, &progress);
  EXPECT_FALSE(failed.diagnosis.has_value());
  ASSERT_EQ(failed.notes.size(), 1u);
  EXPECT_THAT(failed.notes[0], HasSubstr("diagnosis failed: "));
  EXPECT_THAT(failed.notes[0], HasSubstr("nothing to diagnose"));
  EXPECT_EQ(progress.done, 1);  // the step is closed, as after a diagnosis

  const auto intrinsics = r.model.cams[0].intrinsics;
  const size_t notes_before = r.notes.size();
  AddDiagnosis(failed, &r);
  EXPECT_FALSE(r.diagnosis.has_value());
  ASSERT_EQ(r.notes.size(), notes_before + 1);
  EXPECT_EQ(r.notes.back(), failed.notes[0]);
  EXPECT_EQ(r.model.cams[0].intrinsics, intrinsics);
}

TEST(Calibrate, NoisyRunWithinTenPercentOfTheNoiseFloor) {
  SimulationOptions sim = PaperSession(11);
  sim.noise.point_m = 2e-5;
  sim.noise.angle_rad = 1.0 / 206265.0;  // 1 arcsec
  const SimulatedData data = Simulate(sim);
  CalibrationOptions options = ApiOptions(sim.truth);
  options.fit.sigma_edm_m = options.fit.sigma_cam_m = 2e-5;
  const CalibrationResult r = Calibrate(data.obs, options);  // no progress: silent

  // Noise floor: the truth's own error on the same noisy records (Eq. 92).
  // A least-squares model fitted to these records cannot do much worse than
  // the truth on them; 10 % is the margin tests/fit/extract_then_refine_test.cc
  // established for the same noise.
  const ModelErrors fit = EvaluateRecords(r.model, data.obs.records, ErrorMethod::kA);
  const ModelErrors floor = EvaluateRecords(sim.truth, data.obs.records, ErrorMethod::kA);
  EXPECT_LE(fit.compound.mean_m, 1.1 * floor.compound.mean_m);
  EXPECT_LE(fit.edm.mean_m, 1.1 * floor.edm.mean_m);
  EXPECT_LE(fit.cam.mean_m, 1.1 * floor.cam.mean_m);
  // Table 5's full column is the refined model on every record (method B).
  const ModelErrors full = EvaluateRecords(r.refined.model, data.obs.records, ErrorMethod::kB);
  EXPECT_EQ(r.table5.full.compound.mean_m, full.compound.mean_m);
}

// With fit.threads > 1 the reduced set's refinement runs beside the
// gross-error search, from the same start. When the search takes no row
// out, the calibration is the one made with the stages in order (the search
// switched off: the reduced set then starts after the extraction, as
// before). Tolerance: both make the same fits from the same start, but
// Ceres's parallel evaluation sums the cost in a varying order, and a
// round-off difference can take an LM step one way or the other at the
// last digits: 1e-9 relative on Table 5's errors, where a reduced fit from
// another start or with other rows differs in the third digit.
TEST(Calibrate, ReducedSetRefinedBesideTheGrossErrorSearchIsTheOneMadeAfterIt) {
  class Notes : public CalibrationProgress {
   public:
    void Step(const std::string&) override {}
    void Note(const std::string& n) override { notes.push_back(n); }
    void Done() override {}
    std::vector<std::string> notes;
  };
  SimulationOptions sim = PaperSession(11);
  sim.noise.point_m = 2e-5;
  sim.noise.angle_rad = 1.0 / 206265.0;
  const SimulatedData data = Simulate(sim);
  CalibrationOptions in_order = ApiOptions(sim.truth);
  in_order.fit.sigma_edm_m = in_order.fit.sigma_cam_m = 2e-5;
  in_order.fit.gross_errors.enabled = false;
  CalibrationOptions beside = in_order;
  beside.fit.gross_errors.enabled = true;
  ASSERT_GT(beside.fit.num_threads, 1);
  Notes progress;
  const CalibrationResult a = Calibrate(data.obs, in_order);
  const CalibrationResult b = Calibrate(data.obs, beside, &progress);

  EXPECT_THAT(progress.notes, Contains("refined beside the gross-error search"));
  EXPECT_TRUE(b.gross_rows.empty());
  ASSERT_LT(b.table5.reduced_rows, b.table5.full_rows);  // a reduced set of its own
  EXPECT_EQ(a.table5.reduced_rows, b.table5.reduced_rows);
  EXPECT_NEAR(b.table5.reduced.compound.mean_m, a.table5.reduced.compound.mean_m,
              1e-9 * a.table5.reduced.compound.mean_m);
  EXPECT_NEAR(b.table5.cross.compound.mean_m, a.table5.cross.compound.mean_m,
              1e-9 * a.table5.cross.compound.mean_m);
  EXPECT_NEAR(b.table5.full.compound.mean_m, a.table5.full.compound.mean_m,
              1e-9 * a.table5.full.compound.mean_m);
  EXPECT_EQ(a.reduced.fit.iterations, b.reduced.fit.iterations);
}

// diagnose.auto: the ladder adds the effect the truth has and the configured
// model lacks. The tables keep describing the configured model; the run's
// model, its final errors and its diagnosis are the last rung's.
TEST(Calibrate, LadderExtendsTheModelButTheTablesStayOfTheConfiguredOne) {
  SimulationOptions sim;
  sim.seed = 5;
  sim.truth = PaperTruth(1);
  // 10 arcsec of horizontal-circle eccentricity, 20 times the angle noise:
  // far above any test level.
  sim.truth.effects.Add(Effect::kHzEccentricity);
  sim.truth.EffectValue(Effect::kHzEccentricity) = {10.0 / 206265.0 * std::cos(0.7),
                                                    10.0 / 206265.0 * std::sin(0.7)};
  sim.plan = TrainingPlan();
  sim.noise.point_m = 5e-6;
  sim.noise.angle_rad = 0.5 / 206265.0;
  const SimulatedData data = Simulate(sim);
  CalibrationOptions options = ApiOptions(sim.truth);
  options.diagnose.enabled = true;
  options.diagnose.auto_add = true;
  const CalibrationResult r = Calibrate(data.obs, options);

  ASSERT_TRUE(r.diagnosis.has_value());
  ASSERT_TRUE(r.LadderExtendedModel()) << r.ladder_stop;
  EXPECT_EQ(r.ladder[1].added, "hz_eccentricity");
  EXPECT_TRUE(r.model.effects.Has(Effect::kHzEccentricity));
  EXPECT_FALSE(r.refined.model.effects.Has(Effect::kHzEccentricity));
  // Table 5 of the configured model, the final errors of the ladder's.
  const ModelErrors configured =
      EvaluateRecords(r.refined.model, data.obs.records, ErrorMethod::kB);
  EXPECT_EQ(r.table5.full.compound.mean_m, configured.compound.mean_m);
  const FinalErrors final_errors = ComputeFinalErrors(r.model, data.obs);
  EXPECT_EQ(r.final_errors.edm.mean_m, final_errors.edm.mean_m);
  // The missing effect dominated the configured model's error: the rung
  // that adds it must be better.
  EXPECT_LT(r.final_errors.edm.rms_m, ComputeFinalErrors(r.refined.model, data.obs).edm.rms_m);
  EXPECT_THAT(r.notes, Contains(HasSubstr("the stepwise search extended the model")));
}

TEST(Calibrate, InvalidOptionsAreRejectedBeforeAnyWork) {
  SimulationOptions sim;
  sim.truth = PaperTruth(1);
  const SimulatedData data = Simulate(sim);
  CalibrationOptions options = ApiOptions(sim.truth);
  options.diagnose.significance = 1.5;
  EXPECT_THAT(options.Check(), HasSubstr("diagnose.significance"));
  EXPECT_THROW(Calibrate(data.obs, options), std::invalid_argument);
  options = ApiOptions(sim.truth);
  options.fit.max_iterations = 0;
  EXPECT_THAT(options.Check(), HasSubstr("fit.max_iterations"));
}

// The screening runs inside Calibrate, so a program that calls it is
// protected: a zoom of 2147483647 is an InputError naming the row before any
// stage allocates a camera per level (SPEC 2), and no step starts.
TEST(Calibrate, DataMistakesAreRejectedBeforeAnyStep) {
  SimulationOptions sim;
  sim.truth = PaperTruth(1);
  SimulatedData data = Simulate(sim);
  for (size_t i = 0; i < data.obs.records.size(); ++i)
    data.obs.records[i].line = static_cast<int>(i) + 2;
  Record& cam = *std::find_if(data.obs.records.begin(), data.obs.records.end(),
                              [](const Record& r) { return r.tool == Tool::kCam; });
  cam.zoom = std::numeric_limits<int>::max();
  RecordingProgress progress;
  try {
    Calibrate(data.obs, ApiOptions(sim.truth), &progress);
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file, "simulated records");
    EXPECT_EQ(e.line, cam.line);
    EXPECT_EQ(e.column, "zoom");
  }
  EXPECT_THAT(progress.steps, ::testing::IsEmpty());
}

// The start's failures name the file and where its rows are: the
// extraction's (a zoom whose camera rows lie on one pixel line, so that no
// camera tool can be extracted, with intrinsics or without) and the pixels'
// (a zoom shown in one shot only).
TEST(Calibrate, StartFailuresNameTheFileAndTheLines) {
  SimulationOptions sim;
  sim.truth = PaperTruth(1);
  SimulatedData data = Simulate(sim);
  std::vector<Record> records;
  for (const Record& r : data.obs.records) {
    if (r.tool == Tool::kCam && r.v != sim.truth.cams[0].intrinsics[3]) continue;
    records.push_back(r);
  }
  for (size_t i = 0; i < records.size(); ++i) records[i].line = static_cast<int>(i) + 2;
  data.obs.records = records;
  data.obs.records_source = "records.csv";
  int first_cam = 0;
  for (const Record& r : records) {
    if (r.tool == Tool::kCam) {
      first_cam = r.line;
      break;
    }
  }
  try {
    Calibrate(data.obs, ApiOptions(sim.truth));
    FAIL() << "no ExtractionError";
  } catch (const ExtractionError& e) {
    EXPECT_THAT(e.what(), HasSubstr("records.csv: cannot extract the camera tool of zoom 0"));
    EXPECT_THAT(e.what(), HasSubstr("the first on line " + std::to_string(first_cam)));
  }

  SimulationOptions shots;
  shots.truth = PaperTruth(1);
  shots.plan.sweeps = false;
  shots.targets = ZoomScene(shots.truth, 4, 5, 3.0);
  SimulatedData pixels = Simulate(shots);
  const std::string one = pixels.obs.pixels.front().shot;
  std::vector<PixelObservation> kept;
  for (const PixelObservation& p : pixels.obs.pixels) {
    if (p.shot == one) kept.push_back(p);
  }
  for (PixelObservation& p : kept) {
    p.line = 7;  // one photo: one line of shots.csv
    p.X_known = false;
  }
  pixels.obs.pixels = kept;
  pixels.obs.pixels_source = "pixels.csv";
  pixels.obs.targets = shots.targets;
  for (TagBoard& b : pixels.obs.targets.boards) b.pose_known = false;
  // Camera-only, so that the pixels' own start (OpenCV per zoom) is what fails.
  CalibrationOptions camera_only;
  camera_only.model.kinematics = Kinematics::kNone;
  camera_only.model.effects.Add(Effect::kRadialDistortion);
  try {
    Calibrate(pixels.obs, camera_only);
    FAIL() << "no error for a zoom of one shot";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("pixels.csv: zoom 0 (pixels from line 7): 1 usable shot(s)"));
  }
}

// Warnings of the screening start the notes.
TEST(Calibrate, ScreeningWarningsAreNotes) {
  SimulationOptions sim;
  sim.truth = PaperTruth(1);
  SimulatedData data = Simulate(sim);
  data.obs.records.front().phi += 2 * M_PI;
  CalibrationOptions options = ApiOptions(sim.truth);
  const CalibrationResult result = Calibrate(data.obs, options);
  ASSERT_FALSE(result.notes.empty());
  EXPECT_THAT(result.notes.front(),
              ::testing::StartsWith("screening: simulated records: phi beyond 2 pi on 1 of "));
}

}  // namespace
}  // namespace rtscalib

#include "tests/fit/joint_scene.h"

namespace rtscalib {
namespace {

// SPEC 7 end to end: pixels of boards of unknown pose only (no records, no
// known position): Calibrate starts from the pixels alone (per-board views,
// one frame per board), refines the boards with the instrument in the ideal
// base frame and says what it held.
TEST(CalibrateUnknownBoards, PixelsOfBoardsWithoutPoseOnly) {
  InstrumentModel truth = testing_scene::DhTruth(1);
  const InstrumentModel ideal = IdealModel(Kinematics::kDh, 0, CameraTool());
  truth.base = ideal.base;  // the truth's frame is the ideal base frame
  truth.links[0].p[kDhD] = ideal.links[0].p[kDhD];
  truth.links[0].p[kDhGamma] = ideal.links[0].p[kDhGamma];
  SimulationOptions sim = testing_scene::PixelsOnly(truth, 3, 11, 0.2);
  SimulatedData data = Simulate(sim);
  data.obs.records.clear();
  data.obs.targets = sim.targets;
  for (TagBoard& b : data.obs.targets.boards) b.pose_known = false;
  for (PixelObservation& p : data.obs.pixels) {
    p.X_known = false;
    p.X.setZero();
  }
  CalibrationOptions options = ApiOptions(truth);
  const CalibrationResult r = Calibrate(data.obs, options);
  ASSERT_EQ(r.model.boards.size(), sim.targets.boards.size());
  // 0.2 px noise on ~2,000 corners: the intrinsics to a fraction of a pixel
  // (their sigmas are ~0.2-0.4 px, tests/fit/unknown_boards_test.cc); 2 px
  // is far outside noise and far inside a wrong frame or scale.
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(r.model.cams[0].intrinsics[i], truth.cams[0].intrinsics[i], 2.0) << i;
  }
  // Boards in the ideal base frame = the truth's frame, to a few mm at 3-4 m.
  for (const EstimatedBoard& b : r.model.boards) {
    for (const TagBoard& t : sim.targets.boards) {
      if (t.first_id != b.board.first_id) continue;
      EXPECT_LT((b.pose.ToRigid().translation - t.ref_from_board.translation).norm(), 5e-3);
    }
  }
  EXPECT_THAT(r.fit.fixed_gauges, Contains(HasSubstr("base pose held")));
}

// SPEC 7: image sizes come from the images or model.cameras and are never
// guessed silently. Records only, no cameras configured: the extraction's
// guess is used, marked "estimated" and noted; with the photos' sizes in
// Observations::image_sizes those are used; a configured camera of another
// size than the photos is an error.
TEST(Calibrate, ImageSizesComeFromTheImagesOrTheConfigOrAreMarkedEstimated) {
  SimulationOptions sim = PaperSession(7);
  const SimulatedData data = Simulate(sim);
  CalibrationOptions none = ApiOptions(sim.truth);
  none.model.cameras.clear();

  const CalibrationResult guessed = Calibrate(data.obs, none);
  EXPECT_EQ(guessed.size_source.at(0), "estimated");
  EXPECT_THAT(guessed.notes, Contains(HasSubstr("zoom 0: image size")));
  EXPECT_THAT(guessed.notes, Contains(HasSubstr("ESTIMATED")));

  Observations photos = data.obs;
  photos.image_sizes[0] = ImageSize{sim.truth.cams[0].width + 4, sim.truth.cams[0].height + 2};
  const CalibrationResult measured = Calibrate(photos, none);
  EXPECT_EQ(measured.size_source.at(0), "images");
  EXPECT_EQ(measured.model.cams[0].width, sim.truth.cams[0].width + 4);
  EXPECT_EQ(measured.model.cams[0].height, sim.truth.cams[0].height + 2);

  const CalibrationResult configured = Calibrate(data.obs, ApiOptions(sim.truth));
  EXPECT_EQ(configured.size_source.at(0), "config");
  EXPECT_EQ(configured.model.cams[0].width, sim.truth.cams[0].width);

  EXPECT_THROW(Calibrate(photos, ApiOptions(sim.truth)), InputError);
}

}  // namespace
}  // namespace rtscalib

namespace rtscalib {
namespace {

// model.radial_distortion: {coefficients: [k1, k2]} through Calibrate: k3 is
// held at the value model.cameras gives (else 0) in every stage, and the
// fit's list of held parameters names it.
TEST(CalibrateDistortionChoice, UnlistedCoefficientsAreHeldAtTheirGivenValue) {
  InstrumentModel truth = testing_scene::DhTruth(1);
  truth.cams[0].distortion[kK1] = -0.1;
  truth.cams[0].distortion[kK2] = 0.05;
  truth.effects.Add(Effect::kRadialDistortion);
  SimulatedData data = Simulate(testing_scene::PixelsOnly(truth, 3, 13, 0.2));
  data.obs.records.clear();
  CalibrationOptions options = ApiOptions(truth);
  options.model.effects.Add(Effect::kRadialDistortion);
  options.model.cameras[0].distortion = {};
  options.model.cameras[0].distortion[kK3] = 1e-3;  // a value the user gives
  DistortionChoice choice;
  choice.group = Effect::kRadialDistortion;
  choice.coefficients = {kK1, kK2};
  options.model.distortion_choices = {choice};
  const CalibrationResult r = Calibrate(data.obs, options);
  EXPECT_TRUE(r.model.cams[0].distortion_held[kK3]);
  EXPECT_EQ(r.model.cams[0].distortion[kK3], 1e-3);
  EXPECT_EQ(r.start.cams[0].distortion[kK3], 1e-3);
  EXPECT_NE(r.model.cams[0].distortion[kK1], 0.0);
  EXPECT_THAT(r.fit.fixed_gauges, Contains(HasSubstr("k3 = 0.001")));

  // A zoom the model has no camera for is an error naming the key.
  choice.zooms[4] = {kK1};
  options.model.distortion_choices = {choice};
  try {
    Calibrate(data.obs, options);
    ADD_FAILURE() << "zoom 4 of a one-zoom model";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("model.radial_distortion.zooms"));
  }
}

}  // namespace
}  // namespace rtscalib

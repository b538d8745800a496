#include "libcalib/calibrate/calibrate.h"

#include <algorithm>
#include <cmath>
#include <future>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <utility>

#include "libcalib/calibrate/intrinsics.h"
#include "libcalib/calibrate/validate.h"
#include "libcalib/extract/intrinsics_from_rays.h"
#include "libcalib/extract/simplify.h"
#include "libcalib/fit/init_from_pixels.h"
#include "libcalib/fit/robust.h"
#include "libcalib/fit/start_models.h"
#include "libcalib/fit/two_face.h"
#include "libcalib/fit/unknowns.h"
#include "libcalib/geometry/convex_hull.h"
#include "libcalib/text/errors.h"
#include "libcalib/model/kinematics.h"
#include "libcalib/screen/gross.h"
#include "libcalib/screen/screen.h"

namespace rtscalib {
namespace {

// `obs` with `records` for its records and, with face 1 or 2, only that face's
// rows; everything else (the boards, the image sizes, the sources) as in `obs`.
Observations Subset(const Observations& obs, const std::vector<Record>& records, int face = 0) {
  Observations out = obs;
  out.records.clear();
  out.pixels.clear();
  for (const Record& r : records) {
    if (face == 0 || r.face == face) out.records.push_back(r);
  }
  for (const PixelObservation& p : obs.pixels) {
    if (face == 0 || p.face == face) out.pixels.push_back(p);
  }
  return out;
}

// The classical two-face check (libcalib/fit/two_face.h) along the EDM ray,
// or along the first zoom's optical axis when there are no EDM records.
void ReadTwoFaceDifferences(const Observations& obs, FaceComparison* f) {
  const bool edm = std::any_of(obs.records.begin(), obs.records.end(),
                               [](const Record& r) { return r.tool == Tool::kEdm; });
  const std::set<int> zooms = ZoomsInData(obs);
  const int zoom = edm || zooms.empty() ? -1 : *zooms.begin();
  const TwoFaceDifferences d = TwoFaceCheck(f->face1, f->face2, zoom);
  f->collimation = d.collimation;
  f->tilting_axis = d.tilting_axis;
  f->vertical_index = d.vertical_index;
  f->valid = true;
  if (!edm)
    f->note = "read along zoom " + std::to_string(zoom) + "'s optical axis (no EDM records)";
}

// SPEC 7: image sizes come from the images or model.cameras. Photos of a
// zoom whose configured camera has another size are a contradiction.
void CheckImageSizes(const Observations& obs, const CalibrationOptions& options) {
  for (const auto& [z, size] : obs.image_sizes) {
    if (z >= static_cast<int>(options.model.cameras.size())) continue;
    const CameraTool& c = options.model.cameras[z];
    if (c.width != size.width || c.height != size.height) {
      throw InputError::File(
          obs.pixels_source, 0, "image size of zoom " + std::to_string(z),
          "the size of model.cameras[" + std::to_string(z) + "] (" + std::to_string(c.width) +
              " x " + std::to_string(c.height) + ")",
          std::to_string(size.width) + " x " + std::to_string(size.height) + " px in the photos");
    }
  }
}

// What the configured kinematics need from the data, checked before anything
// is fitted, so that a session that cannot determine what the config asks
// for gets an error naming the key or the row, never a model.
//   none (camera-only, SPEC 7.1): no records, no kinematic effect, no known
//     position (each board pose is estimated in its zoom's camera frame),
//     and a camera that did not turn within a placement (readings of one
//     placement and zoom agree to kSameReadingRad);
//   dh, spherical: every row has a reading, and pixels alone determine a
//     chain only when some placement of a board is seen from two readings
//     or some position is known (a board seen from one reading per
//     placement gives each photo its own board pose: nothing ties the
//     camera poses to phi and theta).
void CheckDataFitTheKinematics(const Observations& obs, const CalibrationOptions& options) {
  const Kinematics k = options.model.kinematics;
  const std::string name = KinematicsName(k);
  if (k == Kinematics::kNone) {
    if (!obs.records.empty()) {
      throw std::invalid_argument(
          "model.kinematics: none is a camera-only calibration (SPEC 7.1) and takes no records, "
          "but " + obs.records_source + " has " + std::to_string(obs.records.size()) +
          " rows: leave data.records out, or choose model.kinematics: dh or spherical");
    }
    for (Effect e : options.model.effects.List()) {
      if (IsKinematic(e)) {
        throw std::invalid_argument(std::string("model.effects: ") + Info(e).name +
                                    " is an effect of the instrument's axes or EDM; "
                                    "model.kinematics: none (camera-only) has neither: keep the "
                                    "distortion effects only");
      }
    }
    // Readings of one placement and zoom: 1e-5 rad (2") is far beyond an
    // instrument's reading noise and far below any deliberate turn.
    constexpr double kSameReadingRad = 1e-5;
    std::map<std::pair<std::string, int>, const PixelObservation*> first;
    for (const PixelObservation& p : obs.pixels) {
      if (p.X_known) {
        throw InputError::Cell(
            obs.pixels_source, p.line, "X",
            "a corner of a board without a pose (model.kinematics: none estimates every board's "
            "pose in the camera frame; a surveyed position has no meaning there)",
            "a known position");
      }
      if (!p.has_reading) continue;
      const auto [it, inserted] = first.emplace(std::make_pair(p.placement, p.zoom), &p);
      const PixelObservation& q = *it->second;
      if (!inserted && (std::abs(p.phi - q.phi) > kSameReadingRad ||
                        std::abs(p.theta - q.theta) > kSameReadingRad)) {
        throw InputError::Cell(
            obs.pixels_source, p.line, "phi",
            "the reading of line " + std::to_string(q.line) + " (same placement '" + p.placement +
                "' and zoom " + std::to_string(p.zoom) +
                "): with model.kinematics: none the camera must not turn within a placement; "
                "give each photo its own placement, or use model.kinematics: dh or spherical",
            "a reading that differs by " +
                std::to_string(std::max(std::abs(p.phi - q.phi), std::abs(p.theta - q.theta))) +
                " rad");
      }
    }
    return;
  }
  for (const PixelObservation& p : obs.pixels) {
    if (!p.has_reading) {
      throw InputError::Cell(obs.pixels_source, p.line, "phi",
                             "the instrument's readings phi and theta (model.kinematics: " + name +
                                 " needs them; leave them empty only with model.kinematics: "
                                 "none, a camera-only calibration)",
                             "");
    }
  }
  if (!obs.records.empty() || obs.pixels.empty()) return;
  bool known = false;
  std::map<std::pair<int, std::string>, std::set<std::pair<double, double>>> readings;
  for (const PixelObservation& p : obs.pixels) {
    bool surveyed = p.X_known;
    int board = -1;
    for (const TagBoard& b : obs.targets.boards) {
      if (!b.HasId(p.target)) continue;
      surveyed = surveyed || b.pose_known;
      board = b.first_id;
    }
    known = known || surveyed;
    if (!surveyed) readings[{board, p.placement}].insert({p.phi, p.theta});
  }
  if (known) return;
  for (const auto& [key, seen] : readings) {
    if (seen.size() >= 2) return;
  }
  throw std::invalid_argument(
      "model.kinematics: " + name + " cannot be determined from " + obs.pixels_source +
      ": every placement of every board (" + std::to_string(readings.size()) +
      ") is seen from one reading only, so each photo has its own board pose and nothing ties "
      "the camera to phi and theta; photograph one placement from several readings (turn the "
      "instrument), add records or a surveyed board, or choose model.kinematics: none for a "
      "camera-only calibration");
}

// Sets every zoom's width and height in `model` from the photos or the
// configured cameras; records where each came from in result->size_source.
void ApplyImageSizes(const Observations& obs, const CalibrationOptions& options,
                     InstrumentModel* model, CalibrationResult* result) {
  for (int z = 0; z < model->NumZooms(); ++z) {
    CameraTool& cam = model->cams[z];
    if (const auto it = obs.image_sizes.find(z); it != obs.image_sizes.end()) {
      cam.width = it->second.width;
      cam.height = it->second.height;
      if (result != nullptr) result->size_source[z] = "images";
    } else if (z < static_cast<int>(options.model.cameras.size())) {
      cam.width = options.model.cameras[z].width;
      cam.height = options.model.cameras[z].height;
      if (result != nullptr) result->size_source[z] = "config";
    } else if (result != nullptr && !result->size_source.count(z)) {
      result->size_source[z] = "estimated";
      result->notes.push_back(
          "zoom " + std::to_string(z) + ": image size " + std::to_string(cam.width) + " x " +
          std::to_string(cam.height) +
          " px ESTIMATED from the principal point and the pixels (no photos, no "
          "model.cameras entry); give model.cameras[" +
          std::to_string(z) + "] width/height or data.shots for the true size");
    }
  }
}

// Options of the start from pixels alone (and of a zoom's camera from
// pixels): image sizes from the photos (SPEC 7) where known, else from
// model.cameras; boards of unknown pose from the observations' targets.
InitFromPixelsOptions PixelStartOptions(const CalibrationOptions& options,
                                        const Observations& obs) {
  InitFromPixelsOptions io;
  io.kinematics = options.model.kinematics;
  io.distortion = DistortionGroupsOf(options.model.effects);
  io.cameras = options.model.cameras;
  for (const auto& [zoom, size] : obs.image_sizes) {
    if (zoom < 0 || size.width <= 0 || size.height <= 0) continue;
    if (zoom >= static_cast<int>(io.cameras.size())) io.cameras.resize(zoom + 1);
    io.cameras[zoom].width = size.width;
    io.cameras[zoom].height = size.height;
  }
  io.targets = obs.targets;
  io.source = obs.pixels_source;
  io.critical_region = options.fit.critical_region;
  io.threads = options.fit.num_threads;
  return io;
}

// Stage 1-2: extraction (Klug Sec. 3), with the retry on intrinsics from the
// view rays, and simplification (Sec. 4.1).
void ExtractAndSimplify(const Observations& obs, const CalibrationOptions& options,
                        CalibrationProgress* progress, CalibrationResult* result) {
  progress->Step("extracting the DH model (Klug Sec. 3)");
  ExtractOptions eo;
  eo.critical_region = options.fit.critical_region;
  // The extraction's messages name lines; the file is the records'.
  auto extract = [&](const std::vector<CameraTool>& cameras) {
    try {
      return ExtractDhModel(obs.records, cameras, eo);
    } catch (const ExtractionError& e) {
      throw ExtractionError(obs.records_source + ": " + e.what());
    }
  };
  try {
    result->extraction = extract(options.model.cameras);
  } catch (const ExtractionError& first) {
    // Without Klug's pixel triplets (Eq. 67) and configured intrinsics the
    // camera tools cannot be extracted as the paper does; intrinsics from
    // the view rays (DLT) let the extraction use every camera row instead.
    std::vector<CameraTool> cameras = options.model.cameras;
    const std::set<int> zooms = ZoomsInData(obs);
    bool estimated = false;
    for (int z : zooms) {
      if (z < static_cast<int>(cameras.size())) continue;
      const auto est = EstimateIntrinsicsFromRays(obs.records, z);
      if (!est) throw;
      cameras.resize(z + 1, est->camera);
      cameras[z] = est->camera;
      result->notes.push_back("extraction: " + est->note);
      progress->Note(est->note);
      estimated = true;
    }
    if (!estimated) throw;
    result->notes.push_back(std::string("extraction: first attempt failed (") + first.what() +
                            "); retried with intrinsics from the view rays");
    result->extraction = extract(cameras);
  }
  for (const std::string& n : result->extraction->notes)
    result->notes.push_back("extraction: " + n);
  progress->Step("simplifying (Klug Sec. 4.1)");
  const SimplifiedModel simple = Simplify(result->extraction->model);
  result->simplified = simple.model;
  result->closed_form = "M_B,T(phi, theta) rotation (Eq. 90 form):\n" + simple.rotation.ToString();
  if (simple.euler) result->closed_form += "\n= " + simple.euler->ToString() + "   (Eq. 91 form)";
  for (const std::string& n : simple.notes) result->notes.push_back("simplification: " + n);
}

// Stage 3: the starting model: the extraction, or the pixels alone (OpenCV
// per zoom, then the chain; libcalib/fit/init_from_pixels.h), in the
// configured kinematics with the configured effects enabled.
InstrumentModel StartModel(const Observations& obs, const CalibrationOptions& options,
                           CalibrationProgress* progress, CalibrationResult* result) {
  InstrumentModel start;
  if (result->extraction) {
    start = result->extraction->model;
    // Zooms with pixels but no camera rows: their camera from the pixels.
    std::set<int> pixel_zooms;
    for (const PixelObservation& p : obs.pixels) pixel_zooms.insert(p.zoom);
    for (int z : pixel_zooms) {
      const auto& poses = result->extraction->camera_poses;
      if (z < start.NumZooms() && z < static_cast<int>(poses.size()) && poses[z] > 0) continue;
      progress->Step("zoom " + std::to_string(z) + ": camera from its pixels");
      for (const std::string& n :
           InitCameraFromPixels(obs.pixels, z, PixelStartOptions(options, obs), &start)) {
        result->notes.push_back("pixel start: " + n);
      }
    }
    if (options.model.kinematics == Kinematics::kSpherical) start = SphericalFromDh(start);
  } else {
    progress->Step("starting from the pixels alone (OpenCV per zoom, then the chain)");
    const InitFromPixelsResult init = InitFromPixels(obs.pixels, PixelStartOptions(options, obs));
    for (const std::string& n : init.notes) result->notes.push_back("pixel start: " + n);
    start = init.model;
  }
  for (int z : ZoomsInData(obs)) {
    if (z >= start.NumZooms()) {
      throw std::invalid_argument("zoom " + std::to_string(z) +
                                  " is in the data but the extraction found no camera rows for "
                                  "it; add model.cameras or camera sweep rows for that zoom");
    }
  }
  start.edm_cyclic_unit_length = options.model.edm_cyclic_unit_length;
  EnableEffects(options.model.effects, &start);
  // model.<group>.coefficients: the unlisted ones held at their given value or 0.
  HoldDistortion(options.model.distortion_choices, options.model.cameras, &start);
  for (Effect e : options.model.effects.List()) {
    if (start.kinematics == Kinematics::kDh && Info(e).redundant_in_dh) {
      result->notes.push_back(std::string(Info(e).name) +
                              " is part of the dh model (links and tools) and is not fitted twice");
    }
  }
  return start;
}

// Stage 4's first half: the reduced set's refinement from the start. The
// sweeps alone never span the image: intrinsics stay as they are there.
struct ReducedFit {
  FitOptions options;
  InstrumentModel model;
  FitSummary fit;
};

ReducedFit RefineReduced(const Observations& reduced_obs, const InstrumentModel& start,
                         const FitOptions& fo) {
  ReducedFit r;
  r.options = fo;
  r.options.fit_intrinsics = FitIntrinsicsOnReducedSet(fo.fit_intrinsics, reduced_obs, start);
  r.model = start;
  r.fit = Refine(reduced_obs, r.options, &r.model);
  return r;
}

// Stage 4: refinement (Sec. 4.3) on the reduced set, then on the full set
// starting from it; Table 5 of both. `ahead`: the reduced set's refinement
// already made from this start (beside the gross-error search).
void RefineConfigured(const Observations& obs, const std::vector<Record>& reduced,
                      const FitChecks& checks, CalibrationProgress* progress,
                      CalibrationResult* result, std::optional<ReducedFit> ahead) {
  const FitOptions& fo = result->fit_options;
  const Observations reduced_obs = Subset(obs, reduced);
  const bool has_more = reduced.size() < obs.records.size();
  if (has_more) {
    progress->Step("refining on the reduced set (" + std::to_string(reduced.size()) + " records)");
    if (ahead) {
      progress->Note("refined beside the gross-error search");
    } else {
      ahead = RefineReduced(reduced_obs, result->start, fo);
    }
    result->reduced.model = std::move(ahead->model);
    result->reduced.fit = std::move(ahead->fit);
    ValidateFit("refinement on the reduced set", WithEstimates(reduced_obs, result->reduced.model),
                result->reduced.model, result->reduced.fit, ahead->options, checks);
    MarkUndeterminedTools(reduced_obs, ahead->options, &result->reduced.model);
  }
  progress->Step("refining on the full set (" + std::to_string(obs.records.size()) + " records, " +
                 std::to_string(obs.pixels.size()) + " pixels)");
  Refinement& full = result->refined;
  full.model = has_more ? result->reduced.model : result->start;
  full.model.sigmas = {};
  full.fit = Refine(obs, fo, &full.model, has_more ? &result->reduced.fit : nullptr);
  progress->Note("converged: " + std::string(full.fit.converged ? "yes" : "no") + ", " +
                 std::to_string(full.fit.iterations) + " iterations");
  ValidateFit("refinement on the full set", WithEstimates(obs, full.model), full.model, full.fit,
              fo, checks);
  for (const std::string& n : MarkUndeterminedTools(obs, fo, &full.model)) {
    result->notes.push_back(n);
    progress->Note(n);
  }
  if (!has_more) result->reduced = full;

  Table5& t5 = result->table5;
  t5.reduced = EvaluateRecords(result->reduced.model, reduced, ErrorMethod::kB);
  t5.full = EvaluateRecords(full.model, obs.records, ErrorMethod::kB);
  t5.has_cross = has_more;
  if (has_more) t5.cross = EvaluateRecords(result->reduced.model, obs.records, ErrorMethod::kB);
  t5.reduced_rows = static_cast<int>(reduced.size());
  t5.full_rows = static_cast<int>(obs.records.size());
}

// Stage 5: `faces: separate`: one model per face, started from the joint
// refined model, and the two-face check.
FaceComparison FitFacesSeparately(const Observations& obs, const CalibrationResult& result,
                                  const FitChecks& checks) {
  FaceComparison fc;
  fc.face1 = result.refined.model;
  fc.face2 = result.refined.model;
  const Observations o1 = Subset(obs, obs.records, 1), o2 = Subset(obs, obs.records, 2);
  if ((o1.records.empty() && o1.pixels.empty()) || (o2.records.empty() && o2.pixels.empty())) {
    fc.note = "faces: separate needs observations in both faces";
  } else {
    fc.fit1 = Refine(o1, result.fit_options, &fc.face1);
    ValidateFit("face 1 refinement (faces: separate)", WithEstimates(o1, fc.face1), fc.face1,
                fc.fit1, result.fit_options, checks);
    MarkUndeterminedTools(o1, result.fit_options, &fc.face1);
    fc.fit2 = Refine(o2, result.fit_options, &fc.face2);
    ValidateFit("face 2 refinement (faces: separate)", WithEstimates(o2, fc.face2), fc.face2,
                fc.fit2, result.fit_options, checks);
    MarkUndeterminedTools(o2, result.fit_options, &fc.face2);
    ReadTwoFaceDifferences(obs, &fc);
  }
  return fc;
}

DiagnosisSettings SettingsOf(const CalibrationOptions& options) {
  DiagnosisSettings s;
  s.significance = options.diagnose.significance;
  return s;
}

// The calibration stands without its diagnosis: a failure of it (the
// stepwise refits included) becomes this note, not a failed calibration.
std::string DiagnosisFailed(const std::exception& e, CalibrationProgress* progress) {
  const std::string note = std::string("diagnosis failed: ") + e.what();
  progress->Note(note);
  return note;
}

// Stage 6 with diagnose.auto: the forward stepwise ladder, whose last rung
// becomes the run's model, and the diagnosis of that model. Throws what the
// diagnosis throws.
void StepwiseDiagnosis(const Observations& obs, const CalibrationOptions& options,
                       CalibrationProgress* progress, CalibrationResult* r) {
  const DiagnosisSettings s = SettingsOf(options);
  progress->Step("forward stepwise: adding significant effects one at a time");
  StepwiseResult sw = ForwardStepwise(obs, r->refined.model, r->refined.fit, r->fit_options, s);
  for (size_t i = 1; i < sw.ladder.size(); ++i) {
    progress->Note("added " + sw.ladder[i].added + ": " + sw.ladder[i].model_description);
  }
  progress->Note("stopped: " + sw.stop_reason);
  r->ladder = sw.ladder;
  r->ladder_stop = sw.stop_reason;
  if (r->LadderExtendedModel()) {
    r->notes.push_back(
        "diagnose.auto: the stepwise search extended the model to " +
        sw.ladder.back().model_description +
        "; model.yaml, Tables 6-7, the final errors and the diagnosis are of that model, "
        "Tables 4-5 of the configured one");
  }
  // The ladder's last rung is a fit of its own and becomes the run's model.
  if (r->LadderExtendedModel()) {
    ValidateFit("refinement of the stepwise model " + sw.ladder.back().model_description,
                WithEstimates(obs, sw.model), sw.model, sw.fit, r->fit_options, options.checks);
    MarkUndeterminedTools(obs, r->fit_options, &sw.model);
  }
  r->model = sw.model;
  r->fit = sw.fit;
  r->diagnosis = std::move(sw.diagnosis);
  for (const std::string& v : r->diagnosis->verdict) progress->Note(v);
}

// Stages 1-3 on `obs`: extraction and simplification (records of known
// points), the start, Table 4 and the intrinsics decision. Returns the
// reduced set.
std::vector<Record> Prepare(const Observations& obs, const CalibrationOptions& options,
                            CalibrationProgress* progress, CalibrationResult* result) {
  // The extraction needs records of known points; records of points of
  // unknown position (SPEC 7) are fitted, not extracted from.
  Observations known = obs;
  known.records.clear();
  for (const Record& r : obs.records) {
    if (r.point.empty()) known.records.push_back(r);
  }
  if (!known.records.empty()) {
    ExtractAndSimplify(known, options, progress, result);
    ApplyImageSizes(obs, options, &result->extraction->model, nullptr);
    ApplyImageSizes(obs, options, &*result->simplified, nullptr);
  }
  result->start = StartModel(obs, options, progress, result);
  ApplyImageSizes(obs, options, &result->start, result);

  // Table 4: the extracted and simplified models on the reduced set.
  std::vector<Record> reduced = ReducedRecords(obs.records, result->extraction);
  if (result->extraction) {
    Table4 t;
    t.dh_a = EvaluateRecords(result->extraction->model, reduced, ErrorMethod::kA);
    t.dh_b = EvaluateRecords(result->extraction->model, reduced, ErrorMethod::kB);
    t.simplified_a = EvaluateRecords(*result->simplified, reduced, ErrorMethod::kA);
    t.simplified_b = EvaluateRecords(*result->simplified, reduced, ErrorMethod::kB);
    result->table4 = t;
  }
  result->fit_options = options.fit;
  result->fit_options.fit_intrinsics = FitIntrinsics(options.model.intrinsics, obs, result->start);
  result->intrinsics_fitted = result->fit_options.fit_intrinsics;
  return reduced;
}

}  // namespace

std::string CalibrationOptions::Check() const {
  const std::string fit_problem = fit.Check();
  if (!fit_problem.empty()) return fit_problem;
  if (!(model.edm_cyclic_unit_length > 0)) return "model.edm_cyclic.unit_length must be > 0";
  for (size_t z = 0; z < model.cameras.size(); ++z) {
    const CameraTool& c = model.cameras[z];
    if (c.width <= 0 || c.height <= 0 || !(c.intrinsics[0] > 0) || !(c.intrinsics[1] > 0)) {
      return "model.cameras[" + std::to_string(z) +
             "] must have an image size > 0 and focal lengths > 0";
    }
  }
  if (!(diagnose.significance > 0 && diagnose.significance < 1))
    return "diagnose.significance must be in (0, 1)";
  return checks.Check();
}

std::vector<Record> ReducedRecords(const std::vector<Record>& records,
                                   const std::optional<ExtractionResult>& extraction) {
  const bool labelled =
      std::any_of(records.begin(), records.end(), [](const Record& r) { return !r.set.empty(); });
  std::vector<Record> out;
  if (labelled) {
    for (const Record& r : records) {
      if (r.set.rfind("sweep", 0) == 0) out.push_back(r);
    }
    return out;
  }
  if (!extraction) return records;
  // Unlabelled: the poses of the two sweeps the extraction used.
  std::set<std::pair<double, double>> poses;
  for (const Sweep& s : extraction->sweeps) {
    for (int i : s.rows) poses.insert({records[i].phi, records[i].theta});
  }
  for (const Record& r : records) {
    double phi1 = r.phi, theta1 = r.theta;
    if (r.face == 2) OtherFace(r.phi, r.theta, &phi1, &theta1);
    if (poses.count({r.phi, r.theta}) || poses.count({phi1, theta1})) out.push_back(r);
  }
  return out;
}

FinalErrors ComputeFinalErrors(const InstrumentModel& model, const Observations& obs) {
  FinalErrors f;
  std::vector<double> edm, cam;
  for (const RecordResidual& r : RecordResiduals(model, obs.records)) {
    if (!r.valid) continue;
    (obs.records[r.index].tool == Tool::kEdm ? edm : cam).push_back(r.distance);
  }
  f.edm = StatsOf(edm);
  f.cam = StatsOf(cam);
  f.pixels = EvaluatePixels(model, obs.pixels);
  return f;
}

CalibrationResult CalibrateModel(const Observations& obs, const CalibrationOptions& options,
                                 CalibrationProgress* progress) {
  SilentProgress silent;
  if (progress == nullptr) progress = &silent;
  const std::string problem = options.Check();
  if (!problem.empty()) throw std::invalid_argument("calibration options: " + problem);

  CheckImageSizes(obs, options);
  CheckDataFitTheKinematics(obs, options);
  CalibrationResult result;
  const std::vector<std::string> screening =
      ScreenObservations(obs, options.model.cameras, options.screen);
  result.notes = screening;
  // Gross errors (fit/robust.h, screen/gross.h): rows no instrument could produce are
  // taken out before the extraction; what is left is found by a robust fit
  // from the start, and the calibration starts again without those rows.
  result.gross_rows = FindGrossRows(obs, options.screen.gross_errors);
  std::vector<int> record_from, pixel_from;  // `used` row -> `obs` row
  Observations used = WithoutRows(obs, result.gross_rows, &record_from, &pixel_from);
  std::vector<Record> reduced = Prepare(used, options, progress, &result);
  // The reduced set's refinement starts where the robust search starts and
  // needs none of its results unless it takes rows out (then the
  // calibration starts again without them): with fit.threads > 1 it runs
  // beside the search, on copies, since both leave a core partly idle
  // (Ceres's linear algebra is serial).
  std::future<ReducedFit> reduced_ahead;
  if (options.fit.gross_errors.enabled && result.fit_options.num_threads > 1 &&
      reduced.size() < used.records.size()) {
    reduced_ahead = std::async(
        std::launch::async,
        [reduced_obs = Subset(used, reduced), start = result.start, fo = result.fit_options] {
          return RefineReduced(reduced_obs, start, fo);
        });
  }
  bool restarted = false;
  if (options.fit.gross_errors.enabled) {
    progress->Step("looking for gross errors (robust fit from the start)");
    InstrumentModel robust = result.start;
    RobustFitResult found;
    try {
      // Rows the screening took out make more likely: straight to the robust fit.
      found = FindGrossErrorsByFit(used, result.fit_options, options.fit.gross_errors, &robust,
                                   !result.gross_rows.empty());
    } catch (const std::exception& e) {
      // The least-squares stages below meet the same cause and report it
      // with the rows (validate.h).
      found.notes.push_back(std::string("gross errors: the robust fit failed (") + e.what() +
                            "); no rows taken out by it");
    }
    if (!found.gross.empty()) {
      for (ExcludedRow& e : found.gross) {
        e.index = e.pixel ? pixel_from[e.index] : record_from[e.index];
        result.gross_rows.push_back(e);
      }
      used = WithoutRows(obs, result.gross_rows, &record_from, &pixel_from);
      // The tables and the start of the clean rows.
      CalibrationResult again;
      again.notes = screening;
      again.gross_rows = std::move(result.gross_rows);
      result = std::move(again);
      restarted = true;
      reduced = Prepare(used, options, progress, &result);
    }
    for (std::string& n : found.notes) result.notes.push_back(std::move(n));
  }
  if (!result.gross_rows.empty()) {
    std::sort(result.gross_rows.begin(), result.gross_rows.end());
    const std::string n = "gross errors: " + std::to_string(result.gross_rows.size()) +
                          " rows taken out (listed in the report with their lines and reasons)";
    result.notes.push_back(n);
    progress->Note(n);
  }
  // Against every row: a start made non-finite by one row outside the
  // reduced set (the extraction uses them all) names that row.
  // Pixels of boards of unknown pose are checked at the start's board poses.
  ValidateStart("start of the refinement", WithEstimates(used, result.start), result.start,
                result.fit_options, options.checks);
  std::optional<ReducedFit> ahead;
  if (reduced_ahead.valid()) {
    try {
      ReducedFit r = reduced_ahead.get();
      if (!restarted) ahead = std::move(r);
    } catch (const std::exception&) {
      // Refined again below, in order, where its failure is reported.
    }
  }
  RefineConfigured(used, reduced, options.checks, progress, &result, std::move(ahead));

  if (options.model.faces == FaceMode::kSeparate &&
      options.model.kinematics == Kinematics::kNone) {
    result.notes.push_back(
        "faces: separate ignored: a camera-only calibration (kinematics none) has no two-face "
        "check");
  } else if (options.model.faces == FaceMode::kSeparate) {
    progress->Step("fitting one model per face");
    result.faces = FitFacesSeparately(used, result, options.checks);
  }

  result.model = result.refined.model;
  result.fit = result.refined.fit;
  // Where each zoom's image points (pixels, and cam rows' u, v) fell:
  // outside this hull the distortion is extrapolated (model.yaml
  // valid_region, the uncertainty maps).
  for (int z = 0; z < result.model.NumZooms(); ++z) {
    std::vector<Eigen::Vector2d> uv;
    for (const PixelObservation& p : obs.pixels) {
      if (p.zoom == z) uv.push_back(p.uv);
    }
    for (const Record& r : obs.records) {
      if (r.tool == Tool::kCam && r.zoom == z) uv.emplace_back(r.u, r.v);
    }
    result.model.cams[z].valid_region = ConvexHull(std::move(uv));
  }
  // With diagnose.auto the ladder makes the run's model, so it runs here;
  // a plain diagnosis only reads the result (DiagnoseCalibration).
  if (options.diagnose.enabled && !DiagnosisPending(options)) {
    try {
      // The ladder refits the estimated boards and points (SPEC 7) with every rung.
      StepwiseDiagnosis(used, options, progress, &result);
    } catch (const std::exception& e) {
      result.diagnosis.reset();
      result.notes.push_back(DiagnosisFailed(e, progress));
    }
  }
  result.final_errors = ComputeFinalErrors(result.model, WithEstimates(used, result.model));
  result.residuals =
      ResidualTable(obs, result.model, result.fit_options, result.fit, result.gross_rows);
  result.coverage = MeasureCoverage(used, result.model, result.fit_options);
  result.coverage_warnings = CoverageWarnings(result.coverage, result.model);
  progress->Done();
  return result;
}

bool DiagnosisPending(const CalibrationOptions& options) {
  return options.diagnose.enabled && !options.diagnose.auto_add;
}

CalibrationDiagnosis DiagnoseCalibration(const Observations& obs,
                                         const CalibrationOptions& options,
                                         const CalibrationResult& result,
                                         CalibrationProgress* progress) {
  SilentProgress silent;
  if (progress == nullptr) progress = &silent;
  CalibrationDiagnosis out;
  if (!DiagnosisPending(options)) return out;
  // The rows the fit used; the estimated boards and points (SPEC 7) are
  // free in the diagnosis as in the fit.
  const Observations used = WithoutRows(obs, result.gross_rows);
  progress->Step("diagnosing the model (ranking the missing effects)");
  try {
    out.diagnosis = Diagnose(used, result.model,
                             ContextOf(result.fit_options, result.fit), SettingsOf(options));
    for (const std::string& v : out.diagnosis->verdict) progress->Note(v);
  } catch (const std::exception& e) {
    out.notes.push_back(DiagnosisFailed(e, progress));
  }
  progress->Done();
  return out;
}

void AddDiagnosis(CalibrationDiagnosis diagnosis, CalibrationResult* result) {
  if (diagnosis.diagnosis) result->diagnosis = std::move(diagnosis.diagnosis);
  for (std::string& n : diagnosis.notes) result->notes.push_back(std::move(n));
}

CalibrationResult Calibrate(const Observations& obs, const CalibrationOptions& options,
                            CalibrationProgress* progress) {
  CalibrationResult result = CalibrateModel(obs, options, progress);
  AddDiagnosis(DiagnoseCalibration(obs, options, result, progress), &result);
  return result;
}

}  // namespace rtscalib

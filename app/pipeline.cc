#include "app/pipeline.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>

#include "libcalib/extract/intrinsics_from_rays.h"
#include "libcalib/extract/simplify.h"
#include "libcalib/fit/init_from_pixels.h"
#include "libcalib/fit/start_models.h"
#include "libcalib/fit/two_face.h"
#include "libcalib/io/records.h"
#include "libcalib/model/kinematics.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib::app {
namespace {

// Camera rows (or pixels) of a zoom span the image when their pixels cover at
// least a quarter of its width and height: then the intrinsics are observable.
bool CamDataSpanImage(const Observations& obs, const InstrumentModel& model, int zoom) {
  if (zoom >= model.NumZooms()) return false;
  double umin = 1e300, umax = -1e300, vmin = 1e300, vmax = -1e300;
  auto add = [&](double u, double v) {
    umin = std::min(umin, u);
    umax = std::max(umax, u);
    vmin = std::min(vmin, v);
    vmax = std::max(vmax, v);
  };
  for (const Record& r : obs.records) {
    if (r.tool == Tool::kCam && r.zoom == zoom) add(r.u, r.v);
  }
  for (const PixelObservation& p : obs.pixels) {
    if (p.zoom == zoom) add(p.uv.x(), p.uv.y());
  }
  const CameraTool& c = model.cams[zoom];
  return umax - umin > 0.25 * c.width && vmax - vmin > 0.25 * c.height;
}

std::set<int> ZoomsInData(const Observations& obs) {
  std::set<int> z;
  for (const Record& r : obs.records) {
    if (r.tool == Tool::kCam) z.insert(r.zoom);
  }
  for (const PixelObservation& p : obs.pixels) z.insert(p.zoom);
  return z;
}

Observations Subset(const Observations& obs, const std::vector<Record>& records, int face = 0) {
  Observations out;
  out.records_source = obs.records_source;
  out.pixels_source = obs.pixels_source;
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
void TwoFaceCheck(const Observations& obs, FaceComparison* f) {
  const bool edm = std::any_of(obs.records.begin(), obs.records.end(),
                               [](const Record& r) { return r.tool == Tool::kEdm; });
  const std::set<int> zooms = ZoomsInData(obs);
  const int zoom = edm || zooms.empty() ? -1 : *zooms.begin();
  const TwoFaceDifferences d = rtscalib::TwoFaceCheck(f->face1, f->face2, zoom);
  f->collimation = d.collimation;
  f->tilting_axis = d.tilting_axis;
  f->vertical_index = d.vertical_index;
  f->valid = true;
  if (!edm)
    f->note = "read along zoom " + std::to_string(zoom) + "'s optical axis (no EDM records)";
}

// Options of the start from pixels alone (and of a zoom's camera from pixels).
InitFromPixelsOptions PixelStartOptions(const RunConfig& config) {
  InitFromPixelsOptions io;
  io.kinematics = config.model.kinematics;
  io.distortion = DistortionGroupsOf(config.model.effects);
  io.cameras = config.model.cameras;
  io.min_zenith_rad = config.fit.min_zenith_rad;
  io.max_zenith_rad = config.fit.max_zenith_rad;
  return io;
}

}  // namespace

Observations LoadObservations(const RunConfig& config, const std::string& work_dir,
                              PipelineResult* result, Progress* progress) {
  Observations obs;
  if (!config.records_path.empty() || !config.pixels_path.empty()) {
    progress->Step("reading observations");
    if (!config.records_path.empty()) {
      RecordsFile f = ReadRecords(config.records_path);
      obs.records = std::move(f.records);
      obs.records_source = config.records_path;
      for (const std::string& n : f.notes) progress->Note(n);
      result->notes.insert(result->notes.end(), f.notes.begin(), f.notes.end());
    }
    if (!config.pixels_path.empty()) {
      PixelsFile f = ReadPixels(config.pixels_path);
      obs.pixels = std::move(f.pixels);
      obs.pixels_source = config.pixels_path;
      for (const std::string& n : f.notes) progress->Note(n);
      result->notes.insert(result->notes.end(), f.notes.begin(), f.notes.end());
    }
    return obs;
  }
  if (!config.simulate) {
    throw std::invalid_argument(
        config.config_path + ": the config needs data.records, data.pixels or a simulate section");
  }
  progress->Step("simulating the instrument");
  SimulationOptions sim = *config.simulate;
  if (config.truth_from_paper) sim.truth = PaperTruth(PlanNumZooms(sim.plan));
  SimulatedData data = Simulate(sim);
  result->simulated = true;
  result->truth = sim.truth;
  progress->Note(std::to_string(data.obs.records.size()) + " records, " +
                 std::to_string(data.obs.pixels.size()) + " pixel observations");
  const RenderSettings render = ParseRenderSettings(config);
  if (render.enabled && !sim.targets.boards.empty()) {
    result->render =
        RenderAndDetect(render, sim.truth, sim.targets, work_dir + "/images", &data.obs, progress);
    if (!result->render.note.empty()) result->notes.push_back(result->render.note);
  }
  return std::move(data.obs);
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

PipelineResult RunPipeline(const RunConfig& config, const std::string& work_dir,
                           Progress* progress) {
  PipelineResult result;
  result.obs = LoadObservations(config, work_dir, &result, progress);
  const Observations& obs = result.obs;

  // 1. Extraction (Klug Sec. 3).
  if (!obs.records.empty()) {
    progress->Step("extracting the DH model (Klug Sec. 3)");
    ExtractOptions eo;
    eo.min_zenith_rad = config.fit.min_zenith_rad;
    eo.max_zenith_rad = config.fit.max_zenith_rad;
    try {
      result.extraction = ExtractDhModel(obs.records, config.model.cameras, eo);
    } catch (const ExtractionError& first) {
      // Without Klug's pixel triplets (Eq. 67) and configured intrinsics the
      // camera tools cannot be extracted as the paper does; intrinsics from
      // the view rays (DLT) let the extraction use every camera row instead.
      std::vector<CameraTool> cameras = config.model.cameras;
      const std::set<int> zooms = ZoomsInData(obs);
      bool estimated = false;
      for (int z : zooms) {
        if (z < static_cast<int>(cameras.size())) continue;
        const auto est = EstimateIntrinsicsFromRays(obs.records, z);
        if (!est) throw;
        cameras.resize(z + 1, est->camera);
        cameras[z] = est->camera;
        result.notes.push_back("extraction: " + est->note);
        progress->Note(est->note);
        estimated = true;
      }
      if (!estimated) throw;
      result.notes.push_back(std::string("extraction: first attempt failed (") + first.what() +
                             "); retried with intrinsics from the view rays");
      result.extraction = ExtractDhModel(obs.records, cameras, eo);
    }
    for (const std::string& n : result.extraction->notes)
      result.notes.push_back("extraction: " + n);
    // 2. Simplification (Sec. 4.1).
    progress->Step("simplifying (Klug Sec. 4.1)");
    const SimplifiedModel simple = Simplify(result.extraction->model);
    result.simplified = simple.model;
    result.closed_form = "M_B,T(phi, theta) rotation (Eq. 90 form):\n" + simple.rotation.ToString();
    if (simple.euler) result.closed_form += "\n= " + simple.euler->ToString() + "   (Eq. 91 form)";
    for (const std::string& n : simple.notes) result.notes.push_back("simplification: " + n);
  }

  // The starting model: the extraction, or the pixels alone (OpenCV per zoom,
  // then the chain; libcalib/fit/init_from_pixels.h), in the configured kinematics.
  InstrumentModel start;
  if (result.extraction) {
    start = result.extraction->model;
    // Zooms with pixels but no camera rows: their camera from the pixels.
    std::set<int> pixel_zooms;
    for (const PixelObservation& p : obs.pixels) pixel_zooms.insert(p.zoom);
    for (int z : pixel_zooms) {
      const auto& poses = result.extraction->camera_poses;
      if (z < start.NumZooms() && z < static_cast<int>(poses.size()) && poses[z] > 0) continue;
      progress->Step("zoom " + std::to_string(z) + ": camera from its pixels");
      for (const std::string& n :
           InitCameraFromPixels(obs.pixels, z, PixelStartOptions(config), &start)) {
        result.notes.push_back("pixel start: " + n);
      }
    }
    if (config.model.kinematics == Kinematics::kSpherical) start = SphericalFromDh(start);
  } else {
    progress->Step("starting from the pixels alone (OpenCV per zoom, then the chain)");
    const InitFromPixelsResult init = InitFromPixels(obs.pixels, PixelStartOptions(config));
    for (const std::string& n : init.notes) result.notes.push_back("pixel start: " + n);
    start = init.model;
  }
  for (int z : ZoomsInData(obs)) {
    if (z >= start.NumZooms()) {
      throw std::invalid_argument("zoom " + std::to_string(z) +
                                  " is in the data but the extraction found no camera rows for "
                                  "it; add model.cameras or camera sweep rows for that zoom");
    }
  }
  start.edm_cyclic_unit_length = config.model.edm_cyclic_unit_length;
  EnableEffects(config.model.effects, &start);
  for (Effect e : config.model.effects.List()) {
    if (start.kinematics == Kinematics::kDh && Info(e).redundant_in_dh) {
      result.notes.push_back(std::string(Info(e).name) +
                             " is part of the dh model (links and tools) and is not fitted twice");
    }
  }
  result.start = start;

  // 3. Error measures of the extracted and simplified models (Table 4).
  const std::vector<Record> reduced = ReducedRecords(obs.records, result.extraction);
  if (result.extraction) {
    Table4 t;
    t.dh_a = EvaluateRecords(result.extraction->model, reduced, ErrorMethod::kA);
    t.dh_b = EvaluateRecords(result.extraction->model, reduced, ErrorMethod::kB);
    t.simplified_a = EvaluateRecords(*result.simplified, reduced, ErrorMethod::kA);
    t.simplified_b = EvaluateRecords(*result.simplified, reduced, ErrorMethod::kB);
    result.table4 = t;
  }

  // 4. Refinement (Sec. 4.3): reduced set, then full set (Table 5).
  FitOptions fo = config.fit;
  if (config.model.intrinsics == IntrinsicsMode::kFit) {
    fo.fit_intrinsics = true;
  } else if (config.model.intrinsics == IntrinsicsMode::kAuto) {
    bool span = true;
    for (int z : ZoomsInData(obs)) span = span && CamDataSpanImage(obs, start, z);
    fo.fit_intrinsics = span && !ZoomsInData(obs).empty();
  }
  result.intrinsics_fitted = fo.fit_intrinsics;
  const Observations reduced_obs = Subset(obs, reduced);
  const bool has_more = reduced.size() < obs.records.size();
  if (has_more) {
    progress->Step("refining on the reduced set (" + std::to_string(reduced.size()) + " records)");
    FitOptions ro = fo;
    // The sweeps alone never span the image: intrinsics stay as they are there.
    ro.fit_intrinsics = fo.fit_intrinsics && CamDataSpanImage(reduced_obs, start, 0);
    result.reduced_model = start;
    result.reduced_fit = Refine(reduced_obs, ro, &result.reduced_model);
  }
  progress->Step("refining on the full set (" + std::to_string(obs.records.size()) + " records, " +
                 std::to_string(obs.pixels.size()) + " pixels)");
  result.model = has_more ? result.reduced_model : start;
  result.model.sigmas = {};
  result.fit = Refine(obs, fo, &result.model);
  result.fit_options = fo;
  if (!has_more) {
    result.reduced_model = result.model;
    result.reduced_fit = result.fit;
  }
  progress->Note("converged: " + std::string(result.fit.converged ? "yes" : "no") + ", " +
                 std::to_string(result.fit.iterations) + " iterations");

  Table5& t5 = result.table5;
  t5.reduced = EvaluateRecords(result.reduced_model, reduced, ErrorMethod::kB);
  t5.full = EvaluateRecords(result.model, obs.records, ErrorMethod::kB);
  t5.has_cross = has_more;
  if (has_more) t5.cross = EvaluateRecords(result.reduced_model, obs.records, ErrorMethod::kB);
  t5.reduced_rows = static_cast<int>(reduced.size());
  t5.full_rows = static_cast<int>(obs.records.size());

  // 5. Faces: one model per face and the classical two-face check.
  if (config.model.faces == FaceMode::kSeparate) {
    progress->Step("fitting one model per face");
    FaceComparison fc;
    fc.face1 = result.model;
    fc.face2 = result.model;
    const Observations o1 = Subset(obs, obs.records, 1), o2 = Subset(obs, obs.records, 2);
    if ((o1.records.empty() && o1.pixels.empty()) || (o2.records.empty() && o2.pixels.empty())) {
      fc.note = "faces: separate needs observations in both faces";
    } else {
      fc.fit1 = Refine(o1, fo, &fc.face1);
      fc.fit2 = Refine(o2, fo, &fc.face2);
      TwoFaceCheck(obs, &fc);
    }
    result.faces = fc;
  }

  result.final_errors = ComputeFinalErrors(result.model, obs);
  progress->Done();
  return result;
}

}  // namespace rtscalib::app

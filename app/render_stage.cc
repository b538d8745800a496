#include "app/render_stage.h"

#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <stdexcept>
#include <tuple>

#include "libcalib/io/csv.h"
#include "libcalib/io/targets_io.h"
#include "libcalib/model/focus.h"
#include "libcalib/model/kinematics.h"

#ifdef RTSCALIB_WITH_RENDER
#include "render/shots.h"
#endif

namespace rtscalib::app {

RenderStageResult RenderSession(const render::RenderSettings& settings,
                                const InstrumentModel& truth, const PlacedScenes& scenes,
                                const std::vector<PixelObservation>& exact,
                                const std::string& image_dir, Progress* progress) {
  RenderStageResult out;
  out.image_dir = image_dir;
  const bool placements = scenes.size() > 1 || !scenes.count("");
  if (placements && settings.board_poses_known) {
    throw std::invalid_argument(
        "render.board_poses: known with simulate.placements: a surveyed board does not move "
        "between placements (SPEC 7.1); leave render.board_poses out");
  }
#ifndef RTSCALIB_WITH_RENDER
  (void)settings, (void)truth, (void)scenes, (void)exact, (void)progress;
  out.note = "this build has no renderer (RTSCALIB_WITH_RENDER=OFF): exact projections used";
  return out;
#else
  // One shot per distinct shot id of the simulated pixel observations.
  // SPEC 4.1: with the focus effect each photo is drawn with the intrinsics
  // focused at its D (the simulator's, or the centroid of its points), and
  // D is written to shots.csv as the instrument would report it.
  const bool focus = truth.effects.Has(Effect::kFocus);
  const std::vector<double> distance = PhotoFocusDistances(truth, exact);
  std::vector<render::Shot> shots;
  std::set<std::string> seen;
  for (size_t i = 0; i < exact.size(); ++i) {
    const PixelObservation& p = exact[i];
    if (!seen.insert(p.shot).second) continue;
    render::Shot s;
    s.face = p.face;
    s.zoom = p.zoom;
    s.phi = p.phi;
    s.theta = p.theta;
    s.id = p.shot;
    s.placement = p.placement;
    s.ref_from_cam = RefFromCam(truth, p.zoom, p.phi, p.theta);
    s.cam = truth.cams.at(p.zoom);
    if (focus && distance[i] > 0) {
      s.focus_distance = distance[i];
      FocusedIntrinsics(truth.cams[p.zoom].intrinsics.data(), truth.cams[p.zoom].focus.data(),
                        s.focus_distance, s.cam.intrinsics.data());
    }
    shots.push_back(s);
  }
  if (shots.empty()) {
    out.note = "no shots to render";
    return out;
  }
  progress->Step("rendering " + std::to_string(shots.size()) + " shots with VTK (" +
                 std::to_string(settings.jobs) + " workers)");
  render::RenderShotsOptions ro;
  ro.out_dir = image_dir;
  ro.jobs = settings.jobs;
  ro.progress = !progress->quiet();
  ro.render.supersample = settings.supersample;
  ro.render.noise_sigma = settings.noise_sigma;
  ro.render.blur_sigma = settings.blur_sigma;
  ro.render.exposure = settings.exposure;
  const render::RenderShotsResult rendered = render::RenderShots(scenes, shots, ro);
  out.render_seconds = rendered.seconds;

  // RenderShots wrote shots.csv (SPEC 7 columns plus `index`); the boards as a
  // user would describe them, and the truth apart.
  namespace fs = std::filesystem;
  out.shots_path = (fs::path(image_dir) / render::ShotsTableName(0, 1)).string();
  out.targets_path = (fs::path(image_dir) / "targets.yaml").string();
  // The boards' layout is every placement's; their poses are the placements'.
  const TargetScene& scene = scenes.begin()->second;
  WriteTargets(out.targets_path, scene, settings.board_poses_known,
               settings.board_poses_known
                   ? "Boards of the rendered session, with their (true) surveyed poses."
                   : placements ? "Boards of the rendered session, moved between placements "
                                  "(shots.csv's placement); their poses are estimated with the "
                                  "instrument."
                                : "Boards of the rendered session; their poses are estimated with "
                                  "the instrument\n(the truth is in truth_targets.yaml).");
  if (!placements) {
    WriteTargets((fs::path(image_dir) / "truth_targets.yaml").string(), scene, true,
                 "The boards' true poses of the rendered session (for tests; a user has no such "
                 "file).");
  }
  out.ran = true;
  out.shots = static_cast<int>(shots.size());
  return out;
#endif
}

void CompareWithExact(const std::vector<PixelObservation>& detected, RenderStageResult* result,
                      Progress* progress) {
  const std::string path = (std::filesystem::path(result->image_dir) / "exact.csv").string();
  const CsvTable t = CsvTable::Read(path, {{"shot", "target", "corner", "u", "v", "status"}, {}});
  using Key = std::pair<std::string, int>;  // shot, tag
  std::map<Key, std::string> status;
  std::map<std::tuple<std::string, int, int>, Eigen::Vector2d> uv;
  for (int r = 0; r < t.NumRows(); ++r) {
    const Key k{t.Text(r, "shot"), static_cast<int>(t.Integer(r, "target"))};
    status[k] = t.Text(r, "status");
    uv[{k.first, k.second, static_cast<int>(t.Integer(r, "corner"))}] =
        Eigen::Vector2d(t.Number(r, "u"), t.Number(r, "v"));
  }
  std::set<Key> found;
  double sq = 0;
  int n = 0;
  for (const PixelObservation& p : detected) {
    const Key k{p.shot, p.target};
    const auto s = status.find(k);
    if (s == status.end() || s->second != "visible") continue;
    found.insert(k);
    const auto e = uv.find({p.shot, p.target, p.corner});
    if (e == uv.end()) continue;
    sq += (p.uv - e->second).squaredNorm();
    ++n;
  }
  result->expected_tags = result->found_tags = 0;
  result->skipped_border = result->skipped_grazing = result->skipped_small = 0;
  for (const auto& [k, s] : status) {
    if (s == "visible") ++result->expected_tags;
    if (s == "border") ++result->skipped_border;
    if (s == "grazing") ++result->skipped_grazing;
    if (s == "small") ++result->skipped_small;
  }
  result->found_tags = static_cast<int>(found.size());
  result->detection_rms_px = n > 0 ? std::sqrt(sq / n) : 0.0;
  progress->Note(std::to_string(result->found_tags) + " of " +
                 std::to_string(result->expected_tags) +
                 " visible tags found; detected corners vs exact projections: RMS " +
                 std::to_string(result->detection_rms_px) + " px");
}

}  // namespace rtscalib::app

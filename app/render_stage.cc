#include "app/render_stage.h"

#include <chrono>
#include <cmath>
#include <map>

#include "libcalib/model/kinematics.h"

#ifdef RTSCALIB_WITH_RENDER
#include "render/shots.h"
#endif

namespace rtscalib::app {

RenderStageResult RenderAndDetect(const render::RenderSettings& settings,
                                  const InstrumentModel& truth, const TargetScene& scene,
                                  const std::string& image_dir, Observations* obs,
                                  Progress* progress) {
  RenderStageResult out;
  out.image_dir = image_dir;
#ifndef RTSCALIB_WITH_RENDER
  out.note = "this build has no renderer (RTSCALIB_WITH_RENDER=OFF): exact projections used";
  return out;
#else
  // One shot per distinct shot id of the simulated pixel observations.
  std::vector<render::Shot> shots;
  std::map<std::string, int> seen;
  for (const PixelObservation& p : obs->pixels) {
    if (seen.count(p.shot)) continue;
    seen[p.shot] = static_cast<int>(shots.size());
    render::Shot s;
    s.face = p.face;
    s.zoom = p.zoom;
    s.phi = p.phi;
    s.theta = p.theta;
    s.id = p.shot;
    s.ref_from_cam = RefFromCam(truth, p.zoom, p.phi, p.theta);
    s.cam = truth.cams.at(p.zoom);
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
  const render::RenderShotsResult rendered = render::RenderShots(scene, shots, ro);
  out.render_seconds = rendered.seconds;

  progress->Step("detecting AprilTags in " + std::to_string(shots.size()) + " images");
  const auto t0 = std::chrono::steady_clock::now();
  render::DetectShotsOptions dopt;
  dopt.detector.families = {settings.family};
  dopt.jobs = settings.jobs;
  dopt.progress = !progress->quiet();
  // The truth only counts what was expected; it never filters what the
  // calibration sees, as with a real instrument.
  dopt.match.max_corner_error_px = 1e9;
  const render::DetectShotsResult det = render::DetectShots(scene, shots, image_dir, dopt);
  out.detect_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  out.ran = true;
  out.shots = static_cast<int>(shots.size());
  out.expected_tags = det.total.expected;
  out.found_tags = det.total.found;
  out.skipped_border = det.total.skipped_border;
  out.skipped_grazing = det.total.skipped_grazing;
  out.skipped_small = det.total.skipped_small;
  out.detection_rms_px = det.total.rms_error_px;
  obs->pixels = det.pixels;
  obs->pixels_source = image_dir + " (detected)";
  progress->Note(std::to_string(out.found_tags) + " of " + std::to_string(out.expected_tags) +
                 " visible tags found; detected corners vs exact projections: RMS " +
                 std::to_string(out.detection_rms_px) + " px");
  return out;
#endif
}

}  // namespace rtscalib::app

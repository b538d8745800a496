// Synthetic calibration shots in the run (docs/rendering.md): the
// simulated instrument's shots are rendered with VTK as its camera would see
// them (render/), AprilTags are detected in the images, and the detections
// replace the exact projections as the run's pixel observations, so that the
// calibration sees what it would see from a real instrument.
#pragma once

#include <string>

#include "app/progress.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"
#include "libcalib/model/targets.h"
#include "render/settings.h"

namespace rtscalib::app {

struct RenderStageResult {
  bool ran = false;
  int shots = 0;
  int expected_tags = 0, found_tags = 0;
  int skipped_border = 0, skipped_grazing = 0, skipped_small = 0;
  double detection_rms_px = 0;  // detected corners vs exact projections
  double render_seconds = 0, detect_seconds = 0;
  std::string image_dir;
  std::string note;
};

// Renders every shot in obs->pixels (shot id, zoom, face, phi, theta) with the
// truth's camera poses, detects the tags and replaces obs->pixels by the
// detections. Without VTK in the build, returns ran = false with a note.
RenderStageResult RenderAndDetect(const render::RenderSettings& settings,
                                  const InstrumentModel& truth, const TargetScene& scene,
                                  const std::string& image_dir, Observations* obs,
                                  Progress* progress);

}  // namespace rtscalib::app

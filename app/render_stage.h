// Synthetic calibration shots in the run: the simulated instrument's shots
// are rendered with VTK as its camera would see them (render/) and written as
// a photo session exactly as a user's instrument would give it (SPEC 7):
//   <image_dir>/<shot>.png          the photos
//   <image_dir>/shots.csv           face, zoom, phi, theta, image, shot (+ index),
//                                   placement when the boards moved (SPEC 7.1)
//   <image_dir>/targets.yaml        the boards; poses only with
//                                   render.board_poses: known (never with placements)
//   <image_dir>/truth_targets.yaml  the boards with their true poses (for tests;
//                                   without placements only)
//   <image_dir>/exact.csv           the exact projections (for tests)
// The session is then read back through the same code as `data.shots`
// (app/photo_session.h), so that the calibration sees what it would see from
// a real instrument.
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
  std::string shots_path, targets_path;  // the written session (empty when not rendered)
};

// Renders every shot in `exact` (shot id, zoom, face, phi, theta, placement)
// with the truth's camera poses, each seeing its placement's scene, and
// writes the session into image_dir. Throws std::invalid_argument for
// surveyed board poses (render.board_poses: known) with several placements:
// a surveyed board does not move. Without VTK in the build, returns ran =
// false with a note.
RenderStageResult RenderSession(const render::RenderSettings& settings,
                                const InstrumentModel& truth, const PlacedScenes& scenes,
                                const std::vector<PixelObservation>& exact,
                                const std::string& image_dir, Progress* progress);

// After the session was read back (obs->pixels from the photos): how the
// detections compare with the exact projections in image_dir/exact.csv
// (tags expected = visible ones, found, skipped by reason, corner RMS).
void CompareWithExact(const std::vector<PixelObservation>& detected, RenderStageResult* result,
                      Progress* progress);

}  // namespace rtscalib::app

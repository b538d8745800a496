// A photo session (SPEC 7: shots.csv, its images and targets.yaml) -> pixel
// observations, through one code path for a user's photos and for the photos
// the render stage writes (app/render_stage.h).
//
// Every photo is searched for the boards' tags (detect/photos.h). Each kept
// corner becomes one PixelObservation: face, zoom, phi, theta from the
// photo's shots.csv row, shot = its shot id, line = its shots.csv line (so a
// message about the observation names the photo), target = tag id, corner =
// 0..3, uv = the detected corner; X = the corner in the reference frame for a
// board with a pose (X_known), X_known = false for a board without one (its
// pose is estimated with everything else). Observations::targets receives the
// boards, Observations::image_sizes the size of every zoom's photos (the
// detection throws an InputError naming both photos when one zoom's photos
// differ in size). A photo without any tag of the boards is a warning.
#pragma once

#include <string>
#include <vector>

#include "app/progress.h"
#include "libcalib/model/observations.h"

namespace rtscalib::app {

struct PhotoSessionSummary {
  bool ran = false;
  std::string shots_path, targets_path;
  int boards_with_pose = 0, boards_without_pose = 0;
  bool tag_boards = false;  // any AprilTag board
  std::string point_words;  // the ChArUco and chessboards' targets in words ("chessboard corners"), or ""
  struct Photo {
    int line = 0;
    std::string shot, image;
    int face = 1, zoom = 0;
    int width = 0, height = 0;
    int tags = 0, tags_of_boards = 0;
    double shift_rms_px = 0;  // refined vs libapriltag corners (the detection's own check)
  };
  std::vector<Photo> photos;  // shots.csv order
  // Targets found: tags and the inner corners of ChArUco and chessboards
  // (`apriltags` + `point_corners`); `corners`: the points they give (4 per tag).
  int tags = 0, corners = 0;
  int apriltags = 0, point_corners = 0;
  int from_neighbours = 0;  // tags grown from their neighbours (detect/board_growth.h)
  std::string targets_in_words;  // "AprilTags", "chessboard corners", ... (detect/photos.h)
  int photos_without_tags = 0;  // photos without any target
  int unrefined = 0, not_on_boards = 0, duplicates = 0;  // dropped detections
  // The detection's own check over the tags libapriltag found: refined vs
  // libapriltag corners [px]; `refined_corners` counts them (0: no such check).
  double shift_rms_px = 0, shift_max_px = 0;
  int refined_corners = 0;
  double seconds = 0, images_per_second = 0;
  int jobs = 1;
  std::vector<std::string> warnings;  // e.g. "shots.csv:7: image a.png: no target of the boards found ..."
};

// The detection's summary line for the log: what was found, in the words of
// the boards (tags, inner corners), and the check of the refined corners
// against libapriltag's only where libapriltag found tags.
std::string PhotoSessionLine(const PhotoSessionSummary& summary);

// Reads shots.csv and targets.yaml, detects every photo with `jobs` threads
// and appends the corners to obs->pixels (obs->pixels_source = the shots
// file when obs had no pixels); sets obs->targets and obs->image_sizes.
// shots.csv's phi, theta are read in `angle_unit` (data.angle_unit).
// Throws InputError for bad files, unreadable images and mixed sizes.
PhotoSessionSummary LoadPhotoSession(const std::string& shots_path, const std::string& targets_path,
                                     int jobs, Observations* obs, Progress* progress,
                                     AngleUnit angle_unit = AngleUnit::kRad);

}  // namespace rtscalib::app

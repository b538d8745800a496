#include "app/photo_session.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "detect/photos.h"
#include "detect/tag_family.h"
#include "libcalib/io/shots.h"
#include "libcalib/io/targets_io.h"

namespace rtscalib::app {

PhotoSessionSummary LoadPhotoSession(const std::string& shots_path, const std::string& targets_path,
                                     int jobs, Observations* obs, Progress* progress,
                                     AngleUnit angle_unit) {
  PhotoSessionSummary out;
  out.shots_path = shots_path;
  out.targets_path = targets_path;
  out.jobs = jobs;
  const std::map<std::string, int> families = detect::DetectableCodeCounts();
  const TargetScene targets = ReadTargets(targets_path, &families);
  const ShotsFile shots = ReadShots(shots_path, angle_unit);
  for (const std::string& n : shots.notes) progress->Note(n);
  for (const TagBoard& b : targets.boards)
    ++(b.pose_known ? out.boards_with_pose : out.boards_without_pose);

  progress->Step("detecting AprilTags in " + std::to_string(shots.shots.size()) + " photos of " +
                 shots_path + " (" + std::to_string(jobs) + " job(s))");
  detect::PhotoDetectionOptions options;
  options.jobs = jobs;
  options.progress = !progress->quiet();
  const detect::PhotoDetectionResult det = detect::DetectPhotos(shots, targets, options);
  out.ran = true;
  out.seconds = det.seconds;
  out.images_per_second = det.seconds > 0 ? shots.shots.size() / det.seconds : 0.0;
  out.warnings = det.warnings;

  if (obs->pixels.empty()) obs->pixels_source = shots_path;
  obs->pixel_covariates = shots.covariates;
  const std::vector<PixelObservation> pixels = detect::PixelObservationsOf(shots, targets, det);
  obs->pixels.insert(obs->pixels.end(), pixels.begin(), pixels.end());
  for (const auto& [zoom, size] : detect::ImageSizesOf(shots, det)) obs->image_sizes[zoom] = size;
  double shift_sq = 0;
  int refined_corners = 0;
  for (size_t i = 0; i < shots.shots.size(); ++i) {
    const PhotoShot& s = shots.shots[i];
    const detect::PhotoDetection& p = det.photos[i];
    PhotoSessionSummary::Photo ph;
    ph.line = s.line;
    ph.shot = s.shot;
    ph.image = s.image;
    ph.face = s.face;
    ph.zoom = s.zoom;
    ph.width = p.width;
    ph.height = p.height;
    ph.tags = static_cast<int>(p.tags.size());
    ph.tags_of_boards = p.tags_of_boards;
    ph.shift_rms_px = p.shift_rms_px;
    out.photos.push_back(ph);
    out.tags += ph.tags;
    out.corners += p.corners;
    out.photos_without_tags += p.tags.empty() ? 1 : 0;
    out.unrefined += p.unrefined;
    out.not_on_boards += p.not_on_boards;
    out.duplicates += p.duplicates;
    shift_sq += p.shift_rms_px * p.shift_rms_px * p.refined_corners;
    refined_corners += p.refined_corners;
    out.shift_max_px = std::max(out.shift_max_px, p.shift_max_px);
  }
  out.shift_rms_px = refined_corners > 0 ? std::sqrt(shift_sq / refined_corners) : 0.0;
  obs->targets = targets;

  char line[256];
  std::snprintf(line, sizeof line,
                "%zu photos: %d tags, %d corners; %d photos without tags; %.1f images/s; refined "
                "vs libapriltag corners RMS %.3f px, max %.3f px",
                shots.shots.size(), out.tags, out.corners, out.photos_without_tags,
                out.images_per_second, out.shift_rms_px, out.shift_max_px);
  progress->Note(line);
  for (const std::string& w : out.warnings) progress->Note("warning: " + w);
  return out;
}

}  // namespace rtscalib::app

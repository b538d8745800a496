#include "app/photo_session.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "detect/photos.h"
#include "detect/tag_family.h"
#include "libcalib/io/shots.h"
#include "libcalib/io/targets_io.h"

namespace rtscalib::app {

std::string PhotoSessionLine(const PhotoSessionSummary& s) {
  std::vector<std::string> found;
  if (s.tag_boards) {
    std::string tags = std::to_string(s.apriltags) + " tags (" +
                       std::to_string(4 * s.apriltags) + " corners";
    if (s.from_neighbours > 0) {
      tags += "; " + std::to_string(s.from_neighbours) + " of the tags grown from their neighbours";
    }
    found.push_back(tags + ")");
  }
  if (!s.point_words.empty()) found.push_back(std::to_string(s.point_corners) + " " + s.point_words);
  std::string line = std::to_string(s.photos.size()) + " photos: ";
  for (const std::string& f : found) line += f + ", ";
  char rest[256];
  std::snprintf(rest, sizeof rest, "%d photos without a target; %.1f images/s",
                s.photos_without_tags, s.images_per_second);
  line += rest;
  if (s.refined_corners > 0) {
    std::snprintf(rest, sizeof rest, "; refined vs libapriltag corners RMS %.3f px, max %.3f px",
                  s.shift_rms_px, s.shift_max_px);
    line += rest;
  }
  return line;
}

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
  TargetScene point_boards;
  for (const TagBoard& b : targets.boards) {
    ++(b.pose_known ? out.boards_with_pose : out.boards_without_pose);
    if (b.IsPointBoard()) point_boards.boards.push_back(b);
    out.tag_boards |= !b.IsPointBoard();
  }
  out.point_words = detect::TargetsInWords(point_boards);

  out.targets_in_words = detect::TargetsInWords(targets);
  progress->Step("detecting " + out.targets_in_words + " in " +
                 std::to_string(shots.shots.size()) + " photos of " + shots_path + " (" +
                 std::to_string(jobs) + " job(s))");
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
    for (const detect::DetectedTag& t : p.tags) {
      ++(targets.boards[t.board].IsPointBoard() ? out.point_corners : out.apriltags);
    }
    out.from_neighbours += p.from_neighbours;
    out.corners += p.corners;
    out.photos_without_tags += p.tags.empty() ? 1 : 0;
    out.unrefined += p.unrefined;
    out.not_on_boards += p.not_on_boards;
    out.duplicates += p.duplicates;
    shift_sq += p.shift_rms_px * p.shift_rms_px * p.refined_corners;
    out.refined_corners += p.refined_corners;
    out.shift_max_px = std::max(out.shift_max_px, p.shift_max_px);
  }
  out.shift_rms_px =
      out.refined_corners > 0 ? std::sqrt(shift_sq / out.refined_corners) : 0.0;
  obs->targets = targets;
  progress->Note(PhotoSessionLine(out));
  for (const std::string& w : out.warnings) progress->Note("warning: " + w);
  return out;
}

}  // namespace rtscalib::app

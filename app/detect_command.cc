#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "app/commands.h"
#include "libcalib/io/safe_write.h"
#include "detect/photos.h"
#include "detect/tag_family.h"
#include "libcalib/io/records.h"
#include "libcalib/io/shots.h"
#include "libcalib/io/targets_io.h"

namespace rtscalib::app {

// SPEC 7: `rtscalib detect --shots shots.csv --targets targets.yaml --out pixels.csv`.
// Writes pixels.csv and <out>.summary.csv (one row per photo, detect/photos.h),
// prints the per-photo counts and the warnings.
int RunDetect(const DetectArgs& args) {
  const std::string summary_path = args.out + ".summary.csv";
  for (const std::string& path : {args.out, summary_path}) {
    if (std::filesystem::exists(path) && !args.force) {
      throw std::runtime_error(
          "detect: '" + path +
          "' exists; rtscalib does not overwrite files you have (use --force)");
    }
  }
  const std::map<std::string, int> families = detect::DetectableCodeCounts();
  const TargetScene targets = ReadTargets(args.targets, &families);
  const ShotsFile shots = ReadShots(args.shots, AngleUnitArg("detect", args.angle_unit));
  for (const std::string& note : shots.notes) std::cerr << "detect: note: " << note << "\n";

  detect::PhotoDetectionOptions options;
  options.jobs = args.jobs;
  options.keep_unrefined = args.keep_unrefined;
  options.progress = !args.quiet;
  const detect::PhotoDetectionResult result = detect::DetectPhotos(shots, targets, options);
  // Each file written whole or not at all; kKeep also covers a file that appears meanwhile.
  const Existing existing = args.force ? Existing::kReplace : Existing::kKeep;
  WriteFileAtomicWith(
      args.out,
      [&](const std::string& tmp) {
        WritePixels(tmp, detect::PixelObservationsOf(shots, targets, result), shots.angle_unit,
                    detect::ImageSizesOf(shots, result), shots.covariates);
      },
      existing);
  WriteFileAtomicWith(
      summary_path,
      [&](const std::string& tmp) { detect::WriteDetectionSummary(tmp, shots, result); }, existing);

  int tags = 0, points = 0, corners = 0, unrefined = 0, not_on_boards = 0, duplicates = 0;
  int empty = 0, refined_corners = 0, pattern_refined = 0, from_neighbours = 0;
  double shift_sq = 0, shift_max = 0;
  bool tag_boards = false;
  TargetScene point_boards;
  for (const TagBoard& b : targets.boards) {
    if (b.IsPointBoard()) point_boards.boards.push_back(b);
    tag_boards |= !b.IsPointBoard();
  }
  // The shift against libapriltag's corners only where it can find tags.
  std::printf("%-24s %11s %9s %8s%s\n", "shot", "size", "found", "corners",
              tag_boards ? "  shift_rms" : "");
  for (size_t i = 0; i < shots.shots.size(); ++i) {
    const detect::PhotoDetection& p = result.photos[i];
    char size[32], found[32];
    std::snprintf(size, sizeof size, "%dx%d", p.width, p.height);
    std::snprintf(found, sizeof found, "%zu/%d", p.tags.size(), p.tags_of_boards);
    std::printf("%-24s %11s %9s %8zu", shots.shots[i].shot.c_str(), size, found,
                static_cast<size_t>(p.corners));
    if (tag_boards) std::printf(" %10.3f", p.shift_rms_px);
    std::printf("\n");
    for (const detect::DetectedTag& t : p.tags) {
      ++(targets.boards[t.board].IsPointBoard() ? points : tags);
    }
    corners += p.corners;
    unrefined += p.unrefined;
    not_on_boards += p.not_on_boards;
    duplicates += p.duplicates;
    empty += p.tags.empty() ? 1 : 0;
    shift_sq += p.shift_rms_px * p.shift_rms_px * p.refined_corners;
    shift_max = std::max(shift_max, p.shift_max_px);
    refined_corners += p.refined_corners;
    pattern_refined += p.pattern_refined;
    from_neighbours += p.from_neighbours;
  }
  const int n = static_cast<int>(shots.shots.size());
  std::printf("detect: %d photos (%s), %d corners", n, detect::TargetsInWords(targets).c_str(),
              corners);
  if (tag_boards) {
    std::printf("; %d tags (%d by the pattern fit of small tags, %d grown from their neighbours); "
                "dropped: %d unrefined, %d not on a board, %d duplicated",
                tags, pattern_refined, from_neighbours, unrefined, not_on_boards, duplicates);
  }
  if (!point_boards.boards.empty()) {
    std::printf("; %d %s", points, detect::TargetsInWords(point_boards).c_str());
  }
  std::printf("; %d photos without a target\n", empty);
  if (refined_corners > 0) {
    std::printf("detect: refined vs libapriltag corners: RMS %.3f px, max %.3f px\n",
                std::sqrt(shift_sq / refined_corners), shift_max);
  }
  std::printf("detect: %.2f s, %.1f images/s with %d job(s)\n", result.seconds,
              result.seconds > 0 ? n / result.seconds : 0.0, args.jobs);
  for (const std::string& w : result.warnings) std::cerr << "detect: warning: " << w << "\n";
  std::cerr << "detect: " << corners << " corners -> " << args.out << ", summary -> "
            << summary_path << "\n";
  return 0;
}

}  // namespace rtscalib::app

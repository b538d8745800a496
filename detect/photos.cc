#include "detect/photos.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cmath>
#include <cstdio>
#include <exception>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>

#include <opencv2/core.hpp>

#include "detect/photo_image.h"
#include "detect/point_boards.h"
#include "detect/tag_family.h"
#include "libcalib/io/csv.h"
#include "libcalib/text/errors.h"
#include "libcalib/io/targets_io.h"
#include "libcalib/text/number_text.h"

namespace rtscalib::detect {
namespace {

std::string Where(const ShotsFile& shots, int i) {
  return shots.path + ":" + std::to_string(shots.shots[i].line) + ": image " + shots.shots[i].image;
}

// Keeps the detections of board tags (family and id of a board), in id order.
void KeepBoardTags(const std::vector<TagDetection>& detections, const TargetScene& targets,
                   bool keep_unrefined, PhotoDetection* photo) {
  std::map<int, int> count;  // id -> detections of a board tag
  std::vector<std::pair<const TagDetection*, int>> on_board;
  for (const TagDetection& d : detections) {
    int board = -1;
    for (size_t b = 0; b < targets.boards.size(); ++b) {
      const TagBoard& tb = targets.boards[b];
      if (!tb.IsPointBoard() && tb.family == d.family && tb.border_bits == d.border_bits &&
          tb.HasId(d.id)) {
        board = static_cast<int>(b);
      }
    }
    if (board < 0) {
      ++photo->not_on_boards;
      continue;
    }
    ++count[d.id];
    on_board.emplace_back(&d, board);
  }
  double sum_sq = 0;
  for (const auto& [d, board] : on_board) {
    if (count[d->id] > 1) {
      ++photo->duplicates;
      if (std::find(photo->duplicate_ids.begin(), photo->duplicate_ids.end(), d->id) ==
          photo->duplicate_ids.end()) {
        photo->duplicate_ids.push_back(d->id);
      }
      continue;
    }
    if (!d->refined()) {
      ++photo->unrefined;
      if (!keep_unrefined) continue;
    }
    photo->tags.push_back({board, d->id, d->corners, d->refinement});
    if (d->refinement == CornerRefinement::kPattern) ++photo->pattern_refined;
    if (d->from_neighbours) ++photo->from_neighbours;
    if (d->refined() && !d->from_neighbours) {
      for (int k = 0; k < 4; ++k) {
        const double shift = (d->corners[k] - d->apriltag_corners[k]).norm();
        sum_sq += shift * shift;
        photo->shift_max_px = std::max(photo->shift_max_px, shift);
        ++photo->refined_corners;
      }
    }
  }
  if (photo->refined_corners > 0) photo->shift_rms_px = std::sqrt(sum_sq / photo->refined_corners);
  std::sort(photo->tags.begin(), photo->tags.end(),
            [](const DetectedTag& a, const DetectedTag& b) { return a.id < b.id; });
}

// The inner corners of the ChArUco and chessboards (point_boards.h), one
// DetectedTag each (all four corners the same point), merged in id order.
// `own_placement`: no other photo shares the photo's placement, so that a
// board of unknown pose has a pose of this photo's alone (CopySearch).
void KeepPointBoards(const cv::Mat& gray, const TargetScene& targets, int face,
                     bool own_placement, PhotoDetection* photo) {
  bool added = false;
  for (size_t b = 0; b < targets.boards.size(); ++b) {
    const TagBoard& board = targets.boards[b];
    if (!board.IsPointBoard()) continue;
    const CopySearch copies =
        own_placement && !board.pose_known ? CopySearch::kSkip : CopySearch::kSearch;
    const PointBoardDetection found = DetectPointBoard(gray, board, face, copies);
    if (found.misoriented) ++photo->misoriented_boards;
    if (found.duplicated) ++photo->duplicate_boards;
    for (const auto& [k, uv] : found.corners) {
      photo->tags.push_back({static_cast<int>(b), board.first_id + k, {uv, uv, uv, uv},
                             CornerRefinement::kSaddle});
      added = true;
    }
  }
  if (added) {
    std::sort(photo->tags.begin(), photo->tags.end(),
              [](const DetectedTag& a, const DetectedTag& b) { return a.id < b.id; });
  }
}

// Limits OpenCV's thread pool for the lifetime of the object.
class CvThreads {
 public:
  explicit CvThreads(int n) : previous_(cv::getNumThreads()) { cv::setNumThreads(n); }
  ~CvThreads() { cv::setNumThreads(previous_); }

 private:
  int previous_;
};

}  // namespace

std::string PhotoDetectionOptions::Check() const {
  if (jobs < 1) return "jobs: expected >= 1, got " + std::to_string(jobs);
  DetectorOptions d = detector;
  d.families = {PrintedFamily{}};  // replaced by the boards' families
  if (const std::string msg = d.Check(); !msg.empty()) return "detector." + msg;
  if (const std::string msg = growth.Check(); !msg.empty()) return "growth." + msg;
  return "";
}

std::map<std::string, int> DetectableCodeCounts() {
  std::map<std::string, int> out = FamilyCodeCounts();
  for (const std::string& name : KnownTagFamilies()) {
    if (TakesWideBorder(name)) out[WideBorderKey(name)] = out.at(name);
  }
  for (const auto& [name, markers] : ArucoDictionaryMarkerCounts()) out[ArucoCodesKey(name)] = markers;
  return out;
}

std::string TargetsInWords(const TargetScene& targets) {
  bool tags = false, charuco = false, chessboard = false;
  for (const TagBoard& b : targets.boards) {
    tags |= b.kind == BoardKind::kAprilTag;
    charuco |= b.kind == BoardKind::kCharuco;
    chessboard |= b.kind == BoardKind::kChessboard;
  }
  std::vector<std::string> parts;
  if (tags) parts.push_back("AprilTags");
  if (charuco) parts.push_back(chessboard ? "ChArUco" : "ChArUco corners");
  if (chessboard) parts.push_back("chessboard corners");
  std::string out;
  for (size_t i = 0; i < parts.size(); ++i) {
    out += (i == 0 ? "" : i + 1 == parts.size() ? " and " : ", ") + parts[i];
  }
  return out;
}

PhotoDetectionResult DetectPhotos(const ShotsFile& shots, const TargetScene& targets,
                                  const PhotoDetectionOptions& options) {
  if (const std::string msg = options.Check(); !msg.empty()) {
    throw std::invalid_argument("PhotoDetectionOptions: " + msg);
  }
  if (targets.boards.empty()) throw std::invalid_argument("DetectPhotos: no boards");
  DetectorOptions detector_options = options.detector;
  detector_options.families.clear();
  int tags_of_boards = 0;
  for (const TagBoard& b : targets.boards) {
    tags_of_boards += b.NumTags();
    if (b.IsPointBoard()) continue;  // OpenCV's detectors (point_boards.h)
    const PrintedFamily printed{b.family, b.border_bits};
    if (std::find(detector_options.families.begin(), detector_options.families.end(), printed) ==
        detector_options.families.end()) {
      detector_options.families.push_back(printed);
    }
  }
  const bool any_tags = !detector_options.families.empty();

  const int n = static_cast<int>(shots.shots.size());
  std::map<std::string, int> photos_of_placement;
  for (const PhotoShot& shot : shots.shots) ++photos_of_placement[shot.placement];
  PhotoDetectionResult result;
  result.photos.resize(n);
  std::vector<char> done(n, 0);  // one byte per photo: threads write distinct elements
  const auto start = std::chrono::steady_clock::now();

  std::atomic<int> next{0}, finished{0};
  // Wakes the waiting thread when a photo is done (a timed wait would end
  // the detection up to its period late).
  std::mutex progress_mutex;
  std::condition_variable progress_cv;
  std::atomic<bool> stop{false};
  std::mutex mutex;  // guards size_of_zoom, first_error*
  std::map<int, std::pair<int, int>> size_of_zoom;
  int first_error_index = n;
  std::exception_ptr first_error;

  auto work = [&] {
    std::unique_ptr<TagDetector> detector;
    if (any_tags) detector = std::make_unique<TagDetector>(detector_options);
    while (!stop) {
      const int i = next++;
      if (i >= n) break;
      const PhotoShot& shot = shots.shots[i];
      try {
        Photo image;
        try {
          image = LoadPhoto(shot.image_path);
        } catch (const PhotoError& e) {
          throw InputError::Cell(shots.path, shot.line, "image",
                                 "a whole image OpenCV can read (PNG, JPEG or TIFF; 8 or 16 bit; "
                                 "grey or colour)",
                                 e.what());
        }
        {
          std::lock_guard<std::mutex> lock(mutex);
          const auto [it, inserted] =
              size_of_zoom.emplace(shot.zoom, std::make_pair(image.width, image.height));
          if (!inserted && it->second != std::make_pair(image.width, image.height)) stop = true;
        }
        PhotoDetection& photo = result.photos[i];
        photo.width = image.width;
        photo.height = image.height;
        photo.channels = image.channels;
        photo.bit_depth = image.bit_depth;
        photo.tags_of_boards = tags_of_boards;
        if (detector) {
          std::vector<TagDetection> detections = detector->Detect(image.gray);
          if (options.grow_boards) {
            for (const TagBoard& board : targets.boards) {
              if (!board.IsPointBoard()) {
                GrowBoardTags(image.gray, board, detector.get(), &detections, options.growth);
              }
            }
          }
          KeepBoardTags(detections, targets, options.keep_unrefined, &photo);
        }
        KeepPointBoards(image.gray, targets, shot.face,
                        shots.has_placements && photos_of_placement.at(shot.placement) == 1,
                        &photo);
        for (const DetectedTag& tag : photo.tags) {
          photo.corners += targets.boards[tag.board].CornersPerTarget();
        }
        done[i] = 1;
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex);
        if (i < first_error_index) {
          first_error_index = i;
          first_error = std::current_exception();
        }
        stop = true;
      }
      {
        std::lock_guard<std::mutex> lock(progress_mutex);
        ++finished;
      }
      progress_cv.notify_one();
    }
  };
  {
    const CvThreads cv_threads(options.jobs > 1 ? 1 : cv::getNumThreads());
    std::vector<std::thread> pool;
    for (int t = 0; t < std::min(options.jobs, std::max(1, n)); ++t) pool.emplace_back(work);
    // Progress on long runs: a line every 5 s once a run has lasted 5 s.
    auto last = start;
    while (finished < n && !stop) {
      {
        std::unique_lock<std::mutex> lock(progress_mutex);
        progress_cv.wait_for(lock, std::chrono::seconds(1), [&] { return finished >= n || stop; });
      }
      const auto now = std::chrono::steady_clock::now();
      if (options.progress && now - last >= std::chrono::seconds(5)) {
        last = now;
        const double s = std::chrono::duration<double>(now - start).count();
        std::fprintf(stderr, "[detect] %d/%d images, %.1f images/s\n", finished.load(), n,
                     finished / s);
      }
    }
    for (std::thread& t : pool) t.join();
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // Image sizes within a zoom, checked in shots.csv order so that the message
  // names the first photo of the zoom and the first that differs.
  std::map<int, int> first_of_zoom;
  for (int i = 0; i < n; ++i) {
    if (!done[i]) continue;
    const PhotoDetection& p = result.photos[i];
    const auto [it, inserted] = first_of_zoom.emplace(shots.shots[i].zoom, i);
    const PhotoDetection& q = result.photos[it->second];
    if (!inserted && (p.width != q.width || p.height != q.height)) {
      const PhotoShot& ref = shots.shots[it->second];
      throw InputError::Cell(shots.path, shots.shots[i].line, "image",
                             "an image of " + std::to_string(q.width) + "x" +
                                 std::to_string(q.height) + " px like every photo of zoom " +
                                 std::to_string(ref.zoom) + " (line " + std::to_string(ref.line) +
                                 ", " + ref.image_path + ")",
                             shots.shots[i].image_path + ": " + std::to_string(p.width) + "x" +
                                 std::to_string(p.height) + " px");
    }
  }
  if (first_error) std::rethrow_exception(first_error);

  for (int i = 0; i < n; ++i) {
    if (result.photos[i].misoriented_boards > 0) {
      result.warnings.push_back(
          Where(shots, i) + ": " + std::to_string(result.photos[i].misoriented_boards) +
          " chessboard(s) found turned sideways or mirrored, not used (in face 1 a chessboard's "
          "rows must run along the image's rows; detect/point_boards.h)");
    }
    if (result.photos[i].duplicate_boards > 0) {
      result.warnings.push_back(Where(shots, i) + ": a chessboard found twice (two printed copies, "
                                                  "or a reflection), not used: neither can be "
                                                  "told from the other");
    }
    if (!result.photos[i].duplicate_ids.empty()) {
      std::string ids;
      for (int id : result.photos[i].duplicate_ids) ids += (ids.empty() ? "" : ", ") + std::to_string(id);
      result.warnings.push_back(Where(shots, i) + ": tag(s) " + ids +
                                " seen twice (two printed copies?), not used");
    }
    if (result.photos[i].tags.empty()) {
      const PhotoDetection& p = result.photos[i];
      std::string why = "no target of the boards found (no tag, ChArUco corner or whole chessboard)";
      if (p.unrefined + p.not_on_boards + p.duplicates > 0) {
        why += " (dropped: " + std::to_string(p.unrefined) + " unrefined, " +
               std::to_string(p.not_on_boards) + " not on a board, " +
               std::to_string(p.duplicates) + " duplicated)";
      }
      result.warnings.push_back(Where(shots, i) + ": " + why);
    }
  }
  return result;
}

void AppendPixelObservations(const PhotoShot& shot, const TargetScene& targets,
                             const std::vector<DetectedTag>& tags,
                             std::vector<PixelObservation>* out) {
  for (const DetectedTag& tag : tags) {
    const TagBoard& board = targets.boards[tag.board];
    const std::array<Eigen::Vector3d, 4> corners = board.CornersInBoard(tag.id - board.first_id);
    for (int k = 0; k < board.CornersPerTarget(); ++k) {
      PixelObservation o;
      o.face = shot.face;
      o.zoom = shot.zoom;
      o.phi = shot.phi;
      o.theta = shot.theta;
      o.has_reading = shot.has_reading;
      o.shot = shot.shot;
      o.placement = shot.placement;
      o.focus_distance = shot.focus_distance;
      o.covariates = shot.covariates;
      o.target = tag.id;
      o.corner = k;
      o.X_known = board.pose_known;
      if (board.pose_known) o.X = board.ref_from_board * corners[k];
      o.uv = tag.uv[k];
      o.line = shot.line;
      out->push_back(o);
    }
  }
}

std::vector<PixelObservation> PixelObservationsOf(const ShotsFile& shots,
                                                  const TargetScene& targets,
                                                  const PhotoDetectionResult& result) {
  std::vector<PixelObservation> out;
  for (size_t i = 0; i < shots.shots.size(); ++i) {
    AppendPixelObservations(shots.shots[i], targets, result.photos[i].tags, &out);
  }
  return out;
}

std::map<int, ImageSize> ImageSizesOf(const ShotsFile& shots, const PhotoDetectionResult& result) {
  std::map<int, ImageSize> out;
  for (size_t i = 0; i < shots.shots.size(); ++i) {
    const PhotoDetection& p = result.photos[i];
    if (p.width > 0 && p.height > 0) out[shots.shots[i].zoom] = ImageSize{p.width, p.height};
  }
  return out;
}

void WriteDetectionSummary(const std::string& path, const ShotsFile& shots,
                           const PhotoDetectionResult& result) {
  CsvWriter w(path, {"line", "shot", "image", "face", "zoom", "width", "height", "channels",
                     "bit_depth", "tags_found", "tags_of_boards", "corners", "refined_corners",
                     "unrefined", "not_on_boards", "duplicates", "shift_rms_px", "shift_max_px",
                     "pattern_refined", "from_neighbours"});
  for (size_t i = 0; i < shots.shots.size(); ++i) {
    const PhotoShot& s = shots.shots[i];
    const PhotoDetection& p = result.photos[i];
    char rms[32], max[32];
    std::snprintf(rms, sizeof rms, "%.4f", p.shift_rms_px);
    std::snprintf(max, sizeof max, "%.4f", p.shift_max_px);
    w.Row({std::to_string(s.line), s.shot, s.image, std::to_string(s.face), std::to_string(s.zoom),
           std::to_string(p.width), std::to_string(p.height), std::to_string(p.channels),
           std::to_string(p.bit_depth), std::to_string(p.tags.size()),
           std::to_string(p.tags_of_boards), std::to_string(p.corners),
           std::to_string(p.refined_corners), std::to_string(p.unrefined),
           std::to_string(p.not_on_boards), std::to_string(p.duplicates), rms, max,
           std::to_string(p.pattern_refined), std::to_string(p.from_neighbours)});
  }
  w.Close();
}

}  // namespace rtscalib::detect

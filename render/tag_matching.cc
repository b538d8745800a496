#include "render/tag_matching.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include "libcalib/camera/opencv_model.h"
#include "render/tag_texture.h"

namespace rtscalib::render {
namespace {

// A board's printed rectangle in the reference frame, as an occluder.
struct Occluder {
  Rigid3 ref_from_board;
  Rigid3 board_from_ref;
  BoardRect rect;
};

// Does segment a -> b (reference frame) cross the occluder strictly between
// its ends?
bool Blocks(const Occluder& o, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d pa = o.board_from_ref * a, pb = o.board_from_ref * b;
  if ((pa.z() > 0) == (pb.z() > 0) || pa.z() == pb.z()) return false;
  const double t = pa.z() / (pa.z() - pb.z());
  if (t <= 1e-9 || t >= 1 - 1e-9) return false;
  const Eigen::Vector3d p = pa + t * (pb - pa);
  return p.x() >= o.rect.x_min && p.x() <= o.rect.x_max && p.y() >= o.rect.y_min &&
         p.y() <= o.rect.y_max;
}

}  // namespace

const char* TagStatusName(TagStatus status) {
  switch (status) {
    case TagStatus::kVisible:
      return "visible";
    case TagStatus::kBehind:
      return "behind";
    case TagStatus::kBackFacing:
      return "back_facing";
    case TagStatus::kOutside:
      return "outside";
    case TagStatus::kOccluded:
      return "occluded";
    case TagStatus::kBorder:
      return "border";
    case TagStatus::kGrazing:
      return "grazing";
    case TagStatus::kSmall:
      return "small";
  }
  return "?";
}

std::string VisibilityOptions::Check() const {
  if (!(border_margin_px >= 0)) return "border_margin_px: expected >= 0";
  if (!(max_view_angle_deg > 0 && max_view_angle_deg <= 90)) {
    return "max_view_angle_deg: expected in (0, 90]";
  }
  if (!(min_bit_px >= 0)) return "min_bit_px: expected >= 0";
  return "";
}

std::string MatchOptions::Check() const {
  if (!(max_corner_error_px > 0)) return "max_corner_error_px: expected > 0";
  return "";
}

std::vector<ExpectedTag> ExpectTags(const TargetScene& scene, const Rigid3& ref_from_cam,
                                    const CameraTool& cam, const VisibilityOptions& options) {
  const Rigid3 cam_from_ref = ref_from_cam.Inverse();
  const Eigen::Vector3d centre = ref_from_cam.translation;
  const double* k = cam.intrinsics.data();
  const double* d = cam.distortion.data();
  std::vector<Occluder> occluders;
  for (const TagBoard& b : scene.boards) {
    occluders.push_back({b.ref_from_board, b.ref_from_board.Inverse(), PrintedArea(b)});
  }
  const double max_angle = options.max_view_angle_deg * M_PI / 180.0;
  const double m = options.border_margin_px;
  auto inner = [&](const Eigen::Vector2d& px) {
    return px.x() >= m - 0.5 && px.x() <= cam.width - 0.5 - m && px.y() >= m - 0.5 &&
           px.y() <= cam.height - 0.5 - m;
  };
  // The pixel of reference point X, where the projection is valid: in front
  // of the camera, and where the distortion does not fold the image (the
  // pixel must back-project onto the same ray).
  auto project = [&](const Eigen::Vector3d& X, Eigen::Vector2d* uv) {
    const Eigen::Vector3d p = cam_from_ref * X;
    if (!(p.z() > 0)) return false;
    double px[2];
    ProjectToPixel(k, d, p.data(), px);
    double xn, yn;
    if (!(std::isfinite(px[0]) && std::isfinite(px[1]) && UndistortPixel(k, d, px, &xn, &yn) &&
          std::abs(xn - p.x() / p.z()) + std::abs(yn - p.y() / p.z()) < 1e-7)) {
      return false;
    }
    *uv = Eigen::Vector2d(px[0], px[1]);
    return true;
  };

  std::vector<ExpectedTag> out;
  for (int bi = 0; bi < static_cast<int>(scene.boards.size()); ++bi) {
    const TagBoard& board = scene.boards[bi];
    const int num_corners = board.CornersPerTarget();
    // Code bits per edge length on the board: a tag's quad edge, or the
    // square edges around an inner corner.
    const double edge = board.IsPointBoard() ? board.square_size : board.tag_size;
    const double bits_per_edge = edge / PrintedBitSize(board);
    // The printed side faces the board's -z (targets.h).
    const Eigen::Vector3d printed_normal = -board.ref_from_board.rotation.col(2);
    const bool facing = (centre - board.ref_from_board.translation).dot(printed_normal) > 0;
    for (int i = 0; i < board.NumTags(); ++i) {
      ExpectedTag t;
      t.board = bi;
      t.id = board.first_id + i;
      t.family = board.family;
      t.corners = num_corners;
      const auto corners = board.CornersInBoard(i);
      bool behind = false, any_in = false, all_inner = true, failed = false;
      for (int c = 0; c < num_corners; ++c) {
        t.X[c] = board.ref_from_board * corners[c];
        const Eigen::Vector3d to_cam = (centre - t.X[c]).normalized();
        t.view_angle =
            std::max(t.view_angle, std::acos(std::clamp(to_cam.dot(printed_normal), -1.0, 1.0)));
        if (!((cam_from_ref * t.X[c]).z() > 0)) {
          behind = true;
          continue;
        }
        if (!project(t.X[c], &t.uv[c])) {
          failed = true;
          continue;
        }
        t.projected[c] = true;
        const Eigen::Vector2d& px = t.uv[c];
        t.in_image[c] = px.x() >= -0.5 && px.x() < cam.width - 0.5 && px.y() >= -0.5 &&
                        px.y() < cam.height - 0.5;
        any_in = any_in || t.in_image[c];
        all_inner = all_inner && inner(px);
      }
      if (!behind && !failed) {
        if (board.IsPointBoard()) {
          // The corners of the four squares around the inner corner: all
          // inside the margin, and the squares' edges give the bit size.
          double min_edge = 1e300;
          for (int dy = -1; dy <= 1; ++dy) {
            for (int dx = -1; dx <= 1; ++dx) {
              if (dx == 0 && dy == 0) continue;
              Eigen::Vector2d uv;
              const Eigen::Vector3d n =
                  board.ref_from_board * (corners[0] + edge * Eigen::Vector3d(dx, dy, 0));
              if (!project(n, &uv)) {
                all_inner = false;
                continue;
              }
              all_inner = all_inner && inner(uv);
              if (dx == 0 || dy == 0) min_edge = std::min(min_edge, (uv - t.uv[0]).norm());
            }
          }
          t.bit_px = min_edge < 1e300 ? min_edge / bits_per_edge : 0.0;
        } else {
          double min_edge = 1e300;
          for (int c = 0; c < 4; ++c)
            min_edge = std::min(min_edge, (t.uv[(c + 1) % 4] - t.uv[c]).norm());
          t.bit_px = min_edge / bits_per_edge;
        }
      }
      for (int c = num_corners; c < 4; ++c) {  // a point target repeats its corner
        t.X[c] = t.X[0];
        t.uv[c] = t.uv[0];
        t.projected[c] = t.projected[0];
        t.in_image[c] = t.in_image[0];
      }
      bool occluded = false;
      for (int c = 0; c < num_corners && !occluded; ++c) {
        for (int o = 0; o < static_cast<int>(occluders.size()) && !occluded; ++o) {
          occluded = o != bi && Blocks(occluders[o], centre, t.X[c]);
        }
      }
      if (behind) {
        t.status = TagStatus::kBehind;
      } else if (!facing) {
        t.status = TagStatus::kBackFacing;
      } else if (failed || !any_in) {
        t.status = TagStatus::kOutside;
      } else if (occluded) {
        t.status = TagStatus::kOccluded;
      } else if (!all_inner) {
        t.status = TagStatus::kBorder;
      } else if (t.view_angle > max_angle) {
        t.status = TagStatus::kGrazing;
      } else if (t.bit_px < options.min_bit_px) {
        t.status = TagStatus::kSmall;
      } else {
        t.status = TagStatus::kVisible;
      }
      out.push_back(t);
    }
  }
  return out;
}

void ShotStats::Add(const ShotStats& o) {
  const double sq =
      rms_error_px * rms_error_px * corners_kept + o.rms_error_px * o.rms_error_px * o.corners_kept;
  expected += o.expected;
  found += o.found;
  missed += o.missed;
  unrefined += o.unrefined;
  mismatched += o.mismatched;
  skipped_border += o.skipped_border;
  skipped_grazing += o.skipped_grazing;
  skipped_small += o.skipped_small;
  skipped_occluded += o.skipped_occluded;
  dropped_skipped += o.dropped_skipped;
  unknown += o.unknown;
  duplicate += o.duplicate;
  corners_kept += o.corners_kept;
  rms_error_px = corners_kept > 0 ? std::sqrt(sq / corners_kept) : 0.0;
  max_error_px = std::max(max_error_px, o.max_error_px);
}

std::vector<MatchedTag> MatchDetections(const std::vector<detect::TagDetection>& detections,
                                        const std::vector<ExpectedTag>& expected,
                                        const MatchOptions& options, ShotStats* stats) {
  const std::string shot = stats->shot;
  *stats = ShotStats();
  stats->shot = shot;
  std::map<std::pair<std::string, int>, int> index;
  for (int i = 0; i < static_cast<int>(expected.size()); ++i) {
    const ExpectedTag& t = expected[i];
    index[{t.family, t.id}] = i;
    switch (t.status) {
      case TagStatus::kVisible:
        ++stats->expected;
        break;
      case TagStatus::kBorder:
        ++stats->skipped_border;
        break;
      case TagStatus::kGrazing:
        ++stats->skipped_grazing;
        break;
      case TagStatus::kSmall:
        ++stats->skipped_small;
        break;
      case TagStatus::kOccluded:
        ++stats->skipped_occluded;
        break;
      default:
        break;
    }
  }
  std::vector<bool> seen(expected.size(), false);
  std::vector<MatchedTag> out;
  double sum_sq = 0;
  for (const detect::TagDetection& det : detections) {
    const auto it = index.find({det.family, det.id});
    if (it == index.end()) {
      ++stats->unknown;
      continue;
    }
    const ExpectedTag& t = expected[it->second];
    if (t.status != TagStatus::kVisible) {
      ++stats->dropped_skipped;
      continue;
    }
    if (seen[it->second]) {
      ++stats->duplicate;
      continue;
    }
    seen[it->second] = true;
    if (options.require_refined && !det.refined()) {
      ++stats->unrefined;
      continue;
    }
    double worst = 0, sq = 0;
    for (int c = 0; c < t.corners; ++c) {
      const double e = (det.corners[c] - t.uv[c]).norm();
      worst = std::max(worst, e);
      sq += e * e;
    }
    if (worst > options.max_corner_error_px) {
      ++stats->mismatched;
      continue;
    }
    MatchedTag m;
    m.id = t.id;
    m.corners = t.corners;
    m.X = t.X;
    m.uv = det.corners;
    out.push_back(m);
    ++stats->found;
    stats->corners_kept += t.corners;
    sum_sq += sq;
    stats->max_error_px = std::max(stats->max_error_px, worst);
  }
  stats->missed = stats->expected - stats->found - stats->unrefined - stats->mismatched;
  stats->rms_error_px = stats->corners_kept > 0 ? std::sqrt(sum_sq / stats->corners_kept) : 0.0;
  return out;
}

}  // namespace rtscalib::render

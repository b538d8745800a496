#include "libcalib/model/focus.h"

#include <map>
#include <string>
#include <tuple>

#include "libcalib/model/instrument.h"
#include "libcalib/model/kinematics.h"
#include "libcalib/model/observations.h"
#include "libcalib/model/targets.h"

namespace rtscalib {

std::vector<double> PhotoFocusDistances(const InstrumentModel& model,
                                        const std::vector<PixelObservation>& pixels,
                                        const TargetScene* targets, bool use_given) {
  // The photos as the fit groups them: one per (shot, zoom, phi, theta).
  using Key = std::tuple<std::string, int, double, double>;
  struct Photo {
    double given = 0;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int count = 0;
  };
  std::map<Key, Photo> photos;
  for (const PixelObservation& p : pixels) {
    Photo& photo = photos[Key{p.shot, p.zoom, p.phi, p.theta}];
    if (use_given && p.focus_distance > 0) photo.given = p.focus_distance;
    Eigen::Vector3d x = p.X;
    bool placed = p.X_known;
    if (!placed && p.corner >= 0 && p.corner <= 3) {
      if (const EstimatedBoard* b = model.BoardOf(p.target, p.placement, p.zoom)) {
        x = b->pose.ToRigid() * b->board.CornersInBoard(p.target - b->board.first_id)[p.corner];
        placed = true;
      } else if (targets) {
        for (const TagBoard& tb : targets->boards) {
          if (!tb.HasId(p.target) || !tb.pose_known) continue;
          x = tb.ref_from_board * tb.CornersInBoard(p.target - tb.first_id)[p.corner];
          placed = true;
          break;
        }
      }
    }
    if (!placed) continue;
    photo.sum += x;
    ++photo.count;
  }
  std::map<Key, double> distance;
  for (const auto& [key, photo] : photos) {
    double d = photo.given;
    const int zoom = std::get<1>(key);
    if (d <= 0 && photo.count > 0 && zoom >= 0 && zoom < model.NumZooms()) {
      const Eigen::Vector3d centre =
          RefFromCam(model, zoom, std::get<2>(key), std::get<3>(key)).translation;
      d = (photo.sum / photo.count - centre).norm();
    }
    distance[key] = d;
  }
  std::vector<double> out;
  out.reserve(pixels.size());
  for (const PixelObservation& p : pixels) out.push_back(distance[Key{p.shot, p.zoom, p.phi, p.theta}]);
  return out;
}

std::vector<double> PredictionFocusDistances(const InstrumentModel& model,
                                             const std::vector<PixelObservation>& pixels,
                                             const TargetScene* targets) {
  if (!model.effects.Has(Effect::kFocus)) return std::vector<double>(pixels.size(), 0.0);
  return PhotoFocusDistances(model, pixels, targets);
}

}  // namespace rtscalib

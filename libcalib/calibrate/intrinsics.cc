#include "libcalib/calibrate/intrinsics.h"

#include <algorithm>
#include <set>

namespace rtscalib {

bool CamDataSpanImage(const Observations& obs, const InstrumentModel& model, int zoom) {
  if (zoom >= model.NumZooms()) return false;
  double umin = 1e300, umax = -1e300, vmin = 1e300, vmax = -1e300;
  auto add = [&](double u, double v) {
    umin = std::min(umin, u);
    umax = std::max(umax, u);
    vmin = std::min(vmin, v);
    vmax = std::max(vmax, v);
  };
  for (const Record& r : obs.records) {
    if (r.tool == Tool::kCam && r.zoom == zoom) add(r.u, r.v);
  }
  for (const PixelObservation& p : obs.pixels) {
    if (p.zoom == zoom) add(p.uv.x(), p.uv.y());
  }
  const CameraTool& c = model.cams[zoom];
  return umax - umin > 0.25 * c.width && vmax - vmin > 0.25 * c.height;
}

std::set<int> ZoomsInData(const Observations& obs) {
  std::set<int> z;
  for (const Record& r : obs.records) {
    if (r.tool == Tool::kCam) z.insert(r.zoom);
  }
  for (const PixelObservation& p : obs.pixels) z.insert(p.zoom);
  return z;
}

bool FitIntrinsics(IntrinsicsMode mode, const Observations& obs, const InstrumentModel& start) {
  switch (mode) {
    case IntrinsicsMode::kFit:
      return true;
    case IntrinsicsMode::kFixed:
      return false;
    case IntrinsicsMode::kAuto:
      break;
  }
  const std::set<int> zooms = ZoomsInData(obs);
  bool span = true;
  for (int z : zooms) span = span && CamDataSpanImage(obs, start, z);
  return span && !zooms.empty();
}

bool FitIntrinsicsOnReducedSet(bool whole, const Observations& reduced,
                               const InstrumentModel& start) {
  return whole && CamDataSpanImage(reduced, start, 0);
}

}  // namespace rtscalib

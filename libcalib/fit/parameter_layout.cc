#include "libcalib/fit/parameter_layout.h"

#include <ceres/manifold.h>

#include "libcalib/fit/manifolds.h"

namespace rtscalib {

std::vector<LayoutBlock> ParameterLayout(const InstrumentModel& m) {
  std::vector<LayoutBlock> out;
  int offset = 0;
  auto add = [&](const std::string& name, int size, int ambient, const std::string& unit,
                 LayoutTangent tangent, int use, std::function<double*(InstrumentModel&)> data) {
    LayoutBlock b;
    b.name = name;
    b.offset = offset;
    b.size = size;
    b.ambient = ambient;
    b.unit = unit;
    b.tangent = tangent;
    b.use = use;
    b.const_data = [data](const InstrumentModel& x) {
      return static_cast<const double*>(data(const_cast<InstrumentModel&>(x)));
    };
    b.data = std::move(data);
    out.push_back(std::move(b));
    offset += size;
  };
  add("base.rotation", 3, 4, "rad (half angle)", LayoutTangent::kQuaternion, kLayoutShared,
      [](InstrumentModel& x) { return x.base.q.data(); });
  add("base.t", 3, 3, "m", LayoutTangent::kEuclidean, kLayoutShared,
      [](InstrumentModel& x) { return x.base.t.data(); });
  if (m.kinematics == Kinematics::kDh) {
    for (int k = 0; k < 2; ++k) {
      add("link" + std::to_string(k + 1), 4, 4, "m, rad, rad, m", LayoutTangent::kEuclidean,
          kLayoutShared, [k](InstrumentModel& x) { return x.links[k].p.data(); });
    }
  }
  add("edm.rotation", 2, 4, "rad", LayoutTangent::kNoRoll, kLayoutEdmOnly,
      [](InstrumentModel& x) { return x.edm.q.data(); });
  add("edm.t", 3, 3, "m", LayoutTangent::kEuclidean, kLayoutEdmOnly,
      [](InstrumentModel& x) { return x.edm.t.data(); });
  for (Effect e : m.effects.List()) {
    if (!IsKinematic(e)) continue;
    const int n = Info(e).num_params;
    add(Info(e).name, n, n, "SI (rad, m, 1)", LayoutTangent::kEuclidean, kLayoutShared,
        [e](InstrumentModel& x) { return x.EffectValue(e).data(); });
  }
  for (int z = 0; z < m.NumZooms(); ++z) {
    const std::string c = "cam[" + std::to_string(z) + "]";
    add(c + ".rotation", 3, 4, "rad (half angle)", LayoutTangent::kQuaternion, z,
        [z](InstrumentModel& x) { return x.cams[z].flange_from_cam.q.data(); });
    add(c + ".t", 3, 3, "m", LayoutTangent::kEuclidean, z,
        [z](InstrumentModel& x) { return x.cams[z].flange_from_cam.t.data(); });
    add(c + ".intrinsics", kNumIntrinsics, kNumIntrinsics, "px", LayoutTangent::kEuclidean, z,
        [z](InstrumentModel& x) { return x.cams[z].intrinsics.data(); });
    add(c + ".distortion", kNumDistortion, kNumDistortion, "1 (OpenCV order)",
        LayoutTangent::kEuclidean, z,
        [z](InstrumentModel& x) { return x.cams[z].distortion.data(); });
    if (m.effects.Has(Effect::kFocus)) {
      add(c + ".focus", kNumFocus, kNumFocus, "m, px m, px m", LayoutTangent::kEuclidean, z,
          [z](InstrumentModel& x) { return x.cams[z].focus.data(); });
    }
  }
  return out;
}

int LayoutSize(const std::vector<LayoutBlock>& layout) {
  return layout.empty() ? 0 : layout.back().offset + layout.back().size;
}

void LayoutPlus(const LayoutBlock& b, const double* delta, InstrumentModel* model) {
  double* p = b.data(*model);
  switch (b.tangent) {
    case LayoutTangent::kEuclidean:
      for (int i = 0; i < b.size; ++i) p[i] += delta[i];
      return;
    case LayoutTangent::kQuaternion: {
      const double q[4] = {p[0], p[1], p[2], p[3]};
      ceres::EigenQuaternionManifold().Plus(q, delta, p);
      return;
    }
    case LayoutTangent::kNoRoll: {
      const double q[4] = {p[0], p[1], p[2], p[3]};
      QuaternionNoRollManifold().Plus(q, delta, p);
      return;
    }
  }
}

}  // namespace rtscalib

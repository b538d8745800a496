#include "libcalib/fit/cost_functions.h"

namespace rtscalib {

BlockLayout LayoutFor(InstrumentModel* model, int zoom) {
  BlockLayout l;
  l.kinematics = model->kinematics;
  l.edm_cyclic_unit_length = model->edm_cyclic_unit_length;
  auto add = [&l](double* p, int size) {
    l.blocks.push_back(p);
    l.sizes.push_back(size);
    return static_cast<int>(l.blocks.size()) - 1;
  };
  l.base_q = add(model->base.q.data(), 4);
  l.base_t = add(model->base.t.data(), 3);
  if (model->kinematics == Kinematics::kDh) {
    l.link0 = add(model->links[0].p.data(), 4);
    l.link1 = add(model->links[1].p.data(), 4);
  }
  PoseBlock& tool = zoom < 0 ? model->edm : model->cams.at(zoom).flange_from_cam;
  l.tool_q = add(tool.q.data(), 4);
  l.tool_t = add(tool.t.data(), 3);
  if (zoom >= 0) {
    l.intrinsics = add(model->cams[zoom].intrinsics.data(), kNumIntrinsics);
    l.distortion = add(model->cams[zoom].distortion.data(), kNumDistortion);
    if (model->effects.Has(Effect::kFocus)) l.focus = add(model->cams[zoom].focus.data(), kNumFocus);
  }
  for (Effect e : model->effects.List()) {
    if (!IsKinematic(e)) continue;
    // EDM effects only touch EDM rows.
    if (Info(e).kind == EffectKind::kEdm && zoom >= 0) continue;
    l.effect[static_cast<int>(e)] = add(model->EffectValue(e).data(), Info(e).num_params);
  }
  return l;
}

template ceres::CostFunction* MakeCost<RecordGroupResidual>(RecordGroupResidual*, int, int);
template ceres::CostFunction* MakeCost<ShotResidual>(ShotResidual*, int, int);

}  // namespace rtscalib

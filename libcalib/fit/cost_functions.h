// Residuals of the refinement, all created through one helper (`MakeCost`).
//
// Every functor evaluates the templated kinematics (libcalib/model/kinematics.h)
// on a `BlockLayout`: the list of parameter blocks one observation touches,
// each a pointer into the InstrumentModel's own memory, in this order:
//   base_q(4) base_t(3) [link0(4) link1(4) if dh] tool_q(4) tool_t(3)
//   [intrinsics(4) distortion(14) for camera tools] [one block per enabled
//   kinematic effect, in catalogue order]
// Residuals are whitened by the observation group's sigma.
//   EdmPointResidual:   (F_EDM(phi, theta, d) - x) / sigma           3 values [1]
//   CamPointResidual:   (F_CAM(phi, theta, u, v, d) - x) / sigma      3 values [1]
//   ReprojectionResidual: (project(X) - uv) / sigma                   2 values [1]
#pragma once

#include <ceres/dynamic_autodiff_cost_function.h>

#include <memory>
#include <vector>

#include "libcalib/model/instrument.h"
#include "libcalib/model/kinematics.h"
#include "libcalib/model/observations.h"

namespace rtscalib {

// Jet width of the dynamic autodiff: every residual touches at most
// 7 + 8 + 7 + 4 + 14 + 16 = 56 parameters, so one pass suffices.
constexpr int kCostStride = 56;

struct BlockLayout {
  Kinematics kinematics = Kinematics::kDh;
  std::vector<double*> blocks;
  std::vector<int> sizes;
  int base_q = -1, base_t = -1, link0 = -1, link1 = -1, tool_q = -1, tool_t = -1;
  int intrinsics = -1, distortion = -1;
  int effect[kNumKinematicEffects];
  double edm_cyclic_unit_length = 1.5;

  BlockLayout() { std::fill(std::begin(effect), std::end(effect), -1); }

  template <typename T>
  ModelView<T> View(T const* const* p) const {
    ModelView<T> v;
    v.kinematics = kinematics;
    v.base_q = p[base_q];
    v.base_t = p[base_t];
    if (link0 >= 0) {
      v.link[0] = p[link0];
      v.link[1] = p[link1];
    }
    for (int e = 0; e < kNumKinematicEffects; ++e) {
      if (effect[e] >= 0) v.effect[e] = p[effect[e]];
    }
    v.edm_cyclic_unit_length = edm_cyclic_unit_length;
    return v;
  }
};

// Layout for an EDM observation or a camera observation at `zoom` (-1 = EDM).
BlockLayout LayoutFor(InstrumentModel* model, int zoom);

struct EdmPointResidual {
  BlockLayout layout;
  double phi, theta, d;
  Eigen::Vector3d x;
  double inv_sigma;

  template <typename T>
  bool operator()(T const* const* p, T* r) const {
    const ModelView<T> view = layout.View(p);
    const Vec3<T> calc =
        EdmPoint(view, p[layout.tool_q], p[layout.tool_t], T(phi), T(theta), T(d));
    for (int i = 0; i < 3; ++i) r[i] = (calc[i] - T(x[i])) * T(inv_sigma);
    return true;
  }
};

struct CamPointResidual {
  BlockLayout layout;
  double phi, theta, u, v, d;
  Eigen::Vector3d x;
  double inv_sigma;

  template <typename T>
  bool operator()(T const* const* p, T* r) const {
    const ModelView<T> view = layout.View(p);
    const T pixel[2] = {T(u), T(v)};
    Vec3<T> calc;
    if (!CamPoint(view, p[layout.tool_q], p[layout.tool_t], p[layout.intrinsics],
                  p[layout.distortion], T(phi), T(theta), pixel, T(d), &calc)) {
      return false;
    }
    for (int i = 0; i < 3; ++i) r[i] = (calc[i] - T(x[i])) * T(inv_sigma);
    return true;
  }
};

struct ReprojectionResidual {
  BlockLayout layout;
  double phi, theta;
  Eigen::Vector3d X;
  Eigen::Vector2d uv;
  double inv_sigma;

  template <typename T>
  bool operator()(T const* const* p, T* r) const {
    const ModelView<T> view = layout.View(p);
    T pixel[2];
    if (!ProjectPoint(view, p[layout.tool_q], p[layout.tool_t], p[layout.intrinsics],
                      p[layout.distortion], T(phi), T(theta), Vec3<T>(T(X[0]), T(X[1]), T(X[2])),
                      pixel)) {
      return false;  // behind the camera: the solver must reject the step
    }
    r[0] = (pixel[0] - T(uv[0])) * T(inv_sigma);
    r[1] = (pixel[1] - T(uv[1])) * T(inv_sigma);
    return true;
  }
};

// The one helper that turns a functor into a Ceres cost function over its layout.
template <typename Functor, int kNumResiduals>
ceres::CostFunction* MakeCost(Functor* functor) {
  auto* cost = new ceres::DynamicAutoDiffCostFunction<Functor, kCostStride>(functor);
  for (int size : functor->layout.sizes) cost->AddParameterBlock(size);
  cost->SetNumResiduals(kNumResiduals);
  return cost;
}

ceres::CostFunction* MakeRecordCost(const Record& r, InstrumentModel* model, double sigma);
ceres::CostFunction* MakePixelCost(const PixelObservation& p, InstrumentModel* model, double sigma);

}  // namespace rtscalib

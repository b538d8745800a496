// Residuals of the refinement, all created through one helper (`MakeCost`).
//
// Every functor evaluates the templated kinematics (libcalib/model/kinematics.h)
// on a `BlockLayout`: the list of parameter blocks one group of observations
// touches, each a pointer into the InstrumentModel's own memory, in this order:
//   base_q(4) base_t(3) [link0(4) link1(4) if dh] tool_q(4) tool_t(3)
//   [intrinsics(4) distortion(14) for camera tools] [one block per enabled
//   kinematic effect, in catalogue order]
// Observations that share a pointing share one residual block, so that the
// chain ref_from_tool(phi, theta) is differentiated once per pointing, not
// once per point (with a robust loss every observation gets its own block,
// because the loss acts per block). Residuals are whitened by their sigma:
//   records of one pose and tool:  (F_EDM / F_CAM - x) / sigma     3 per row
//   pixels of one shot:            (project(X) - uv) / sigma        2 per point
#pragma once

#include <ceres/dynamic_autodiff_cost_function.h>

#include <memory>
#include <vector>

#include "libcalib/model/instrument.h"
#include "libcalib/model/kinematics.h"
#include "libcalib/model/observations.h"

namespace rtscalib {

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

// Layout for EDM observations (zoom = -1) or camera observations at `zoom`.
BlockLayout LayoutFor(InstrumentModel* model, int zoom);

// Records of one pointing and one tool (the EDM, or the camera at one zoom).
struct RecordGroupResidual {
  struct Row {
    double u = 0, v = 0, d = 0;
    Eigen::Vector3d x;
    double inv_sigma = 1;
  };
  BlockLayout layout;
  bool edm = true;
  double phi = 0, theta = 0;
  std::vector<Row> rows;

  template <typename T>
  bool operator()(T const* const* p, T* r) const {
    const ModelView<T> view = layout.View(p);
    const RigidT<T> ref_from_tool =
        RefFromFlange(view, T(phi), T(theta)) * PoseFromBlocks(p[layout.tool_q], p[layout.tool_t]);
    for (size_t k = 0; k < rows.size(); ++k) {
      const Row& row = rows[k];
      Vec3<T> local;
      if (edm) {
        local = Vec3<T>(T(0), T(0), TrueDistance(view, T(row.d)));  // Klug Eq. 76
      } else {
        const T pixel[2] = {T(row.u), T(row.v)};
        T ray[3];
        if (!camera::PixelToRay(p[layout.intrinsics], p[layout.distortion], pixel, ray)) {
          return false;
        }
        local = Vec3<T>(ray[0], ray[1], ray[2]) * T(row.d);  // SPEC 2: ray LENGTH d
      }
      const Vec3<T> calc = ref_from_tool * local;
      for (int i = 0; i < 3; ++i) r[3 * k + i] = (calc[i] - T(row.x[i])) * T(row.inv_sigma);
    }
    return true;
  }
};

// Image observations of one shot (one pointing, one zoom).
struct ShotResidual {
  struct Point {
    Eigen::Vector3d X;
    Eigen::Vector2d uv;
  };
  BlockLayout layout;
  double phi = 0, theta = 0;
  double inv_sigma = 1;
  std::vector<Point> points;

  template <typename T>
  bool operator()(T const* const* p, T* r) const {
    const ModelView<T> view = layout.View(p);
    const RigidT<T> ref_from_cam =
        RefFromFlange(view, T(phi), T(theta)) * PoseFromBlocks(p[layout.tool_q], p[layout.tool_t]);
    const Mat3<T> cam_from_ref_R = ref_from_cam.R.transpose();
    for (size_t k = 0; k < points.size(); ++k) {
      const Vec3<T> x_cam = cam_from_ref_R * (points[k].X.cast<T>() - ref_from_cam.t);
      T pixel[2];
      if (!camera::ProjectToPixel(p[layout.intrinsics], p[layout.distortion], x_cam.data(), pixel)) {
        return false;  // behind the camera: the solver must reject the step
      }
      r[2 * k + 0] = (pixel[0] - T(points[k].uv[0])) * T(inv_sigma);
      r[2 * k + 1] = (pixel[1] - T(points[k].uv[1])) * T(inv_sigma);
    }
    return true;
  }
};

// The one helper that turns a functor into a Ceres cost function over its
// layout. `active` = number of parameters in non-constant blocks: the jet
// width is chosen to cover them in one pass (DynamicAutoDiffCostFunction
// skips constant blocks).
template <int kStride, typename Functor>
ceres::CostFunction* MakeCostWithStride(Functor* functor, int num_residuals) {
  auto* cost = new ceres::DynamicAutoDiffCostFunction<Functor, kStride>(functor);
  for (int size : functor->layout.sizes) cost->AddParameterBlock(size);
  cost->SetNumResiduals(num_residuals);
  return cost;
}

template <typename Functor>
ceres::CostFunction* MakeCost(Functor* functor, int num_residuals, int active) {
  if (active <= 12) return MakeCostWithStride<12>(functor, num_residuals);
  if (active <= 20) return MakeCostWithStride<20>(functor, num_residuals);
  if (active <= 28) return MakeCostWithStride<28>(functor, num_residuals);
  if (active <= 40) return MakeCostWithStride<40>(functor, num_residuals);
  return MakeCostWithStride<56>(functor, num_residuals);
}

}  // namespace rtscalib

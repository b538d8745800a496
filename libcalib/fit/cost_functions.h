// Residuals of the refinement, all created through one helper (`MakeCost`).
//
// Every functor evaluates the templated kinematics (libcalib/model/kinematics.h)
// on a `BlockLayout`: the list of parameter blocks one group of observations
// touches, each a pointer into the InstrumentModel's own memory, in this order:
//   base_q(4) base_t(3) [link0(4) link1(4) if dh] tool_q(4) tool_t(3)
//   [intrinsics(4) distortion(14) for camera tools] [focus(3) for camera tools
//   when the model has the focus effect] [one block per enabled kinematic
//   effect, in catalogue order] [board_q(4) board_t(3) per board of
//   unknown pose the group sees, and its warp(2) when the model has
//   board_warp] [point(3) per point of unknown position]
// Observations that share a pointing share one residual block, so that the
// chain ref_from_tool(phi, theta) is differentiated once per pointing, not
// once per point (with a robust loss every observation gets its own block,
// because the loss acts per block). Residuals are whitened by their sigma:
//   records of one pose and tool:  (F_EDM / F_CAM - x) / sigma     3 per row
//   pixels of one shot:            (project(X) - uv) / sigma        2 per point
// SPEC 7: a record of a named point uses that point's block as x; a pixel of
// a board of unknown pose uses X = ref_from_board * corner_in_board, with
// ref_from_board from that board's blocks; with a warp block (board_warp,
// TagBoard::warp) the corner leaves the board's plane by
// wx (1 - xr^2) + wy (1 - yr^2) along the board's z.
// SPEC 4.1 (focus block present): a camera record projects with the
// intrinsics focused at D = its ray length d, a shot with those focused at
// the photo's D (libcalib/model/focus.h): its focus_distance when given, else
// the distance from the camera centre to the centroid of the photo's points
// as the blocks place them (a function of the chain and the boards' poses,
// differentiated like everything else).
#pragma once

#include <ceres/dynamic_autodiff_cost_function.h>
#include <ceres/jet.h>

#include <memory>
#include <type_traits>
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
  int focus = -1;  // the zoom's focus block (SPEC 4.1), when the model has the effect
  int effect[kNumKinematicEffects];
  double edm_cyclic_unit_length = 1.5;
  // Layout indices of the (q, t) blocks of boards of unknown pose and of the
  // points of unknown position (SPEC 7), in the order the functor refers to;
  // per board, the index of its warp block (board_warp), -1 without one.
  std::vector<std::pair<int, int>> boards;
  std::vector<int> board_warps;
  std::vector<int> points;

  BlockLayout() { std::fill(std::begin(effect), std::end(effect), -1); }
  // The warp block of board slot `board`, -1 without one.
  int WarpBlock(int board) const {
    return board < static_cast<int>(board_warps.size()) ? board_warps[board] : -1;
  }

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
  // Appends a block; returns its layout index.
  int Add(double* p, int size) {
    blocks.push_back(p);
    sizes.push_back(size);
    return static_cast<int>(blocks.size()) - 1;
  }
};

// Layout for EDM observations (zoom = -1) or camera observations at `zoom`.
BlockLayout LayoutFor(InstrumentModel* model, int zoom);

namespace internal {

// Is T a ceres::Jet (the autodiff pass) or a plain double?
template <typename T>
struct IsJet : std::false_type {};
template <typename S, int N>
struct IsJet<ceres::Jet<S, N>> : std::true_type {
  static constexpr int kSize = N;
};

// The projection's own variables (kProjectionVars, opencv_model.h): camera
// point (3), intrinsics (4), distortion (14). ShotResidual forms the tilt
// matrix once per photo in these jets (LocalCamera seeds the intrinsics and
// distortion), which gives its derivatives with respect to the tilt angles,
// and takes each point's projection and Jacobian in the same variables from
// the camera (ProjectWithJacobian) before chaining them onto the caller's
// wide jets.
using LocalJet = ceres::Jet<double, kProjectionVars>;

// Where a parameter jet's derivative lives: DynamicAutoDiffCostFunction seeds
// each parameter with a unit vector (or zero when its block is constant or
// not in this pass). `slot` = index of the 1, -1 for zero, -2 for anything
// else (then the full product is taken).
template <int N>
int SeedSlot(const ceres::Jet<double, N>& j) {
  int slot = -1;
  for (int k = 0; k < N; ++k) {
    if (j.v[k] == 0.0) continue;
    if (j.v[k] != 1.0 || slot != -1) return -2;
    slot = k;
  }
  return slot;
}

// The intrinsics and distortion of the caller's wide jets (width N) as
// variables first .. first + 17 of a narrow local jet type J, and back: a
// value computed in J carries its derivatives with respect to them, and
// Chain() turns those into the caller's derivatives,
//   d out = sum_i (d value / d param_i) d param_i.
// Parameters are seeded unit vectors (one slot each) or zero, so the sum is
// a scatter, except for a parameter seeded otherwise (slot -2).
template <typename J, int N>
struct LocalCamera {
  J intrinsics[kNumIntrinsics], dist[kNumDistortion];
  const ceres::Jet<double, N>* wide_intrinsics;
  const ceres::Jet<double, N>* wide_dist;
  int first;
  int slot[kNumIntrinsics + kNumDistortion];

  LocalCamera(const ceres::Jet<double, N>* intrinsics_in, const ceres::Jet<double, N>* dist_in,
              int first_variable)
      : wide_intrinsics(intrinsics_in), wide_dist(dist_in), first(first_variable) {
    for (int i = 0; i < kNumIntrinsics; ++i) {
      intrinsics[i] = J(intrinsics_in[i].a, first + i);
      slot[i] = SeedSlot<N>(intrinsics_in[i]);
    }
    for (int i = 0; i < kNumDistortion; ++i) {
      dist[i] = J(dist_in[i].a, first + kNumIntrinsics + i);
      slot[kNumIntrinsics + i] = SeedSlot<N>(dist_in[i]);
    }
  }

  // Adds the part of `local`'s derivative that runs through the intrinsics
  // and distortion to `out`.
  void Chain(const J& local, ceres::Jet<double, N>* out) const {
    for (int i = 0; i < kNumIntrinsics + kNumDistortion; ++i) {
      const double d = local.v[first + i];
      if (slot[i] >= 0) {
        out->v[slot[i]] += d;
      } else if (slot[i] == -2) {
        out->v += d * (i < kNumIntrinsics ? wide_intrinsics[i].v : wide_dist[i - kNumIntrinsics].v);
      }
    }
  }
};

// The back-projection's own variables: intrinsics (4) and distortion (14).
// A camera record's ray is computed in these 18-wide jets (undistortion
// included) and chained onto the caller's wide jets (RecordGroupResidual).
constexpr int kRayVars = kNumIntrinsics + kNumDistortion;
using RayJet = ceres::Jet<double, kRayVars>;

}  // namespace internal

// Records of one pointing and one tool (the EDM, or the camera at one zoom).
struct RecordGroupResidual {
  struct Row {
    double u = 0, v = 0, d = 0;
    Eigen::Vector3d x;
    double inv_sigma = 1;
    int point = -1;  // >= 0: x is layout.points[point]'s block (x above unused)
  };
  BlockLayout layout;
  bool edm = true;
  double phi = 0, theta = 0;
  std::vector<Row> rows;

  // The camera-frame unit ray of a camera row's pixel. With jets, the
  // undistortion (an iteration and an implicit-function step,
  // opencv_model.h) runs in the 18-wide local jets of the intrinsics and
  // distortion, and only the ray is chained onto the caller's wide jets: the
  // same values, at less than half the cost of undistorting in the wide
  // jets.
  template <typename T>
  bool Ray(T const* const* p, const Row& row, T* ray) const {
    // SPEC 4.1: the camera of a cam record is focused at its ray length.
    T intrinsics[kNumIntrinsics];
    if (!FocusedIntrinsics(p[layout.intrinsics], layout.focus >= 0 ? p[layout.focus] : nullptr,
                           T(row.d), intrinsics)) {
      return false;
    }
    const T* dist = p[layout.distortion];
    if constexpr (!internal::IsJet<T>::value) {
      const T pixel[2] = {row.u, row.v};
      return PixelToRay(intrinsics, dist, pixel, ray);
    } else {
      using internal::RayJet;
      const internal::LocalCamera<RayJet, internal::IsJet<T>::kSize> cam(intrinsics, dist, 0);
      const RayJet pixel[2] = {RayJet(row.u), RayJet(row.v)};
      RayJet local[3];
      if (!PixelToRay(cam.intrinsics, cam.dist, pixel, local)) return false;
      for (int c = 0; c < 3; ++c) {
        ray[c] = T(local[c].a);
        cam.Chain(local[c], &ray[c]);
      }
      return true;
    }
  }

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
        T ray[3];
        if (!Ray(p, row, ray)) return false;
        local = Vec3<T>(ray[0], ray[1], ray[2]) * T(row.d);  // SPEC 2: ray LENGTH d
      }
      const Vec3<T> calc = ref_from_tool * local;
      if (row.point >= 0) {
        const T* x = p[layout.points[row.point]];
        for (int i = 0; i < 3; ++i) r[3 * k + i] = (calc[i] - x[i]) * T(row.inv_sigma);
      } else {
        for (int i = 0; i < 3; ++i) r[3 * k + i] = (calc[i] - T(row.x[i])) * T(row.inv_sigma);
      }
    }
    return true;
  }
};

// Image observations of one shot (one pointing, one zoom).
//
// Speed (docs/refinement.md; joint_refine_benchmark measures it): the chain
// ref_from_cam is evaluated once per shot in the caller's jets (width ~40),
// and so is cam_from_board for each board the shot sees. Per point, only
// x_cam = cam_from_frame * X (X a plain constant) is formed in those wide
// jets; the projection (distortion, tilt, intrinsics) comes with its 2 x 21
// Jacobian over (x_cam, intrinsics, distortion) from the camera
// (ProjectWithJacobian, written out there: autodiff in 21-wide local jets
// makes a joint refinement markedly slower, joint_refine_benchmark), and
// that Jacobian is chained onto the wide jets:
//   d pixel = J_pixel_wrt_xcam d x_cam + J_pixel_wrt_intrinsics d intrinsics
//             + J_pixel_wrt_distortion d distortion.
// Intrinsics and distortion are seeded unit vectors, so their part is a
// scatter into one slot each. The values are the camera's formula's.
struct ShotResidual {
  struct Point {
    Eigen::Vector3d X;  // reference frame, or the flat board's frame when board >= 0
    Eigen::Vector2d uv;
    int board = -1;  // >= 0: X is a corner of layout.boards[board]
    // The warp's shape at X (TagBoard::WarpShape) when the board has a warp block.
    Eigen::Vector2d warp_shape = Eigen::Vector2d::Zero();
  };
  // The photo's points summed for its centroid (SPEC 4.1): known points
  // (board -1, reference frame) or the corners of one board of unknown pose
  // (its board frame), `count` of them: every point of the photo (its
  // residual block).
  struct FocusTerm {
    int board = -1;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    Eigen::Vector2d warp_shape_sum = Eigen::Vector2d::Zero();  // of the points' warp shapes
    int count = 0;
  };
  BlockLayout layout;
  double phi = 0, theta = 0;
  double inv_sigma = 1;
  std::vector<Point> points;
  double focus_distance = 0;  // [m] the photo's D when given (focus_distance column); 0: centroid
  std::vector<FocusTerm> focus_terms;
  int focus_count = 0;

  // cam_from_frame * x for a constant point x: products of the caller's
  // jets with plain numbers only.
  template <typename T>
  static Vec3<T> Apply(const RigidT<T>& cam_from_frame, const Eigen::Vector3d& x) {
    Vec3<T> out;
    for (int i = 0; i < 3; ++i) {
      out[i] = cam_from_frame.R(i, 0) * x[0] + cam_from_frame.R(i, 1) * x[1] +
               cam_from_frame.R(i, 2) * x[2] + cam_from_frame.t[i];
    }
    return out;
  }

  // The warp's offset along the board's z of a point of board slot `board`
  // with warp shape `shape` (0 without a warp block).
  template <typename T>
  T WarpOffset(T const* const* p, int board, const Eigen::Vector2d& shape) const {
    const int w = layout.WarpBlock(board);
    if (w < 0) return T(0);
    return p[w][0] * shape[0] + p[w][1] * shape[1];
  }

  // The intrinsics of this photo: focused at its D when the layout has a
  // focus block (SPEC 4.1), the block's own otherwise.
  template <typename T>
  bool PhotoIntrinsics(T const* const* p, const std::vector<RigidT<T>>& boards,
                       const RigidT<T>& ref_from_cam, T* k) const {
    const T* intrinsics = p[layout.intrinsics];
    if (layout.focus < 0) {
      for (int i = 0; i < kNumIntrinsics; ++i) k[i] = intrinsics[i];
      return true;
    }
    T distance(focus_distance);
    if (!(focus_distance > 0)) {
      if (focus_count <= 0) return false;
      Vec3<T> sum(T(0), T(0), T(0));
      for (const FocusTerm& f : focus_terms) {
        if (f.board < 0) {
          sum += f.sum.cast<T>();
        } else {
          Vec3<T> in_board = f.sum.cast<T>();
          in_board[2] += WarpOffset(p, f.board, f.warp_shape_sum);
          sum += boards[f.board].R * in_board + boards[f.board].t * T(f.count);
        }
      }
      const Vec3<T> from_camera = sum / T(focus_count) - ref_from_cam.t;
      distance = from_camera.norm();
    }
    return FocusedIntrinsics(intrinsics, p[layout.focus], distance, k);
  }

  template <typename T>
  bool operator()(T const* const* p, T* r) const {
    const ModelView<T> view = layout.View(p);
    const RigidT<T> ref_from_cam =
        RefFromFlange(view, T(phi), T(theta)) * PoseFromBlocks(p[layout.tool_q], p[layout.tool_t]);
    const Mat3<T> cam_from_ref_R = ref_from_cam.R.transpose();
    // cam_from_frame of every frame the points are given in, once per shot:
    // each board's (slot b: cam_from_ref * ref_from_board) and, last, the
    // reference frame's. A point then costs one 3 x 3 product with its
    // constant coordinates, not two rotations in the caller's wide jets.
    std::vector<RigidT<T>> cam_from_frame;
    cam_from_frame.reserve(layout.boards.size() + 1);
    std::vector<RigidT<T>> boards;  // ref_from_board
    boards.reserve(layout.boards.size());
    for (const auto& b : layout.boards) {
      const RigidT<T>& ref_from_board = boards.emplace_back(PoseFromBlocks(p[b.first], p[b.second]));
      cam_from_frame.push_back({cam_from_ref_R * ref_from_board.R,
                                cam_from_ref_R * (ref_from_board.t - ref_from_cam.t)});
    }
    cam_from_frame.push_back({cam_from_ref_R, -(cam_from_ref_R * ref_from_cam.t)});
    // The point in the camera frame: cam_from_frame * X, and for a warped
    // board's corner its offset along the board's z (column 2 of
    // cam_from_board's rotation).
    const auto in_camera = [&](size_t k) {
      const Point& pt = points[k];
      if (pt.board < 0) return Apply(cam_from_frame[layout.boards.size()], pt.X);
      const RigidT<T>& frame = cam_from_frame[pt.board];
      Vec3<T> x = Apply(frame, pt.X);
      if (layout.WarpBlock(pt.board) >= 0) {
        const T dz = WarpOffset(p, pt.board, pt.warp_shape);
        for (int i = 0; i < 3; ++i) x[i] += frame.R(i, 2) * dz;
      }
      return x;
    };
    T intrinsics[kNumIntrinsics];
    if (!PhotoIntrinsics(p, boards, ref_from_cam, intrinsics)) return false;
    const T* dist = p[layout.distortion];
    if constexpr (!internal::IsJet<T>::value) {
      T m[9];
      TiltMatrix(dist[kTauX], dist[kTauY], m);
      for (size_t k = 0; k < points.size(); ++k) {
        const Vec3<T> x_cam = in_camera(k);
        T pixel[2];
        if (!ProjectWithTiltMatrix(intrinsics, dist, m, x_cam.data(), pixel)) {
          return false;  // behind the camera: the solver must reject the step
        }
        r[2 * k + 0] = (pixel[0] - T(points[k].uv[0])) * T(inv_sigma);
        r[2 * k + 1] = (pixel[1] - T(points[k].uv[1])) * T(inv_sigma);
      }
      return true;
    } else {
      using internal::LocalJet;
      // Local jets of intrinsics and distortion (variables 3..20, after the
      // camera point); focused intrinsics carry a full product, not a seed.
      const internal::LocalCamera<LocalJet, internal::IsJet<T>::kSize> cam(intrinsics, dist, 3);
      // The tilt matrix and its derivatives with respect to the tilt angles
      // (local variables 3 + 4 + kTauX and kTauY), once per photo.
      LocalJet tilt[9];
      TiltMatrix(cam.dist[kTauX], cam.dist[kTauY], tilt);
      constexpr int kTauVar = 3 + kNumIntrinsics + kTauX;
      double m[9], dm_dtau[2][9], k_values[kNumIntrinsics], d_values[kNumDistortion];
      for (int i = 0; i < 9; ++i) {
        m[i] = tilt[i].a;
        dm_dtau[0][i] = tilt[i].v[kTauVar];
        dm_dtau[1][i] = tilt[i].v[kTauVar + 1];
      }
      for (int i = 0; i < kNumIntrinsics; ++i) k_values[i] = cam.intrinsics[i].a;
      for (int i = 0; i < kNumDistortion; ++i) d_values[i] = cam.dist[i].a;
      for (size_t k = 0; k < points.size(); ++k) {
        const Vec3<T> x_cam = in_camera(k);
        const double point[3] = {x_cam[0].a, x_cam[1].a, x_cam[2].a};
        double value[2], J[2 * kProjectionVars];
        if (!ProjectWithJacobian(k_values, d_values, m, dm_dtau, point, value, J)) return false;
        for (int c = 0; c < 2; ++c) {
          const double* row = J + c * kProjectionVars;
          LocalJet pixel;
          pixel.a = value[c];
          for (int i = 0; i < kProjectionVars; ++i) pixel.v[i] = row[i];
          T out;
          out.a = value[c];
          out.v = row[0] * x_cam[0].v + row[1] * x_cam[1].v + row[2] * x_cam[2].v;
          cam.Chain(pixel, &out);
          r[2 * k + c] = (out - T(points[k].uv[c])) * T(inv_sigma);
        }
      }
      return true;
    }
  }
};

// The one helper that turns a functor into a Ceres cost function over its
// layout. `active` = number of parameters in non-constant blocks: the jet
// width is chosen to cover them in one pass (DynamicAutoDiffCostFunction
// skips constant blocks). Each width is one more instantiation of every
// residual (about a tenth of this library's compile time); the narrowest is 20
// because no block of the shipped configs has fewer than 14 active
// parameters (paper: 14 to 47; photos and zoom3: 18 to 56).
template <int kStride, typename Functor>
ceres::CostFunction* MakeCostWithStride(Functor* functor, int num_residuals) {
  auto* cost = new ceres::DynamicAutoDiffCostFunction<Functor, kStride>(functor);
  for (int size : functor->layout.sizes) cost->AddParameterBlock(size);
  cost->SetNumResiduals(num_residuals);
  return cost;
}

template <typename Functor>
ceres::CostFunction* MakeCost(Functor* functor, int num_residuals, int active) {
  if (active <= 20) return MakeCostWithStride<20>(functor, num_residuals);
  if (active <= 28) return MakeCostWithStride<28>(functor, num_residuals);
  if (active <= 40) return MakeCostWithStride<40>(functor, num_residuals);
  return MakeCostWithStride<56>(functor, num_residuals);
}

// The two residuals' cost functions at every jet width are compiled once, in
// cost_functions.cc: the autodiff of a residual is most of a file's compile
// time, and every other file that makes one (the tests' gradient checks
// among them) links to these instead of instantiating it again.
extern template ceres::CostFunction* MakeCost<RecordGroupResidual>(RecordGroupResidual*, int, int);
extern template ceres::CostFunction* MakeCost<ShotResidual>(ShotResidual*, int, int);

}  // namespace rtscalib

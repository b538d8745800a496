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

// The projection's own variables: camera point (3), intrinsics (4),
// distortion (14). The intrinsics and distortion are seeded in these
// 21-wide jets (LocalCamera) and the tilt matrix is computed in them once
// per shot; the projection's derivatives are written out in the same
// variables (ProjectWithTiltLocal) and chained onto the caller's wide jets
// (ShotResidual below).
constexpr int kLocalVars = 3 + kNumIntrinsics + kNumDistortion;
using LocalJet = ceres::Jet<double, kLocalVars>;

// ProjectToPixel with the tilt matrix `m` computed once per shot
// (it depends on the distortion block only): the same formula, line for line
// (opencv_model.h). tests/fit/cost_functions_test.cc checks both agree.
template <typename T>
bool ProjectWithTilt(const T* intrinsics, const T* dist, const T* m, const T* point, T* pixel) {
  if (!(point[2] > T(0))) return false;
  const T x = point[0] / point[2];
  const T y = point[1] / point[2];
  T xd, yd;
  DistortNormalized(dist, x, y, &xd, &yd);
  const T xt = m[0] * xd + m[1] * yd + m[2];
  const T yt = m[3] * xd + m[4] * yd + m[5];
  const T zt = m[6] * xd + m[7] * yd + m[8];
  pixel[0] = intrinsics[0] * xt / zt + intrinsics[2];
  pixel[1] = intrinsics[1] * yt / zt + intrinsics[3];
  return true;
}

// ProjectWithTilt in the local variables of ShotResidual, with its 2 x 21
// Jacobian written out instead of carried through 21-wide jets: the
// variables are the camera point (local 0-2, plain numbers here), the
// intrinsics (3-6) and the distortion (7-20) as LocalCamera seeds them,
// and the tilt matrix `m` (computed once per shot in local jets: its
// derivatives sit in the tau slots 19 and 20). The value is ProjectWithTilt's
// on the same numbers, operation for operation; the derivatives are the
// chain rule through the steps of opencv_model.h:
//   pixel <- (xt, yt, zt) <- (x'', y'') <- (x', y') <- point,
// each a 2 x 2 or 2 x 3 block, the coefficients entering at their step.
// An autodiff pass of 21-wide jets does ~21 x the work of the value at
// every operation; this is a few dozen products per point.
// tests/fit/cost_functions_test.cc compares the chained Jacobian with plain
// autodiff through ProjectToPixel and with numeric differences.
inline bool ProjectWithTiltLocal(const LocalJet* intrinsics, const LocalJet* dist,
                                 const LocalJet* m, const double* point, LocalJet* pixel) {
  constexpr int kIntrinsicsVar = 3, kDistVar = 3 + kNumIntrinsics;
  constexpr int kTauXVar = kDistVar + kTauX, kTauYVar = kDistVar + kTauY;
  if (!(point[2] > 0.0)) return false;
  double d[kNumDistortion];
  for (int i = 0; i < kNumDistortion; ++i) d[i] = dist[i].a;
  const double fx = intrinsics[0].a, fy = intrinsics[1].a;
  // The value, as ProjectWithTilt computes it.
  const double x = point[0] / point[2];
  const double y = point[1] / point[2];
  double xd, yd;
  DistortNormalized(d, x, y, &xd, &yd);
  const double xt = m[0].a * xd + m[1].a * yd + m[2].a;
  const double yt = m[3].a * xd + m[4].a * yd + m[5].a;
  const double zt = m[6].a * xd + m[7].a * yd + m[8].a;
  pixel[0] = LocalJet(fx * xt / zt + intrinsics[2].a);
  pixel[1] = LocalJet(fy * yt / zt + intrinsics[3].a);

  // (x', y') <- point.
  const double iz = 1.0 / point[2];
  // (x'', y'') <- (x', y'), and the coefficients' columns.
  const double r2 = x * x + y * y, r4 = r2 * r2, r6 = r4 * r2;
  const double iden = 1.0 / (1.0 + d[kK4] * r2 + d[kK5] * r4 + d[kK6] * r6);
  const double radial = (1.0 + d[kK1] * r2 + d[kK2] * r4 + d[kK3] * r6) * iden;
  const double radial_r2 = ((d[kK1] + 2.0 * d[kK2] * r2 + 3.0 * d[kK3] * r4) -
                            radial * (d[kK4] + 2.0 * d[kK5] * r2 + 3.0 * d[kK6] * r4)) *
                           iden;
  const double b00 = radial + 2.0 * x * x * radial_r2 + 2.0 * d[kP1] * y + 6.0 * d[kP2] * x +
                     2.0 * d[kS1] * x + 4.0 * d[kS2] * r2 * x;
  const double b01 = 2.0 * x * y * radial_r2 + 2.0 * d[kP1] * x + 2.0 * d[kP2] * y +
                     2.0 * d[kS1] * y + 4.0 * d[kS2] * r2 * y;
  const double b10 = 2.0 * x * y * radial_r2 + 2.0 * d[kP1] * x + 2.0 * d[kP2] * y +
                     2.0 * d[kS3] * x + 4.0 * d[kS4] * r2 * x;
  const double b11 = radial + 2.0 * y * y * radial_r2 + 6.0 * d[kP1] * y + 2.0 * d[kP2] * x +
                     2.0 * d[kS3] * y + 4.0 * d[kS4] * r2 * y;
  // pixel <- (x'', y''): through the tilt and the intrinsics.
  const double izt = 1.0 / zt, px = xt * izt, py = yt * izt;
  const double a00 = fx * (m[0].a - px * m[6].a) * izt, a01 = fx * (m[1].a - px * m[7].a) * izt;
  const double a10 = fy * (m[3].a - py * m[6].a) * izt, a11 = fy * (m[4].a - py * m[7].a) * izt;
  // pixel <- (x', y') = A B, then <- point: dx'/dpoint = (1, 0, -x') / z,
  // dy'/dpoint = (0, 1, -y') / z.
  const double c00 = a00 * b00 + a01 * b10, c01 = a00 * b01 + a01 * b11;
  const double c10 = a10 * b00 + a11 * b10, c11 = a10 * b01 + a11 * b11;
  pixel[0].v[0] = c00 * iz;
  pixel[0].v[1] = c01 * iz;
  pixel[0].v[2] = -(c00 * x + c01 * y) * iz;
  pixel[1].v[0] = c10 * iz;
  pixel[1].v[1] = c11 * iz;
  pixel[1].v[2] = -(c10 * x + c11 * y) * iz;
  // Intrinsics: u = fx xt / zt + cx, v = fy yt / zt + cy.
  pixel[0].v[kIntrinsicsVar + 0] = px;
  pixel[0].v[kIntrinsicsVar + 2] = 1.0;
  pixel[1].v[kIntrinsicsVar + 1] = py;
  pixel[1].v[kIntrinsicsVar + 3] = 1.0;
  // Distortion coefficients: each moves (x'', y'') by (ex, ey), the pixel by A (ex, ey).
  auto coefficient = [&](int k, double ex, double ey) {
    pixel[0].v[kDistVar + k] = a00 * ex + a01 * ey;
    pixel[1].v[kDistVar + k] = a10 * ex + a11 * ey;
  };
  const double rad_terms[3] = {r2 * iden, r4 * iden, r6 * iden};
  coefficient(kK1, x * rad_terms[0], y * rad_terms[0]);
  coefficient(kK2, x * rad_terms[1], y * rad_terms[1]);
  coefficient(kK3, x * rad_terms[2], y * rad_terms[2]);
  coefficient(kK4, -x * radial * rad_terms[0], -y * radial * rad_terms[0]);
  coefficient(kK5, -x * radial * rad_terms[1], -y * radial * rad_terms[1]);
  coefficient(kK6, -x * radial * rad_terms[2], -y * radial * rad_terms[2]);
  coefficient(kP1, 2.0 * x * y, r2 + 2.0 * y * y);
  coefficient(kP2, r2 + 2.0 * x * x, 2.0 * x * y);
  coefficient(kS1, r2, 0.0);
  coefficient(kS2, r4, 0.0);
  coefficient(kS3, 0.0, r2);
  coefficient(kS4, 0.0, r4);
  // The tilt angles move the matrix: (xt, yt, zt) by dm (x'', y'', 1).
  for (const int tau : {kTauXVar, kTauYVar}) {
    const double dxt = m[0].v[tau] * xd + m[1].v[tau] * yd + m[2].v[tau];
    const double dyt = m[3].v[tau] * xd + m[4].v[tau] * yd + m[5].v[tau];
    const double dzt = m[6].v[tau] * xd + m[7].v[tau] * yd + m[8].v[tau];
    pixel[0].v[tau] = fx * (dxt - px * dzt) * izt;
    pixel[1].v[tau] = fy * (dyt - py * dzt) * izt;
  }
  return true;
}

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
// Speed (docs/refinement.md): the chain ref_from_cam is evaluated once per
// shot in the caller's jets (width ~40), and so is cam_from_board for each
// board the shot sees. Per point, only x_cam = cam_from_frame * X (X a plain
// constant) is formed in those wide jets; the projection (distortion, tilt,
// intrinsics) is evaluated with its 2 x 21 Jacobian over (x_cam,
// intrinsics, distortion) written out (ProjectWithTiltLocal), and that
// Jacobian is chained onto the wide jets:
//   d pixel = J_pixel_wrt_xcam d x_cam + J_pixel_wrt_intrinsics d intrinsics
//             + J_pixel_wrt_distortion d distortion.
// Intrinsics and distortion are seeded unit vectors, so their part is a
// scatter into one slot each. Projecting in the wide jets cost twice as
// much, and the written-out Jacobian instead of 21-wide local jets took
// another quarter off a joint refinement (joint_refine_benchmark
// --benchmark_filter=FiveIterations/3); the values are identical.
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
        if (!internal::ProjectWithTilt(intrinsics, dist, m, x_cam.data(), pixel)) {
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
      LocalJet m[9];
      TiltMatrix(cam.dist[kTauX], cam.dist[kTauY], m);
      for (size_t k = 0; k < points.size(); ++k) {
        const Vec3<T> x_cam = in_camera(k);
        const double lx[3] = {x_cam[0].a, x_cam[1].a, x_cam[2].a};
        LocalJet pixel[2];
        if (!internal::ProjectWithTiltLocal(cam.intrinsics, cam.dist, m, lx, pixel)) return false;
        for (int c = 0; c < 2; ++c) {
          T out;
          out.a = pixel[c].a;
          out.v =
              pixel[c].v[0] * x_cam[0].v + pixel[c].v[1] * x_cam[1].v + pixel[c].v[2] * x_cam[2].v;
          cam.Chain(pixel[c], &out);
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

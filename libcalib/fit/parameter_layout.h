// The model's parameter vector p as one list of blocks: what the full
// parameter covariance (ModelSigmas::covariance, covariance.yaml, the API's
// ParameterBlocks()) is indexed by. One place defines the order, so that the
// fit that fills the covariance and the API that uses it agree.
//
// Order (a block is always listed, free or held in the fit; a held block has
// zero rows and columns in the covariance):
//   base.rotation (3), base.t (3), link1 (4), link2 (4) (dh only),
//   edm.rotation (2), edm.t (3), each kinematic/EDM effect in EffectSet order
//   (1 or 2), then per zoom z: cam[z].rotation (3), cam[z].t (3),
//   cam[z].intrinsics (4: fx fy cx cy), cam[z].distortion (14, OpenCV order),
//   and cam[z].focus (3: kf, au, av; SPEC 4.1) when the model has the focus
//   effect.
// Boards and points of unknown position (SPEC 7) are not in p: they are
// nuisance parameters of the fit, and the covariance is the marginal one
// over them.
//
// Coordinates are tangent coordinates of the manifolds the fit uses
// (libcalib/fit/manifolds.h):
//   base.rotation, cam[z].rotation: Ceres' EigenQuaternionManifold,
//       q -> exp(delta) q, rotation angle 2 |delta| [rad]
//   edm.rotation: QuaternionNoRollManifold, q -> q exp([d0, d1, 0])
//   everything else: the block's own values (model.yaml order and SI units);
//       a block the fit held partly (SubsetManifold) is still listed whole,
//       with zero rows for the held coordinates.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "libcalib/model/instrument.h"

namespace rtscalib {

enum class LayoutTangent { kEuclidean, kQuaternion, kNoRoll };

// Which predictions a block influences.
constexpr int kLayoutShared = -2;   // every prediction (base, links, effects)
constexpr int kLayoutEdmOnly = -1;  // EDM points only
// (z >= 0: zoom z's camera only)

struct LayoutBlock {
  std::string name;  // "base.rotation", "link1", "hz_eccentricity", "cam[0].intrinsics", ...
  int offset = 0;    // into p
  int size = 0;      // tangent coordinates
  int ambient = 0;   // stored values (4 for a quaternion)
  std::string unit;
  LayoutTangent tangent = LayoutTangent::kEuclidean;
  int use = kLayoutShared;
  std::function<double*(InstrumentModel&)> data;  // the block's storage in a model
  std::function<const double*(const InstrumentModel&)> const_data;
};

// The blocks of `model` in the order above.
std::vector<LayoutBlock> ParameterLayout(const InstrumentModel& model);
// Total tangent size (the covariance's rows).
int LayoutSize(const std::vector<LayoutBlock>& layout);
// Moves block `b` of `model` by `delta` (b.size values) in its tangent coordinates.
void LayoutPlus(const LayoutBlock& b, const double* delta, InstrumentModel* model);

}  // namespace rtscalib

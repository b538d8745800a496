// Which parameters a fit of the instrument model frees, and which observations
// it groups into one residual block: the one place that decides both, for the
// refinement (refine.cc) and for the diagnosis's linearisation
// (libcalib/diagnose/linearization.cc), so that the diagnosis asks its
// questions about exactly the parameters the fit had.
//
// Blocks and their decisions (gauge freedoms held, docs/refinement.md):
//   base.rotation    quaternion manifold (3 tangent columns x, y, z)
//   base.t           free [m], Klug Eq. 98 window around the start value
//   dh:  link1       {alpha, a} free; d and gamma_offset held (the base absorbs them)
//        link2       held (the EDM and camera tools absorb it)
//        edm.rotation no-roll manifold (x, y): roll about the ray is unobservable (Eq. 79)
//        edm.t       free [m], Eq. 98 window
//   spherical: edm.rotation held (the line of sight), edm.t {x, y} free, t_z held (edm_offset)
//   cam[z].rotation  quaternion manifold; cam[z].t free, Eq. 98 window
//   cam[z].intrinsics free when FitOptions::fit_intrinsics, else held
//   cam[z].distortion the coefficients of the enabled distortion groups free, except those
//                    the user holds (CameraTool::distortion_held, set by HoldDistortion
//                    from the config's model.<group>.coefficients); the rest held
//   cam[z].focus     {kf, au, av} free when the model has the focus effect (SPEC 4.1)
//   <effect>         one free block per enabled kinematic effect (effects.h)
//   board[id]        a board of unknown pose (SPEC 7): quaternion manifold + free t
//   point[name]      a point of unknown position (SPEC 7): free 3-vector
//   board_warp[id]   {wx, wy} of the board whose first tag is id, when the model has
//                    board_warp: free, one pair per board shared by its poses
// What the data cannot determine (DataFacts, docs/refinement.md) is held:
//   no row with a known position: the base pose (and, dh, link1 d and
//     gamma_offset as always) at the ideal base frame (SPEC 7);
//   EDM rows but none with a known x: the EDM translation along its ray and
//     every EDM effect (each point's distance absorbs any function of d).
// Effects the kinematics already contain are never fitted (`ContainedInKinematics`).
//
// Every tangent column carries its name and, when it is an effect's parameter,
// which effect: the diagnosis adds candidate effects by enabling them in a
// copy of the model and reading off their columns, without deciding anything
// itself. A new kind of block (a board pose, an unknown point) is one more
// entry in `Parameterization`'s constructor (parameterization.cc).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "libcalib/fit/cost_functions.h"
#include "libcalib/fit/manifolds.h"
#include "libcalib/fit/refine.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"

namespace ceres {
class CostFunction;
class Problem;
}  // namespace ceres

namespace rtscalib {

// True when `kinematics` already contains effect `e` (SPEC 4: dh holds
// collimation, tilting_axis, vertical_index and edm_offset in its links and
// tools), so that no fit frees it twice.
bool ContainedInKinematics(Kinematics kinematics, Effect e);
// Removes such effects from `model`; returns the ones removed.
std::vector<Effect> RemoveContainedEffects(InstrumentModel* model);

// Whether a fit of `model` frees coefficient `index` (DistortionIndex) of
// zoom `zoom`'s distortion: its group is enabled and the coefficient is not
// held (CameraTool::distortion_held). The Parameterization below decides
// with it; model.yaml and the diagnosis read it to say what was fitted.
bool DistortionIsFree(const InstrumentModel& model, int zoom, int index);

// Applies the config's distortion choices (model.<group>: {coefficients,
// zooms}) to `model`: per zoom, every coefficient of a chosen group that is
// not listed is held (CameraTool::distortion_held) at its start value, the
// configured camera's (`configured[zoom].distortion`, model.cameras) or 0;
// listed ones are freed. Groups without a choice are left as they are.
// Throws std::invalid_argument naming the key when a choice names a zoom the
// model has no camera for, or a group that is not enabled.
void HoldDistortion(const std::vector<DistortionChoice>& choices,
                    const std::vector<CameraTool>& configured, InstrumentModel* model);

// One tangent column of a free block.
struct FreeColumn {
  std::string name;              // "base.rotation[x]", "link1.alpha", "cam[0].k1", "edm_scale[0]"
  std::optional<Effect> effect;  // the effect this parameter belongs to, if any
  int zoom = -1;                 // per-zoom blocks: the zoom
  int board = -1;                // per-board blocks (board_warp): the board's first_id
  int index = 0;                 // ambient index within the block (distortion: coefficient)
};

struct BlockDecision {
  double* block = nullptr;
  BlockKind kind = BlockKind::kFree;
  std::string name;  // "base.rotation", "cam[0].distortion" (covariance and reports)
  int size = 0;
  std::vector<int> frozen;           // kSubset: held ambient indices
  std::vector<double> bound_centre;  // translations: Klug Eq. 98 window centre (start value)
  std::vector<FreeColumn> columns;   // one per tangent column; empty when held
};

// What the observations a fit uses can determine (SPEC 7). The defaults are
// those of data with known positions (records with x, pixels with X).
struct DataFacts {
  bool known_positions = true;      // some used row has a known reference-frame position
  bool known_edm_distances = true;  // no EDM row, or some EDM row with a known x
};
struct UsedRows;
DataFacts FactsOf(const Observations& obs, const UsedRows& rows);

class Parameterization {
 public:
  // Decides every block of `model` (pointers into its memory; the model must
  // outlive this object). Translation windows are centred on the model's
  // values now.
  Parameterization(InstrumentModel* model, const FitOptions& options,
                   const DataFacts& facts = DataFacts());

  // All decisions, in a fixed order: base, links, EDM, cameras by zoom, effects
  // in catalogue order, boards, points, board warps.
  const std::vector<BlockDecision>& Blocks() const { return blocks_; }
  const BlockDecision* Find(const double* block) const;
  // Human-readable list of the held gauge freedoms (FitSummary::fixed_gauges).
  const std::vector<std::string>& FixedGauges() const { return fixed_gauges_; }

  // Number of parameters in the blocks of `layout` that are not held (the
  // cost functions size their jets to it).
  int ActiveSize(const BlockLayout& layout) const;

  // Sets manifolds and held blocks on every decided block present in
  // `problem`; with `with_bounds`, also Klug Eq. 98's translation windows as
  // hard bounds. Returns the blocks present and not held, in `Blocks()` order.
  std::vector<const BlockDecision*> Apply(ceres::Problem* problem, bool with_bounds) const;

  // Names of translations that left their Eq. 98 window (empty if none).
  std::vector<std::string> OutsideBounds() const;

 private:
  void Add(BlockDecision d);

  double translation_bound_m_ = 0;
  std::vector<BlockDecision> blocks_;
  std::vector<std::string> fixed_gauges_;
};

// ---------------------------------------------------------------------------
// Observations: which rows a fit uses and how they are grouped.

enum class ObsGroup { kEdm = 0, kCam = 1, kPixel = 2 };

struct UsedRows {
  std::vector<int> records;  // into obs.records
  std::vector<int> pixels;   // into obs.pixels
  int excluded_critical = 0;
};
// What to do with a row whose zoom has no camera in the model: the refinement
// reports it as bad input, the diagnosis (which sees a model already fitted)
// skips it.
enum class UnknownZoom { kThrow, kSkip };
// Rows outside the critical regions (SPEC 1, FitOptions zenith limits).
// Throws std::invalid_argument naming file and line for kThrow.
UsedRows SelectRows(const Observations& obs, const FitOptions& options, int num_zooms,
                    UnknownZoom unknown_zoom);

// Observations that share a pointing and a tool (records) or a shot (pixels):
// one residual block each, so that the chain ref_from_tool(phi, theta) is
// differentiated once per pointing (a robust loss acts on each observation
// inside its group: observation_loss.h). Record groups come first, in order
// of first appearance, then pixel groups; a photo is one group, so its focus
// distance (SPEC 4.1, the centroid of all its points) is its group's.
struct ObservationGroup {
  ObsGroup kind = ObsGroup::kEdm;
  int zoom = -1;  // -1 for the EDM
  double phi = 0, theta = 0;
  int face = 1;              // of the group's first observation
  std::vector<int> indices;  // into obs.records (edm, cam) or obs.pixels
  std::string shot;          // pixels: the shot's name
};
std::vector<ObservationGroup> GroupObservations(const Observations& obs, const UsedRows& rows);

// The residual block of one group (cost_functions.h), whitened by
// `inv_sigma`, its jets sized to the blocks `param` leaves free; `blocks`
// receives the parameter blocks in the cost's order. The caller owns the cost.
// A pixel with X_known == false uses the model's estimated board holding its
// tag, or else a board of obs.targets with a pose (its corner is then known);
// a record with a `point` uses the model's point of that name. Throws
// std::invalid_argument naming the file and line when neither exists.
ceres::CostFunction* MakeGroupCost(const Observations& obs, const ObservationGroup& group,
                                   double inv_sigma, const Parameterization& param,
                                   InstrumentModel* model, std::vector<double*>* blocks);

}  // namespace rtscalib

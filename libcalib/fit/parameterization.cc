#include "libcalib/fit/parameterization.h"

#include <ceres/problem.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <stdexcept>
#include <tuple>


namespace rtscalib {

bool ContainedInKinematics(Kinematics kinematics, Effect e) {
  return kinematics == Kinematics::kDh && Info(e).redundant_in_dh;
}

std::vector<Effect> RemoveContainedEffects(InstrumentModel* model) {
  std::vector<Effect> removed;
  for (Effect e : model->effects.List()) {
    if (ContainedInKinematics(model->kinematics, e)) {
      model->effects.Remove(e);
      removed.push_back(e);
    }
  }
  return removed;
}

bool DistortionIsFree(const InstrumentModel& model, int zoom, int index) {
  return model.effects.Has(DistortionGroupOf(index)) && !model.cams[zoom].distortion_held[index];
}

void HoldDistortion(const std::vector<DistortionChoice>& choices,
                    const std::vector<CameraTool>& configured, InstrumentModel* model) {
  for (const DistortionChoice& choice : choices) {
    const std::string key = std::string("model.") + Info(choice.group).name;
    if (!model->effects.Has(choice.group)) {
      throw std::invalid_argument(key + ": " + Info(choice.group).name +
                                  " is not in model.effects (its coefficients are all held)");
    }
    for (const auto& [zoom, list] : choice.zooms) {
      if (zoom < 0 || zoom >= model->NumZooms()) {
        throw std::invalid_argument(key + ".zooms: expected zoom levels of the model (0.." +
                                    std::to_string(model->NumZooms() - 1) + "), got " +
                                    std::to_string(zoom));
      }
    }
    for (int z = 0; z < model->NumZooms(); ++z) {
      CameraTool& cam = model->cams[z];
      const std::vector<int>& fitted = choice.At(z);
      for (int index : Info(choice.group).distortion_indices) {
        const bool fit = std::find(fitted.begin(), fitted.end(), index) != fitted.end();
        cam.distortion_held[index] = !fit;
        if (fit) continue;
        // Held at the start value the user gave, else at zero (an extraction
        // or OpenCV start may have estimated it; that is not a given value).
        cam.distortion[index] =
            z < static_cast<int>(configured.size()) ? configured[z].distortion[index] : 0.0;
      }
    }
  }
}

namespace {

// A held value for a message: %g keeps 0 as "0".
std::string FormatNumber(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

// Names of the columns of translations and rotations.
const char* const kAxes[] = {"x", "y", "z"};

BlockDecision Decision(double* p, BlockKind kind, const std::string& name, int size,
                       std::vector<int> frozen = {}) {
  BlockDecision d;
  d.block = p;
  d.kind = kind;
  d.name = name;
  d.size = size;
  d.frozen = std::move(frozen);
  return d;
}

FreeColumn Column(const std::string& name, std::optional<Effect> effect, int index) {
  FreeColumn c;
  c.name = name;
  c.effect = effect;
  c.index = index;
  return c;
}

// A rotation block: its tangent columns are rotations about the local axes.
BlockDecision Rotation(double* q, const std::string& name, BlockKind kind) {
  BlockDecision d = Decision(q, kind, name + ".rotation", 4);
  const int tangent = kind == BlockKind::kQuaternion ? 3 : kind == BlockKind::kNoRoll ? 2 : 0;
  for (int i = 0; i < tangent; ++i) {
    d.columns.push_back(Column(name + ".rotation[" + kAxes[i] + "]", std::nullopt, i));
  }
  return d;
}

// A Euclidean block (free, held or a subset): one column per ambient index
// that is not held, named `prefix + names[i] + suffix`.
BlockDecision Euclidean(double* p, const std::string& name, BlockKind kind, int size,
                        std::vector<int> frozen, const std::string& prefix,
                        const char* const* names, const std::string& suffix) {
  BlockDecision d = Decision(p, kind, name, size, std::move(frozen));
  if (kind == BlockKind::kConstant) return d;
  for (int i = 0; i < size; ++i) {
    bool held = false;
    for (int f : d.frozen) held = held || f == i;
    if (!held) d.columns.push_back(Column(prefix + names[i] + suffix, std::nullopt, i));
  }
  return d;
}

// A translation: free (or a subset), with Klug Eq. 98's window around its
// value at decision time.
BlockDecision Translation(double* t, const std::string& name, std::vector<int> frozen) {
  const BlockKind kind = frozen.empty() ? BlockKind::kFree : BlockKind::kSubset;
  BlockDecision d = Euclidean(t, name + ".t", kind, 3, std::move(frozen), name + ".t[", kAxes, "]");
  // Refine bounded only fully free translations (the spherical EDM's t_z is
  // held, its x, y need no window).
  if (kind == BlockKind::kFree) d.bound_centre.assign(t, t + 3);
  return d;
}

}  // namespace

DataFacts FactsOf(const Observations& obs, const UsedRows& rows) {
  DataFacts f;
  f.known_positions = false;
  bool edm_rows = false, edm_known = false;
  for (int i : rows.records) {
    const Record& r = obs.records[i];
    if (r.point.empty()) f.known_positions = true;
    if (r.tool == Tool::kEdm) {
      edm_rows = true;
      edm_known = edm_known || r.point.empty();
    }
  }
  for (int i : rows.pixels) {
    const PixelObservation& p = obs.pixels[i];
    if (p.X_known) {
      f.known_positions = true;
      continue;
    }
    // A corner of a surveyed board is a known position.
    for (const TagBoard& b : obs.targets.boards) {
      if (b.HasId(p.target) && b.pose_known) f.known_positions = true;
    }
  }
  f.known_edm_distances = !edm_rows || edm_known;
  return f;
}

Parameterization::Parameterization(InstrumentModel* model, const FitOptions& options,
                                   const DataFacts& facts)
    : translation_bound_m_(options.translation_bound_m) {
  InstrumentModel& m = *model;
  const bool dh = m.kinematics == Kinematics::kDh;
  const bool camera_only = m.kinematics == Kinematics::kNone;
  if (camera_only) {
    // SPEC 7.1: no chain. Base, links and tools stay at the identity, so that
    // each zoom's camera frame is the reference of its shots; only the
    // cameras' intrinsics and distortion and the boards' poses are free.
    Add(Rotation(m.base.q.data(), "base", BlockKind::kConstant));
    Add(Decision(m.base.t.data(), BlockKind::kConstant, "base.t", 3));
    Add(Rotation(m.edm.q.data(), "edm", BlockKind::kConstant));
    Add(Decision(m.edm.t.data(), BlockKind::kConstant, "edm.t", 3));
    fixed_gauges_.push_back(
        "kinematics none (camera-only): no chain is estimated; each zoom's camera frame is the "
        "reference frame of its shots, and each board pose per placement is cam_from_board");
  } else if (facts.known_positions) {
    Add(Rotation(m.base.q.data(), "base", BlockKind::kQuaternion));
    Add(Translation(m.base.t.data(), "base", {}));
  } else {
    // SPEC 7: without any known position the reference frame is the ideal
    // base frame; the whole scene would otherwise move with the base.
    Add(Rotation(m.base.q.data(), "base", BlockKind::kConstant));
    Add(Decision(m.base.t.data(), BlockKind::kConstant, "base.t", 3));
    fixed_gauges_.push_back(
        "base pose held at the instrument's ideal base frame: no observation has a known "
        "position (SPEC 7), so the reference frame is defined by the instrument");
  }
  if (camera_only) {
    // (held above)
  } else if (dh) {
    Add(Euclidean(m.links[0].p.data(), "link1", BlockKind::kSubset, 4, {kDhD, kDhGamma}, "link1.",
                  kDhParamNames, ""));
    Add(Euclidean(m.links[1].p.data(), "link2", BlockKind::kConstant, 4, {}, "", kDhParamNames,
                  ""));
    fixed_gauges_.push_back(
        "link1.d and link1.gamma_offset held at their start values (equivalent to base "
        "translation along and rotation about axis 1)");
    fixed_gauges_.push_back(
        "link2 {d, gamma_offset, alpha, a} held (the EDM and camera tool transforms absorb them)");
    Add(Rotation(m.edm.q.data(), "edm", BlockKind::kNoRoll));
    fixed_gauges_.push_back(
        "EDM roll about its ray held at the extraction's convention (Klug Eq. 79)");
    if (facts.known_edm_distances) {
      Add(Translation(m.edm.t.data(), "edm", {}));
    } else {
      // The flange-frame axis closest to the ray: its translation moves the
      // EDM along the ray, which every point of unknown position absorbs.
      const Eigen::Vector3d ray = m.edm.ToRigid().rotation.col(2);
      int along = 0;
      ray.cwiseAbs().maxCoeff(&along);
      Add(Translation(m.edm.t.data(), "edm", {along}));
      fixed_gauges_.push_back(std::string("EDM t_") + kAxes[along] +
                              " (along the ray) held: no EDM row has a known x, so the "
                              "distance offset is not determined (each point absorbs it)");
    }
  } else {
    // Spherical: the EDM ray is the line of sight; its offset along the ray
    // is edm_offset's job.
    Add(Rotation(m.edm.q.data(), "edm", BlockKind::kConstant));
    Add(Translation(m.edm.t.data(), "edm", {2}));
    fixed_gauges_.push_back(
        "spherical: EDM rotation is the line of sight (held); EDM t_z held (edm_offset models it)");
  }

  for (int z = 0; z < m.NumZooms(); ++z) {
    CameraTool& cam = m.cams[z];
    // Distortion coefficients are free exactly when an enabled group owns
    // them and the user did not hold them (model.<group>.coefficients).
    std::vector<int> frozen_distortion;
    std::string held;
    for (int i = 0; i < kNumDistortion; ++i) {
      if (!DistortionIsFree(m, z, i)) frozen_distortion.push_back(i);
      if (m.effects.Has(DistortionGroupOf(i)) && cam.distortion_held[i]) {
        held += std::string(held.empty() ? "" : ", ") + kDistortionCoefficientNames[i] + " = " +
                FormatNumber(cam.distortion[i]);
      }
    }
    if (!held.empty()) {
      fixed_gauges_.push_back("cam[" + std::to_string(z) + "] distortion held (not estimated, " +
                              "model.<group>.coefficients): " + held);
    }
    const std::string zs = "cam[" + std::to_string(z) + "]";
    auto per_zoom = [z](BlockDecision d) {
      for (FreeColumn& c : d.columns) c.zoom = z;
      return d;
    };
    if (camera_only) {
      Add(Rotation(cam.flange_from_cam.q.data(), zs, BlockKind::kConstant));
      Add(Decision(cam.flange_from_cam.t.data(), BlockKind::kConstant, zs + ".t", 3));
    } else {
      Add(per_zoom(Rotation(cam.flange_from_cam.q.data(), zs, BlockKind::kQuaternion)));
      Add(per_zoom(Translation(cam.flange_from_cam.t.data(), zs, {})));
    }
    Add(per_zoom(Euclidean(cam.intrinsics.data(), zs + ".intrinsics",
                           options.fit_intrinsics ? BlockKind::kFree : BlockKind::kConstant,
                           kNumIntrinsics, {}, zs + ".", kIntrinsicsParamNames, "")));
    BlockDecision dist = per_zoom(Euclidean(cam.distortion.data(), zs + ".distortion",
                                            BlockKind::kSubset, kNumDistortion, frozen_distortion,
                                            zs + ".", kDistortionCoefficientNames, ""));
    for (FreeColumn& c : dist.columns) c.effect = DistortionGroupOf(c.index);
    Add(std::move(dist));
    // SPEC 4.1: how the zoom's intrinsics change with the focus distance.
    if (m.effects.Has(Effect::kFocus)) {
      BlockDecision focus = per_zoom(Euclidean(cam.focus.data(), zs + ".focus", BlockKind::kFree,
                                               kNumFocus, {}, zs + ".", kFocusParamNames, ""));
      for (FreeColumn& c : focus.columns) c.effect = Effect::kFocus;
      Add(std::move(focus));
    }
  }
  for (Effect e : m.effects.List()) {
    if (!IsKinematic(e)) continue;
    const EffectInfo& info = Info(e);
    if (!facts.known_edm_distances && info.kind == EffectKind::kEdm) {
      Add(Decision(m.EffectValue(e).data(), BlockKind::kConstant, info.name, info.num_params));
      fixed_gauges_.push_back(std::string(info.name) +
                              " held: no EDM row has a known x, so no function of the distance "
                              "is determined (each point absorbs it)");
      continue;
    }
    BlockDecision d =
        Decision(m.EffectValue(e).data(), BlockKind::kFree, info.name, info.num_params);
    for (int k = 0; k < info.num_params; ++k) {
      d.columns.push_back(Column(std::string(info.name) + "[" + std::to_string(k) + "]", e, k));
    }
    Add(std::move(d));
  }
  // SPEC 7: boards of unknown pose and points of unknown position. No Eq. 98
  // window: their start (PnP, ideal EDM) is not an extraction's.
  for (EstimatedBoard& b : m.boards) {
    const std::string name = b.Key();
    Add(Rotation(b.pose.q.data(), name, BlockKind::kQuaternion));
    Add(Euclidean(b.pose.t.data(), name + ".t", BlockKind::kFree, 3, {}, name + ".t[", kAxes, "]"));
  }
  for (EstimatedPoint& p : m.points) {
    const std::string name = "point[" + p.name + "]";
    Add(Euclidean(p.x.data(), name, BlockKind::kFree, 3, {}, name + "[", kAxes, "]"));
  }
  // board_warp: one free pair per board of unknown pose, shared by its poses.
  if (m.effects.Has(Effect::kBoardWarp)) {
    const EffectInfo& info = Info(Effect::kBoardWarp);
    for (BoardWarp& w : m.board_warps) {
      const std::string name = std::string(info.name) + "[" + std::to_string(w.first_id) + "]";
      BlockDecision d = Euclidean(w.w.data(), name, BlockKind::kFree, kNumBoardWarp, {},
                                  name + ".", info.param_names.data(), "");
      for (FreeColumn& c : d.columns) {
        c.effect = Effect::kBoardWarp;
        c.board = w.first_id;
      }
      Add(std::move(d));
    }
  }
}

void Parameterization::Add(BlockDecision d) {
  if (d.kind == BlockKind::kSubset && static_cast<int>(d.frozen.size()) == d.size) {
    d.kind = BlockKind::kConstant;
  }
  if (d.kind == BlockKind::kConstant) d.columns.clear();
  blocks_.push_back(std::move(d));
}

const BlockDecision* Parameterization::Find(const double* block) const {
  for (const BlockDecision& d : blocks_) {
    if (d.block == block) return &d;
  }
  return nullptr;
}

int Parameterization::ActiveSize(const BlockLayout& layout) const {
  int n = 0;
  for (size_t i = 0; i < layout.blocks.size(); ++i) {
    const BlockDecision* d = Find(layout.blocks[i]);
    if (!d || d->kind != BlockKind::kConstant) n += layout.sizes[i];
  }
  return n;
}

std::vector<const BlockDecision*> Parameterization::Apply(ceres::Problem* problem,
                                                          bool with_bounds) const {
  std::vector<const BlockDecision*> free;
  for (const BlockDecision& d : blocks_) {
    if (!problem->HasParameterBlock(d.block)) continue;
    ParameterizeBlock(problem, d.block, d.kind, d.size, d.frozen);
    // Klug Eq. 98: |t| <= t_max, applied as a window around the start value
    // (the extraction is good to a fraction of it), so that a station far
    // from the origin stays admissible.
    if (with_bounds && !d.bound_centre.empty() && translation_bound_m_ > 0) {
      for (int i = 0; i < d.size; ++i) {
        problem->SetParameterLowerBound(d.block, i, d.bound_centre[i] - translation_bound_m_);
        problem->SetParameterUpperBound(d.block, i, d.bound_centre[i] + translation_bound_m_);
      }
    }
    if (d.kind != BlockKind::kConstant) free.push_back(&d);
  }
  return free;
}

std::vector<std::string> Parameterization::OutsideBounds() const {
  std::vector<std::string> out;
  if (translation_bound_m_ <= 0) return out;
  for (const BlockDecision& d : blocks_) {
    for (size_t i = 0; i < d.bound_centre.size(); ++i) {
      if (std::abs(d.block[i] - d.bound_centre[i]) > translation_bound_m_) {
        out.push_back(d.name);
        break;
      }
    }
  }
  return out;
}

UsedRows SelectRows(const Observations& obs, const FitOptions& options, int num_zooms,
                    UnknownZoom unknown_zoom) {
  UsedRows rows;
  // Returns whether the row's zoom has a camera; throws for kThrow.
  auto known = [&](int zoom, const std::string& source, int line) {
    if (zoom >= 0 && zoom < num_zooms) return true;
    if (unknown_zoom == UnknownZoom::kSkip) return false;
    throw std::invalid_argument(source + ":" + std::to_string(line) + ": zoom " +
                                std::to_string(zoom) + " has no camera in the model");
  };
  for (size_t i = 0; i < obs.records.size(); ++i) {
    const Record& r = obs.records[i];
    if (options.critical_region.Contains(r.theta)) {
      ++rows.excluded_critical;
      continue;
    }
    if (r.tool == Tool::kCam && !known(r.zoom, obs.records_source, r.line)) continue;
    rows.records.push_back(static_cast<int>(i));
  }
  for (size_t i = 0; i < obs.pixels.size(); ++i) {
    const PixelObservation& p = obs.pixels[i];
    if (options.critical_region.Contains(p.theta)) {
      ++rows.excluded_critical;
      continue;
    }
    if (!known(p.zoom, obs.pixels_source, p.line)) continue;
    rows.pixels.push_back(static_cast<int>(i));
  }
  return rows;
}

std::vector<ObservationGroup> GroupObservations(const Observations& obs, const UsedRows& rows) {
  std::vector<ObservationGroup> groups;
  std::map<std::tuple<bool, int, double, double>, int> record_index;
  for (int i : rows.records) {
    const Record& r = obs.records[i];
    const bool edm = r.tool == Tool::kEdm;
    const int zoom = edm ? -1 : r.zoom;
    const auto key = std::make_tuple(edm, zoom, r.phi, r.theta);
    auto it = record_index.find(key);
    if (it == record_index.end()) {
      record_index[key] = static_cast<int>(groups.size());
      groups.push_back(
          {edm ? ObsGroup::kEdm : ObsGroup::kCam, zoom, r.phi, r.theta, r.face, {i}, ""});
    } else {
      groups[it->second].indices.push_back(i);
    }
  }
  std::map<std::tuple<std::string, int, double, double>, int> shot_index;
  for (int i : rows.pixels) {
    const PixelObservation& p = obs.pixels[i];
    const auto key = std::make_tuple(p.shot, p.zoom, p.phi, p.theta);
    auto it = shot_index.find(key);
    if (it == shot_index.end()) {
      shot_index[key] = static_cast<int>(groups.size());
      groups.push_back({ObsGroup::kPixel, p.zoom, p.phi, p.theta, p.face, {i}, p.shot});
    } else {
      groups[it->second].indices.push_back(i);
    }
  }
  return groups;
}

ceres::CostFunction* MakeGroupCost(const Observations& obs, const ObservationGroup& g,
                                   double inv_sigma, const Parameterization& param,
                                   InstrumentModel* model, std::vector<double*>* blocks) {
  if (g.kind == ObsGroup::kPixel) {
    auto* f = new ShotResidual;
    f->layout = LayoutFor(model, g.zoom);
    f->phi = g.phi;
    f->theta = g.theta;
    f->inv_sigma = inv_sigma;
    std::map<const EstimatedBoard*, int> slots;
    // Point (in the reference frame, or in the frame of layout board
    // `board`) of one pixel observation.
    auto place = [&](const PixelObservation& px) {
      ShotResidual::Point pt{px.X, px.uv, -1};
      if (px.X_known) return pt;
      const std::string where = obs.pixels_source + ":" + std::to_string(px.line) + ": ";
      if (px.corner < 0 || px.corner > 3) {
        throw std::invalid_argument(where + "corner must be 0..3, got " +
                                    std::to_string(px.corner));
      }
      if (EstimatedBoard* b = model->BoardOf(px.target, px.placement, px.zoom)) {
        // board_warp: the board's warp block, shared by all its poses.
        BoardWarp* warp = model->effects.Has(Effect::kBoardWarp)
                              ? model->WarpOf(b->board.first_id)
                              : nullptr;
        auto it = slots.find(b);
        if (it == slots.end()) {
          it = slots.emplace(b, static_cast<int>(f->layout.boards.size())).first;
          f->layout.boards.push_back(
              {f->layout.Add(b->pose.q.data(), 4), f->layout.Add(b->pose.t.data(), 3)});
          int warp_block = -1;
          if (warp) {
            // One block appears once per residual, whichever of the board's
            // poses the shot sees.
            for (size_t k = 0; k < f->layout.blocks.size() && warp_block < 0; ++k) {
              if (f->layout.blocks[k] == warp->w.data()) warp_block = static_cast<int>(k);
            }
            if (warp_block < 0) warp_block = f->layout.Add(warp->w.data(), kNumBoardWarp);
          }
          f->layout.board_warps.push_back(warp_block);
        }
        // The flat corner: the warp enters through its block (or not at all).
        pt.X = b->board.FlatCornersInBoard(px.target - b->board.first_id)[px.corner];
        if (warp) pt.warp_shape = b->board.WarpShape(pt.X);
        pt.board = it->second;
        return pt;
      }
      const TagBoard* known = nullptr;
      for (const TagBoard& tb : obs.targets.boards) {
        if (tb.HasId(px.target) && tb.pose_known) known = &tb;
      }
      if (!known) {
        throw std::invalid_argument(
            where + "X, Y, Z are empty but target " + std::to_string(px.target) +
            " is not a tag of a board in the targets (SPEC 7: empty X, Y, Z need one)");
      }
      pt.X = known->ref_from_board * known->CornersInBoard(px.target - known->first_id)[px.corner];
      return pt;
    };
    for (int i : g.indices) f->points.push_back(place(obs.pixels[i]));
    if (f->layout.focus >= 0) {
      // SPEC 4.1: the photo's D, given or from the centroid of all its points.
      for (int i : g.indices) {
        if (obs.pixels[i].focus_distance > 0) f->focus_distance = obs.pixels[i].focus_distance;
      }
      if (!(f->focus_distance > 0)) {
        std::map<int, int> term_of;  // layout board (-1: known points) -> focus_terms index
        for (int i : g.indices) {
          const ShotResidual::Point pt = place(obs.pixels[i]);
          auto it = term_of.find(pt.board);
          if (it == term_of.end()) {
            it = term_of.emplace(pt.board, static_cast<int>(f->focus_terms.size())).first;
            f->focus_terms.push_back({pt.board, Eigen::Vector3d::Zero(), Eigen::Vector2d::Zero(), 0});
          }
          f->focus_terms[it->second].sum += pt.X;
          f->focus_terms[it->second].warp_shape_sum += pt.warp_shape;
          ++f->focus_terms[it->second].count;
          ++f->focus_count;
        }
      }
    }
    *blocks = f->layout.blocks;
    return MakeCost(f, 2 * static_cast<int>(g.indices.size()), param.ActiveSize(f->layout));
  }
  auto* f = new RecordGroupResidual;
  f->layout = LayoutFor(model, g.zoom);
  f->edm = g.kind == ObsGroup::kEdm;
  f->phi = g.phi;
  f->theta = g.theta;
  std::map<const EstimatedPoint*, int> slots;
  for (int i : g.indices) {
    const Record& r = obs.records[i];
    RecordGroupResidual::Row row{r.u, r.v, r.d, r.x, inv_sigma, -1};
    if (!r.point.empty()) {
      EstimatedPoint* q = model->Point(r.point);
      if (!q) {
        throw std::invalid_argument(obs.records_source + ":" + std::to_string(r.line) +
                                    ": point '" + r.point + "' has no start value in the model");
      }
      auto it = slots.find(q);
      if (it == slots.end()) {
        it = slots.emplace(q, static_cast<int>(f->layout.points.size())).first;
        f->layout.points.push_back(f->layout.Add(q->x.data(), 3));
      }
      row.point = it->second;
    }
    f->rows.push_back(row);
  }
  *blocks = f->layout.blocks;
  return MakeCost(f, 3 * static_cast<int>(g.indices.size()), param.ActiveSize(f->layout));
}

}  // namespace rtscalib

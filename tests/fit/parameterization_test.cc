#include "libcalib/fit/parameterization.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>
#include <vector>

#include "libcalib/diagnose/linearization.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib {
namespace {

// A few noise-free records in both faces (EDM and camera rows, so that every
// kind of block is touched): enough for one Jacobian, cheap for 64 cases.
Observations SmallData(const InstrumentModel& truth) {
  SimulationOptions o;
  o.truth = truth;
  o.plan.sweep_points = 6;
  o.plan.faces = {1, 2};
  return Simulate(o).obs;
}

InstrumentModel Truth(Kinematics k) {
  if (k == Kinematics::kDh) return PaperTruth(1);
  InstrumentModel m = IdealModel(Kinematics::kSpherical, 1, PaperTruth(1).cams[0]);
  m.edm.t = {2e-4, -1e-4, 0.0};
  return m;
}

// The refinement's free parameters of `model`: Refine's parameterisation
// (after it drops the effects the kinematics contain), restricted to the
// blocks the observations touch (the EDM layout and zoom 0's).
std::vector<std::string> RefinementColumns(InstrumentModel model, const FitOptions& fit) {
  RemoveContainedEffects(&model);
  const Parameterization param(&model, fit);
  std::set<const double*> touched;
  for (int zoom : {-1, 0}) {
    for (double* p : LayoutFor(&model, zoom).blocks) touched.insert(p);
  }
  std::vector<std::string> out;
  for (const BlockDecision& d : param.Blocks()) {
    if (!touched.count(d.block)) continue;
    for (const FreeColumn& c : d.columns) out.push_back(c.name);
  }
  return out;
}

std::vector<std::string> Sorted(std::vector<std::string> v) {
  std::sort(v.begin(), v.end());
  return v;
}

std::string CaseName(Kinematics k, Effect e, bool fit_intrinsics) {
  return std::string(KinematicsName(k)) + " + " + Info(e).name +
         (fit_intrinsics ? ", intrinsics fitted" : ", intrinsics fixed");
}

// Every kinematics x effect x intrinsics mode (FitOptions::fit_intrinsics;
// the config's `auto` resolves to one of the two before the fit): the
// diagnosis's columns equal the refinement's free parameters, both for the
// effect as a fitted part of the model and as a candidate added to it.
TEST(Parameterization, RefinementAndDiagnosisFreeTheSameParameters) {
  for (Kinematics k : {Kinematics::kDh, Kinematics::kSpherical}) {
    const InstrumentModel baseline = Truth(k);
    const Observations obs = SmallData(baseline);
    for (bool fit_intrinsics : {false, true}) {
      FitOptions fit;
      fit.fit_intrinsics = fit_intrinsics;
      fit.num_threads = 1;
      for (const EffectInfo& info : EffectCatalogue()) {
        const Effect e = info.effect;
        SCOPED_TRACE(CaseName(k, e, fit_intrinsics));
        InstrumentModel with_e = baseline;
        with_e.effects.Add(e);
        const std::vector<std::string> refinement = RefinementColumns(with_e, fit);

        if (ContainedInKinematics(k, e)) {
          // Never fitted: the refinement frees what it frees without it, and
          // the diagnosis never offers it as a candidate (diagnose.cc).
          EXPECT_EQ(refinement, RefinementColumns(baseline, fit));
          continue;
        }

        // e fitted: the linearisation's base columns are the refinement's
        // free parameters, in the same order.
        LinearizeOptions fitted;
        fitted.fit = fit;
        const Linearization lin_fitted = Linearize(obs, with_e, fitted);
        EXPECT_EQ(lin_fitted.base_names, refinement);

        // e a candidate: base columns are the baseline's free parameters and
        // e's columns complete them to the refinement's set with e.
        LinearizeOptions candidate = fitted;
        candidate.candidates = {e};
        const Linearization lin = Linearize(obs, baseline, candidate);
        EXPECT_EQ(lin.base_names, RefinementColumns(baseline, fit));
        const ColumnBlock* block = lin.Find(info.name);
        ASSERT_NE(block, nullptr);
        if (IsBoardEffect(e)) {
          // These boards are surveyed (known corners): a warp belongs to a
          // board of estimated pose only, so there is nothing to free
          // (tests/fit/board_warp_test.cc fits it with estimated boards).
          EXPECT_EQ(block->size, 0);
          EXPECT_EQ(refinement, RefinementColumns(baseline, fit));
          continue;
        }
        EXPECT_GT(block->size, 0);
        std::vector<std::string> both = lin.base_names;
        both.insert(both.end(), block->param_names.begin(), block->param_names.end());
        EXPECT_EQ(Sorted(both), Sorted(refinement));
        EXPECT_EQ(static_cast<int>(both.size()), static_cast<int>(refinement.size()))
            << "a candidate column duplicates a base column";
      }
    }
  }
}

// The decisions themselves (docs/refinement.md's gauge list), spot-checked
// by name so that a change to them is a deliberate change to this list.
TEST(Parameterization, HoldsTheGaugeFreedoms) {
  FitOptions fit;
  InstrumentModel dh = Truth(Kinematics::kDh);
  dh.effects.Add(Effect::kTangentialDistortion);
  dh.effects.Add(Effect::kEdmScale);
  const Parameterization p(&dh, fit);
  auto kind_of = [&](const double* block) { return p.Find(block)->kind; };
  EXPECT_EQ(kind_of(dh.base.q.data()), BlockKind::kQuaternion);
  EXPECT_EQ(kind_of(dh.links[0].p.data()), BlockKind::kSubset);
  EXPECT_EQ(p.Find(dh.links[0].p.data())->frozen, (std::vector<int>{kDhD, kDhGamma}));
  EXPECT_EQ(kind_of(dh.links[1].p.data()), BlockKind::kConstant);
  EXPECT_EQ(kind_of(dh.edm.q.data()), BlockKind::kNoRoll);
  EXPECT_EQ(kind_of(dh.cams[0].intrinsics.data()), BlockKind::kConstant);
  const BlockDecision* dist = p.Find(dh.cams[0].distortion.data());
  ASSERT_EQ(dist->columns.size(), 2u);
  EXPECT_EQ(dist->columns[0].name, "cam[0].p1");
  EXPECT_EQ(dist->columns[1].effect, Effect::kTangentialDistortion);
  EXPECT_EQ(p.Find(dh.EffectValue(Effect::kEdmScale).data())->columns.size(), 1u);
  EXPECT_EQ(p.FixedGauges().size(), 3u);

  InstrumentModel sph = Truth(Kinematics::kSpherical);
  const Parameterization q(&sph, fit);
  EXPECT_EQ(q.Find(sph.edm.q.data())->kind, BlockKind::kConstant);
  EXPECT_EQ(q.Find(sph.edm.t.data())->frozen, (std::vector<int>{2}));
  EXPECT_EQ(q.Find(sph.links[0].p.data()), nullptr);  // spherical has no links in its chain
  // No distortion group enabled: the whole block is held.
  EXPECT_EQ(q.Find(sph.cams[0].distortion.data())->kind, BlockKind::kConstant);
}

// Klug Eq. 98's window: centred on the values at decision time.
TEST(Parameterization, TranslationWindowIsCentredOnTheStart) {
  FitOptions fit;
  fit.translation_bound_m = 0.1;
  InstrumentModel m = Truth(Kinematics::kDh);
  const Parameterization p(&m, fit);
  EXPECT_TRUE(p.OutsideBounds().empty());
  m.cams[0].flange_from_cam.t[1] += 0.05;  // inside the window
  EXPECT_TRUE(p.OutsideBounds().empty());
  m.base.t[0] += 0.2;  // outside
  EXPECT_EQ(p.OutsideBounds(), (std::vector<std::string>{"base.t"}));
}

TEST(GroupObservations, GroupsByPointingAndTool) {
  const InstrumentModel truth = Truth(Kinematics::kDh);
  const Observations obs = SmallData(truth);
  FitOptions fit;
  const UsedRows rows = SelectRows(obs, fit, truth.NumZooms(), UnknownZoom::kThrow);
  const auto grouped = GroupObservations(obs, rows);
  EXPECT_LT(grouped.size(), rows.records.size());
  size_t total = 0;
  for (const ObservationGroup& g : grouped) {
    total += g.indices.size();
    for (int i : g.indices) {
      const Record& r = obs.records[i];
      EXPECT_EQ(r.phi, g.phi);
      EXPECT_EQ(r.theta, g.theta);
      EXPECT_EQ(r.tool == Tool::kEdm, g.kind == ObsGroup::kEdm);
    }
  }
  EXPECT_EQ(total, rows.records.size());
}

TEST(SelectRows, UnknownZoomThrowsOrIsSkipped) {
  const InstrumentModel truth = Truth(Kinematics::kDh);
  Observations obs = SmallData(truth);
  obs.records_source = "records.csv";
  Record& r = obs.records.back();
  r.tool = Tool::kCam;
  r.zoom = 3;
  r.theta = M_PI / 2;  // outside the critical regions
  FitOptions fit;
  EXPECT_THROW(SelectRows(obs, fit, truth.NumZooms(), UnknownZoom::kThrow), std::invalid_argument);
  const UsedRows rows = SelectRows(obs, fit, truth.NumZooms(), UnknownZoom::kSkip);
  EXPECT_EQ(rows.records.size() + static_cast<size_t>(rows.excluded_critical),
            obs.records.size() - 1);
}

}  // namespace
}  // namespace rtscalib

namespace rtscalib {
namespace {

// model.<group>.coefficients (HoldDistortion): for every distortion group,
// kinematics and intrinsics mode, fitting only the group's first coefficient
// (or none of it) frees exactly that in the refinement, and the diagnosis's
// linearisation has the same free set; held coefficients are at their
// configured start value, or 0.
TEST(Parameterization, HeldDistortionCoefficientsAreHeldByRefinementAndDiagnosis) {
  for (Kinematics k : {Kinematics::kDh, Kinematics::kSpherical}) {
    const InstrumentModel baseline = Truth(k);
    const Observations obs = SmallData(baseline);
    for (bool fit_intrinsics : {false, true}) {
      FitOptions fit;
      fit.fit_intrinsics = fit_intrinsics;
      fit.num_threads = 1;
      for (const EffectInfo& info : EffectCatalogue()) {
        if (info.kind != EffectKind::kDistortion) continue;
        for (bool none : {false, true}) {
          SCOPED_TRACE(CaseName(k, info.effect, fit_intrinsics) + (none ? ", none fitted" : ""));
          InstrumentModel m = baseline;
          m.effects.Add(info.effect);
          for (int i : info.distortion_indices) m.cams[0].distortion[i] = 1e-3;
          std::vector<CameraTool> configured(1);
          configured[0].distortion[info.distortion_indices.back()] = 2e-4;
          DistortionChoice choice;
          choice.group = info.effect;
          if (!none) choice.coefficients = {info.distortion_indices.front()};
          HoldDistortion({choice}, configured, &m);

          const std::vector<std::string> refinement = RefinementColumns(m, fit);
          for (int i : info.distortion_indices) {
            const std::string name = std::string("cam[0].") + kDistortionCoefficientNames[i];
            const bool fitted = !none && i == info.distortion_indices.front();
            EXPECT_EQ(std::count(refinement.begin(), refinement.end(), name), fitted ? 1 : 0)
                << name;
            EXPECT_EQ(DistortionIsFree(m, 0, i), fitted);
            const double start = fitted ? 1e-3 : i == info.distortion_indices.back() ? 2e-4 : 0.0;
            EXPECT_EQ(m.cams[0].distortion[i], start) << name;
          }
          LinearizeOptions lo;
          lo.fit = fit;
          const Linearization lin = Linearize(obs, m, lo);
          EXPECT_EQ(lin.base_names, refinement);
        }
      }
    }
  }
}

TEST(Parameterization, HoldDistortionRejectsZoomsAndGroupsTheModelLacks) {
  InstrumentModel m = Truth(Kinematics::kDh);
  DistortionChoice choice;
  choice.group = Effect::kRadialDistortion;
  choice.coefficients = {kK1};
  EXPECT_THROW(HoldDistortion({choice}, {}, &m), std::invalid_argument);  // not enabled
  m.effects.Add(Effect::kRadialDistortion);
  choice.zooms[3] = {kK1};
  try {
    HoldDistortion({choice}, {}, &m);
    ADD_FAILURE() << "zoom 3 of a one-zoom model";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("model.radial_distortion.zooms"), std::string::npos);
  }
}

}  // namespace
}  // namespace rtscalib

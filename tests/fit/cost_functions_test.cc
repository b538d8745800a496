// Derivatives of the refinement's residuals, checked at three levels as
// COLMAP's models_jacobian_test does: ceres::GradientChecker (autodiff against Ridders' numeric
// differences) on RecordGroupResidual and ShotResidual in both kinematics
// with kinematic/EDM effects and every distortion group enabled, and the
// ShotResidual's projection Jacobian (the camera's ProjectWithJacobian)
// chained onto the wide jets (LocalCamera) against plain autodiff through
// ProjectToPixel in the wide jets: the same formula (opencv_model.h), so the
// two agree to rounding, far closer than numeric differences can check.
#include "libcalib/fit/cost_functions.h"

#include <ceres/gradient_checker.h>
#include <ceres/manifold.h>
#include <gtest/gtest.h>

#include <memory>

#include "libcalib/sim/simulator.h"

namespace rtscalib {
namespace {

// A model with every effect its kinematics can fit switched on at a non-zero
// value, and all 14 distortion coefficients non-zero.
InstrumentModel ModelWithEverything(Kinematics k) {
  InstrumentModel m;
  if (k == Kinematics::kDh) {
    m = PaperTruth(1);
  } else {
    m = IdealModel(Kinematics::kSpherical, 1, PaperTruth(1).cams[0]);
    m.base = PoseBlock::FromRigid(Rigid3::FromEuler({1e-3, -2e-3, 0.4}, {0.3, -0.2, 1.5}));
    m.cams[0].flange_from_cam =
        PoseBlock::FromRigid(Rigid3::FromEuler({2e-3, -1e-3, 4e-3}, {1e-3, -2e-3, 3e-2}));
    m.edm.t = {2e-4, -1e-4, 0.0};
  }
  for (const EffectInfo& info : EffectCatalogue()) {
    if (k == Kinematics::kDh && info.redundant_in_dh) continue;
    m.effects.Add(info.effect);
    if (IsKinematic(info.effect)) m.EffectValue(info.effect) = {3e-5, -2e-5};
  }
  m.cams[0].distortion = {-0.12, 0.05, 8e-4,  -5e-4, -0.01, 0.05, -0.01,
                          0.002, 1e-3, -5e-4, -8e-4, 3e-4,  0.01, -0.015};
  m.cams[0].focus = {0.03, 8.0, -5.0};  // SPEC 4.1: kf 30 mm, au, av [px m]
  return m;
}

std::vector<const ceres::Manifold*> ManifoldsFor(
    const BlockLayout& layout, std::vector<std::unique_ptr<ceres::Manifold>>* own) {
  std::vector<const ceres::Manifold*> out(layout.blocks.size(), nullptr);
  std::vector<int> rotations = {layout.base_q, layout.tool_q};
  for (const auto& b : layout.boards) rotations.push_back(b.first);
  for (int i : rotations) {
    own->push_back(std::make_unique<ceres::EigenQuaternionManifold>());
    out[i] = own->back().get();
  }
  return out;
}

int TotalSize(const BlockLayout& layout) {
  int n = 0;
  for (int s : layout.sizes) n += s;
  return n;
}

// GradientChecker's numeric derivatives use steps relative to each
// parameter (1e-8, at least sqrt(eps)): small enough for the distortion and
// the undistortion's trusted region, and their round-off is ~1e-8 of the
// residual scale. Ceres's own verdict is per entry relative to that entry,
// which fails on derivatives that are genuinely ~1e-9 (a rational
// coefficient's effect near the image centre). The comparison here is
// relative to the largest entry of the same block, the scale at which the
// solver sees that block: 1e-6 of it, 100 x the numeric round-off.
constexpr double kBlockRelativePrecision = 1e-6;

void ExpectGradientsMatch(ceres::CostFunction* cost, const BlockLayout& layout) {
  std::vector<std::unique_ptr<ceres::Manifold>> own;
  const std::vector<const ceres::Manifold*> manifolds = ManifoldsFor(layout, &own);
  ceres::NumericDiffOptions nd;
  nd.relative_step_size = 1e-8;
  nd.ridders_relative_initial_step_size = 1e-4;
  ceres::GradientChecker checker(cost, &manifolds, nd);
  ceres::GradientChecker::ProbeResults results;
  std::vector<const double*> params(layout.blocks.begin(), layout.blocks.end());
  checker.Probe(params.data(), kBlockRelativePrecision, &results);
  ASSERT_TRUE(results.return_value) << results.error_log;
  ASSERT_EQ(results.local_jacobians.size(), layout.blocks.size());
  for (size_t b = 0; b < layout.blocks.size(); ++b) {
    const Eigen::MatrixXd& user = results.local_jacobians[b];
    const Eigen::MatrixXd& numeric = results.local_numeric_jacobians[b];
    const double scale = std::max(numeric.cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_GT(user.cwiseAbs().maxCoeff(), 0.0) << "block " << b << " has no derivative";
    EXPECT_LE((user - numeric).cwiseAbs().maxCoeff(), kBlockRelativePrecision * scale)
        << "block " << b << "\nautodiff:\n"
        << user << "\nnumeric:\n"
        << numeric;
  }
}

class CostFunctionGradients : public ::testing::TestWithParam<Kinematics> {};

TEST_P(CostFunctionGradients, EdmRecordGroup) {
  InstrumentModel m = ModelWithEverything(GetParam());
  auto* f = new RecordGroupResidual;
  f->layout = LayoutFor(&m, -1);
  f->edm = true;
  f->phi = 0.7;
  f->theta = 1.2;
  for (double d : {1.3, 7.9, 31.0}) {
    f->rows.push_back({0, 0, d, PredictEdm(m, 0.71, 1.21, d), 1.0 / 1e-5});
  }
  const BlockLayout layout = f->layout;
  std::unique_ptr<ceres::CostFunction> cost(MakeCost(f, 9, TotalSize(layout)));
  ExpectGradientsMatch(cost.get(), layout);
}

TEST_P(CostFunctionGradients, CameraRecordGroupWithDistortion) {
  InstrumentModel m = ModelWithEverything(GetParam());
  auto* f = new RecordGroupResidual;
  f->layout = LayoutFor(&m, 0);
  f->edm = false;
  f->phi = 2.1;
  f->theta = 1.9;
  for (const auto& [u, v] :
       std::vector<std::pair<double, double>>{{640, 480}, {100, 80}, {1200, 900}}) {
    f->rows.push_back({u, v, 2.5, PredictCam(m, 0, 2.11, 1.89, u, v, 2.5), 1.0 / 1e-5});
  }
  const BlockLayout layout = f->layout;
  std::unique_ptr<ceres::CostFunction> cost(MakeCost(f, 9, TotalSize(layout)));
  ExpectGradientsMatch(cost.get(), layout);
}

// SPEC 7: records of a point of unknown position, x from the point's block.
TEST_P(CostFunctionGradients, EdmRecordGroupOfAnUnknownPoint) {
  InstrumentModel m = ModelWithEverything(GetParam());
  EstimatedPoint prism;
  prism.name = "P1";
  const Eigen::Vector3d x = PredictEdm(m, 0.71, 1.21, 7.9);
  prism.x = {x.x() + 1e-3, x.y() - 2e-3, x.z()};
  auto* f = new RecordGroupResidual;
  f->layout = LayoutFor(&m, -1);
  f->layout.points.push_back(f->layout.Add(prism.x.data(), 3));
  f->edm = true;
  f->phi = 0.7;
  f->theta = 1.2;
  f->rows.push_back({0, 0, 7.9, Eigen::Vector3d::Zero(), 1.0 / 1e-5, 0});
  f->rows.push_back({0, 0, 3.1, PredictEdm(m, 0.7, 1.2, 3.1), 1.0 / 1e-5, -1});
  const BlockLayout layout = f->layout;
  std::unique_ptr<ceres::CostFunction> cost(MakeCost(f, 6, TotalSize(layout)));
  ExpectGradientsMatch(cost.get(), layout);
}

// Points over the whole image of a shot, observed 0.3 px off; the photo's
// focus distance (SPEC 4.1) is the centroid of its points, a function of
// the chain.
ShotResidual* MakeShot(InstrumentModel* m) {
  auto* f = new ShotResidual;
  f->layout = LayoutFor(m, 0);
  f->phi = 0.4;
  f->theta = 1.4;
  f->inv_sigma = 1.0 / 0.5;
  ShotResidual::FocusTerm known;
  for (double u : {30.0, 640.0, 1250.0}) {
    for (double v : {20.0, 480.0, 940.0}) {
      const Eigen::Vector3d X = PredictCam(*m, 0, f->phi, f->theta, u, v, 4.0);
      f->points.push_back({X, Eigen::Vector2d(u + 0.3, v - 0.3)});
      known.sum += X;
      ++known.count;
    }
  }
  f->focus_terms.push_back(known);
  f->focus_count = known.count;
  return f;
}

TEST_P(CostFunctionGradients, ShotWithDistortion) {
  InstrumentModel m = ModelWithEverything(GetParam());
  ShotResidual* f = MakeShot(&m);
  const BlockLayout layout = f->layout;
  const int n = 2 * static_cast<int>(f->points.size());
  std::unique_ptr<ceres::CostFunction> cost(MakeCost(f, n, TotalSize(layout)));
  ExpectGradientsMatch(cost.get(), layout);
}

// DynamicAutoDiffCostFunction with a stride below the parameter count
// differentiates in several passes; in each, some blocks carry zero jets
// (the chained projection must then add nothing for them).
TEST_P(CostFunctionGradients, ShotInSeveralPasses) {
  InstrumentModel m = ModelWithEverything(GetParam());
  ShotResidual* f = MakeShot(&m);
  const BlockLayout layout = f->layout;
  const int n = 2 * static_cast<int>(f->points.size());
  std::unique_ptr<ceres::CostFunction> cost(MakeCostWithStride<12>(f, n));
  ExpectGradientsMatch(cost.get(), layout);
}

// The same residual written the plain way: every point projected by
// ProjectToPixel in the wide jets.
struct PlainShotResidual {
  const ShotResidual* shot;
  const BlockLayout& layout() const { return shot->layout; }
  template <typename T>
  bool operator()(T const* const* p, T* r) const {
    const ModelView<T> view = shot->layout.View(p);
    const RigidT<T> ref_from_cam = RefFromFlange(view, T(shot->phi), T(shot->theta)) *
                                   PoseFromBlocks(p[shot->layout.tool_q], p[shot->layout.tool_t]);
    T intrinsics[kNumIntrinsics];
    if (!shot->PhotoIntrinsics(p, std::vector<RigidT<T>>(), ref_from_cam, intrinsics)) return false;
    for (size_t k = 0; k < shot->points.size(); ++k) {
      const Vec3<T> x_cam = ref_from_cam.InverseApply(shot->points[k].X.cast<T>());
      T pixel[2];
      if (!ProjectToPixel(intrinsics, p[shot->layout.distortion], x_cam.data(), pixel)) {
        return false;
      }
      for (int c = 0; c < 2; ++c)
        r[2 * k + c] = (pixel[c] - T(shot->points[k].uv[c])) * T(shot->inv_sigma);
    }
    return true;
  }
};

TEST_P(CostFunctionGradients, ShotChainedJacobianEqualsPlainAutodiff) {
  InstrumentModel m = ModelWithEverything(GetParam());
  ShotResidual* f = MakeShot(&m);
  const BlockLayout layout = f->layout;
  const int n = 2 * static_cast<int>(f->points.size());
  std::unique_ptr<ceres::CostFunction> fast(MakeCost(f, n, TotalSize(layout)));
  auto* plain_functor = new PlainShotResidual{f};
  ceres::DynamicAutoDiffCostFunction<PlainShotResidual, 16> plain(plain_functor);
  for (int s : layout.sizes) plain.AddParameterBlock(s);
  plain.SetNumResiduals(n);

  std::vector<const double*> params(layout.blocks.begin(), layout.blocks.end());
  std::vector<double> r_fast(n), r_plain(n);
  std::vector<std::vector<double>> j_fast, j_plain;
  std::vector<double*> jf, jp;
  for (int s : layout.sizes) {
    j_fast.emplace_back(n * s);
    j_plain.emplace_back(n * s);
  }
  for (size_t b = 0; b < layout.sizes.size(); ++b) {
    jf.push_back(j_fast[b].data());
    jp.push_back(j_plain[b].data());
  }
  ASSERT_TRUE(fast->Evaluate(params.data(), r_fast.data(), jf.data()));
  ASSERT_TRUE(plain.Evaluate(params.data(), r_plain.data(), jp.data()));
  // Same formula, different order of the chain rule: round-off only.
  for (int i = 0; i < n; ++i) EXPECT_NEAR(r_fast[i], r_plain[i], 1e-9) << i;
  for (size_t b = 0; b < layout.sizes.size(); ++b) {
    double scale = 0;
    for (double x : j_plain[b]) scale = std::max(scale, std::abs(x));
    for (size_t i = 0; i < j_plain[b].size(); ++i) {
      EXPECT_NEAR(j_fast[b][i], j_plain[b][i], 1e-9 * std::max(scale, 1.0))
          << "block " << b << " entry " << i;
    }
  }
}

// A point behind the camera makes the residual fail, never silently zero.
TEST_P(CostFunctionGradients, ShotBehindCameraFails) {
  InstrumentModel m = ModelWithEverything(GetParam());
  ShotResidual* f = MakeShot(&m);
  const Rigid3 ref_from_cam = RefFromCam(m, 0, f->phi, f->theta);
  f->points.push_back({ref_from_cam * Eigen::Vector3d(0.1, 0.1, -2.0), Eigen::Vector2d(0, 0)});
  const BlockLayout layout = f->layout;
  const int n = 2 * static_cast<int>(f->points.size());
  std::unique_ptr<ceres::CostFunction> cost(MakeCost(f, n, TotalSize(layout)));
  std::vector<const double*> params(layout.blocks.begin(), layout.blocks.end());
  std::vector<double> r(n);
  EXPECT_FALSE(cost->Evaluate(params.data(), r.data(), nullptr));
}

INSTANTIATE_TEST_SUITE_P(Kinematics, CostFunctionGradients,
                         ::testing::Values(Kinematics::kDh, Kinematics::kSpherical),
                         [](const auto& info) { return std::string(KinematicsName(info.param)); });

// SPEC 7: a shot of two boards of unknown pose, X = ref_from_board *
// corner_in_board with the boards' blocks, next to points of known X.
TEST_P(CostFunctionGradients, ShotOfBoardsOfUnknownPose) {
  InstrumentModel m = ModelWithEverything(GetParam());
  auto* f = MakeShot(&m);
  for (int b = 0; b < 2; ++b) {
    // A board 4 m along the shot's line of sight, turned a little.
    const Rigid3 ref_from_cam = RefFromCam(m, 0, f->phi, f->theta);
    EstimatedBoard board;
    board.board.rows = 2;
    board.board.cols = 3;
    board.board.first_id = 10 * b;
    const Rigid3 cam_from_board =
        Rigid3::FromEuler({0.2 - 0.3 * b, 0.1, 0.05}, {-0.3 + 0.2 * b, -0.1, 4.0});
    board.pose = PoseBlock::FromRigid(ref_from_cam * cam_from_board);
    m.boards.push_back(board);
  }
  for (int b = 0; b < 2; ++b) {
    EstimatedBoard& board = m.boards[b];
    f->layout.boards.push_back(
        {f->layout.Add(board.pose.q.data(), 4), f->layout.Add(board.pose.t.data(), 3)});
    // The photo's focus distance: the centroid of all its points, these
    // boards' corners included (through their pose blocks).
    ShotResidual::FocusTerm term;
    term.board = b;
    for (int tag = 0; tag < board.board.NumTags(); tag += 2) {
      for (int k = 0; k < 4; ++k) {
        const Eigen::Vector3d in_board = board.board.CornersInBoard(tag)[k];
        Eigen::Vector2d uv;
        ASSERT_TRUE(
            PredictPixel(m, 0, f->phi, f->theta, board.pose.ToRigid() * in_board, &uv, 4.0));
        f->points.push_back({in_board, uv + Eigen::Vector2d(0.2, -0.1), b});
        term.sum += in_board;
        ++term.count;
      }
    }
    f->focus_terms.push_back(term);
    f->focus_count += term.count;
  }
  const BlockLayout layout = f->layout;
  std::unique_ptr<ceres::CostFunction> cost(
      MakeCost(f, 2 * static_cast<int>(f->points.size()), TotalSize(layout)));
  ExpectGradientsMatch(cost.get(), layout);
}

// SPEC 4.1 with the photo's focus distance given (the focus_distance
// column): the focus terms' derivatives at that D, no chain through D.
TEST_P(CostFunctionGradients, ShotWithGivenFocusDistance) {
  InstrumentModel m = ModelWithEverything(GetParam());
  ShotResidual* f = MakeShot(&m);
  f->focus_distance = 6.5;
  f->focus_terms.clear();
  f->focus_count = 0;
  const BlockLayout layout = f->layout;
  ASSERT_GE(layout.focus, 0);
  const int n = 2 * static_cast<int>(f->points.size());
  std::unique_ptr<ceres::CostFunction> cost(MakeCost(f, n, TotalSize(layout)));
  ExpectGradientsMatch(cost.get(), layout);
}

}  // namespace
}  // namespace rtscalib

#include "libcalib/extract/tools.h"

#include <gtest/gtest.h>

#include <random>

#include "tests/extract/extract_fixture.h"

namespace rtscalib {
namespace {

// Exact data at unit scale; the camera tool's triangle is 1 mm wide, so its
// rotation carries ~1e-16 / 1e-3 rad of round-off. 1e-10 bounds both.
constexpr double kToolsExact = 1e-10;

std::vector<int> AllRows(const std::vector<Record>& records) {
  std::vector<int> rows;
  for (int i = 0; i < static_cast<int>(records.size()); ++i) {
    if (IsUsableForExtraction(records[i], ExtractOptions())) rows.push_back(i);
  }
  return rows;
}

TEST(BaseFromFirstFrame, IsTheFrameItself) {
  LinkFrame f;
  f.o = Eigen::Vector3d(1, 2, 3);
  f.x = Eigen::Vector3d(0, 1, 0);
  f.y = Eigen::Vector3d(0, 0, 1);
  f.z = Eigen::Vector3d(1, 0, 0);
  const Rigid3 b = BaseFromFirstFrame(f);
  EXPECT_LT((b.rotation - f.Rotation()).norm(), 1e-15);
  EXPECT_LT((b.translation - f.o).norm(), 1e-15);
}

// With the truth's base and links, the tools come out as the truth's (the
// EDM up to its roll about the ray, which is a convention).
TEST(ExtractTools, RecoverTheTruthToolsGivenTheChain) {
  std::mt19937 rng(3);
  const InstrumentModel truth = fixture::RandomTruth(rng, 1e-3, 1e-2);
  const auto records = fixture::PaperPlanRecords(truth);
  const auto rows = AllRows(records);
  const PrincipalPoint pp{{640, 480}, false};
  InstrumentModel chain = truth;
  chain.cams[0].flange_from_cam = PoseBlock();
  chain.edm = PoseBlock();
  const auto cam = ExtractCameraTool(records, rows, chain, 0, pp, &truth.cams[0], ExtractOptions());
  ASSERT_TRUE(cam.has_value());
  EXPECT_EQ(cam->poses, 24);
  EXPECT_LT(cam->rms, kToolsExact);
  const Rigid3 c_true = truth.cams[0].flange_from_cam.ToRigid();
  const Rigid3 c_found = cam->camera.flange_from_cam.ToRigid();
  EXPECT_LT((c_true.rotation - c_found.rotation).norm(), kToolsExact);
  EXPECT_LT((c_true.translation - c_found.translation).norm(), kToolsExact);

  chain.cams[0] = cam->camera;
  const auto edm = ExtractEdmTool(records, rows, chain, 0, ExtractOptions());
  ASSERT_TRUE(edm.has_value());
  const Rigid3 e_true = truth.edm.ToRigid();
  const Rigid3 e_found = edm->flange_from_edm.ToRigid();
  EXPECT_LT((e_true.rotation.col(2) - e_found.rotation.col(2)).norm(), kToolsExact);  // ray
  EXPECT_LT((e_true.translation - e_found.translation).norm(), kToolsExact);          // origin
  // Eq. 79: the EDM x axis is the camera x projected off the ray.
  const Eigen::Vector3d xc = c_true.rotation.col(0), z = e_found.rotation.col(2);
  EXPECT_LT(((xc - xc.dot(z) * z).normalized() - e_found.rotation.col(0)).norm(), kToolsExact);
  EXPECT_NE(edm->x_reference.find("camera x of zoom 0 at 24 poses"), std::string::npos);
}

// No camera: the EDM x axis comes from the flange x axis.
TEST(ExtractTools, EdmWithoutCameraUsesTheFlangeX) {
  const InstrumentModel ideal = IdealModel(Kinematics::kDh, 0, CameraTool{});
  fixture::PaperPlan plan;
  plan.cam = false;
  const auto records = fixture::PaperPlanRecords(ideal, plan);
  const auto edm = ExtractEdmTool(records, AllRows(records), ideal, -1, ExtractOptions());
  ASSERT_TRUE(edm.has_value());
  EXPECT_NE(edm->x_reference.find("flange x (no camera)"), std::string::npos);
  EXPECT_FALSE(ExtractEdmTool(records, {}, ideal, -1, ExtractOptions()).has_value());
}

}  // namespace
}  // namespace rtscalib

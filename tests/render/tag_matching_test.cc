// Which tags are expected, and that skipped tags are counted, never reported.
#include "render/tag_matching.h"

#include <gtest/gtest.h>

#include <cmath>

#include "render/scene_renderer.h"
#include "tests/render/render_fixture.h"

namespace rtscalib::render {
namespace {

using detect::TagDetection;
using detect::TagDetector;
using testing::AimAt;
using testing::EnsureDisplay;
using testing::FrontBoard;
using testing::SceneOf;
using testing::TestCamera;

int Count(const std::vector<ExpectedTag>& tags, TagStatus s) {
  int n = 0;
  for (const ExpectedTag& t : tags) n += t.status == s;
  return n;
}

// Exact classification, no rendering.
TEST(ExpectTagsTest, ClassifiesByGeometry) {
  const TagBoard board = FrontBoard();
  const TargetScene scene = SceneOf(board);
  const CameraTool cam = TestCamera(true);
  const Eigen::Vector3d centre = board.CentreInRef();

  std::vector<ExpectedTag> home = ExpectTags(scene, Rigid3(), cam);
  ASSERT_EQ(home.size(), 12u);
  EXPECT_EQ(Count(home, TagStatus::kVisible), 12);
  EXPECT_NEAR(home[0].bit_px, 1000 * 0.01 / 2.0, 0.1);  // 1 cm bits at 2 m, fx = 1000
  for (const ExpectedTag& t : home) EXPECT_LT(t.view_angle, 0.15);

  // Turned away: everything behind.
  Rigid3 away;
  away.rotation = Ry(M_PI);
  EXPECT_EQ(Count(ExpectTags(scene, away, cam), TagStatus::kBehind), 12);

  // From behind the board, looking at it: its unprinted side.
  const Rigid3 behind = AimAt(Eigen::Vector3d(0, 0, 4), centre, 640, 480, 0, cam);
  EXPECT_EQ(Count(ExpectTags(scene, behind, cam), TagStatus::kBackFacing), 12);

  // Looking past it.
  const Rigid3 past = AimAt(Eigen::Vector3d::Zero(), centre, 640 + 2000, 480, 0, cam);
  EXPECT_EQ(Count(ExpectTags(scene, past, cam), TagStatus::kOutside), 12);

  // Board centre at the image's left edge: the left columns are cut.
  const Rigid3 cut = AimAt(Eigen::Vector3d::Zero(), centre, 30, 480, 0, cam);
  const std::vector<ExpectedTag> at_edge = ExpectTags(scene, cut, cam);
  EXPECT_GT(Count(at_edge, TagStatus::kBorder), 0);
  EXPECT_GT(Count(at_edge, TagStatus::kVisible) + Count(at_edge, TagStatus::kOutside), 0);

  // Seen at 80 degrees from its normal: grazing.
  const Eigen::Vector3d side = centre + 2.0 * Eigen::Vector3d(std::sin(1.4), 0, -std::cos(1.4));
  const Rigid3 grazing = AimAt(side, centre, 640, 480, 0, cam);
  EXPECT_EQ(Count(ExpectTags(scene, grazing, cam), TagStatus::kGrazing), 12);

  // Far away: tiny bits.
  const Rigid3 far = AimAt(Eigen::Vector3d(0, 0, -30), centre, 640, 480, 0, cam);
  EXPECT_EQ(Count(ExpectTags(scene, far, cam), TagStatus::kSmall), 12);
}

TEST(ExpectTagsTest, OccludedByANearerBoard) {
  TargetScene scene = SceneOf(FrontBoard(3, 4, 3.0));
  TagBoard front = FrontBoard(1, 1, 1.5);
  front.first_id = 20;
  scene.boards.push_back(front);
  const std::vector<ExpectedTag> tags = ExpectTags(scene, Rigid3(), TestCamera(false));
  ASSERT_EQ(tags.size(), 13u);
  EXPECT_GT(Count(tags, TagStatus::kOccluded), 0);
  EXPECT_EQ(tags.back().status, TagStatus::kVisible);  // the near tag itself
}

// ChArUco and chessboards: one target per inner corner, its corner
// repeated; border and small judged by the four squares around it.
TEST(ExpectTagsTest, PointBoardsHaveOneCornerPerTarget) {
  TagBoard charuco;
  charuco.kind = BoardKind::kCharuco;
  charuco.family = "DICT_4X4_50";
  charuco.first_id = 100;
  charuco.rows = 5;
  charuco.cols = 7;
  charuco.square_size = 0.04;
  charuco.marker_size = 0.03;  // 6 bits of 5 mm
  charuco.ref_from_board.translation = Eigen::Vector3d(-0.14, -0.1, 1.0);
  TagBoard chessboard;
  chessboard.kind = BoardKind::kChessboard;
  chessboard.family = "chessboard";
  chessboard.first_id = 200;
  chessboard.rows = 6;
  chessboard.cols = 9;
  chessboard.square_size = 0.04;  // 8 bits of 5 mm
  chessboard.ref_from_board.translation = Eigen::Vector3d(-0.18, -0.12, 1.0);
  const CameraTool cam = TestCamera(false);
  for (const TagBoard& board : {charuco, chessboard}) {
    const TargetScene scene = SceneOf(board);
    const std::vector<ExpectedTag> home = ExpectTags(scene, Rigid3(), cam);
    ASSERT_EQ(static_cast<int>(home.size()), board.NumTags());
    EXPECT_EQ(Count(home, TagStatus::kVisible), board.NumTags()) << board.family;
    for (const ExpectedTag& t : home) {
      EXPECT_EQ(t.corners, 1);
      EXPECT_EQ(t.family, board.family);
      EXPECT_NEAR(t.bit_px, 1000 * 0.005 / 1.0, 0.1);  // 5 mm bits at 1 m, fx = 1000
      for (int c = 1; c < 4; ++c) {
        EXPECT_EQ(t.X[c], t.X[0]);
        EXPECT_EQ(t.uv[c], t.uv[0]);
      }
    }
    EXPECT_NEAR((home[0].X[0] - board.ref_from_board * board.CornersInBoard(0)[0]).norm(), 0,
                1e-15);
    // The inner corner 8 px inside the image edge: its squares reach beyond.
    const Eigen::Vector3d first = home[0].X[0];
    const Rigid3 cut = AimAt(Eigen::Vector3d::Zero(), first, 12, 400, 0, cam);
    const std::vector<ExpectedTag> at_edge = ExpectTags(scene, cut, cam);
    EXPECT_EQ(at_edge[0].status, TagStatus::kBorder) << board.family;
    EXPECT_GT(Count(at_edge, TagStatus::kVisible), 0);
    const Rigid3 far = AimAt(Eigen::Vector3d(0, 0, -2), board.CentreInRef(), 640, 480, 0, cam);
    EXPECT_EQ(Count(ExpectTags(scene, far, cam), TagStatus::kSmall), board.NumTags());
  }
}

// Rendered and detected: tags at the image border and at grazing angles are
// skipped and counted; every kept corner is a correct one.
void ExpectOnlyGoodCorners(const TargetScene& scene, const Rigid3& pose, const CameraTool& cam,
                           ShotStats* stats) {
  SceneRenderer renderer(scene);
  TagDetector detector;
  const std::vector<TagDetection> detections = detector.Detect(renderer.Render(pose, cam));
  const std::vector<ExpectedTag> expected = ExpectTags(scene, pose, cam);
  const std::vector<MatchedTag> kept = MatchDetections(detections, expected, MatchOptions(), stats);
  for (const MatchedTag& m : kept) {
    const ExpectedTag* e = nullptr;
    for (const ExpectedTag& t : expected) {
      if (t.id == m.id) e = &t;
    }
    ASSERT_NE(e, nullptr);
    EXPECT_EQ(e->status, TagStatus::kVisible);
    for (int k = 0; k < 4; ++k) EXPECT_LT((m.uv[k] - e->uv[k]).norm(), 0.2) << "tag " << m.id;
  }
  EXPECT_EQ(stats->found, static_cast<int>(kept.size()));
  EXPECT_EQ(stats->mismatched, 0);
  EXPECT_EQ(stats->unknown, 0);
  EXPECT_EQ(stats->expected, stats->found + stats->missed + stats->unrefined + stats->mismatched);
}

TEST(MatchDetectionsTest, BorderTagsAreSkippedAndCounted) {
  EnsureDisplay();
  const TargetScene scene = SceneOf(FrontBoard(4, 6, 2.0));
  const CameraTool cam = TestCamera(true);
  // Board centre near the top-left image corner: tags cut on two sides.
  const Rigid3 pose =
      AimAt(Eigen::Vector3d::Zero(), scene.boards[0].CentreInRef(), 60, 40, 0.1, cam);
  ShotStats stats;
  ExpectOnlyGoodCorners(scene, pose, cam, &stats);
  EXPECT_GT(stats.skipped_border, 0);
  EXPECT_GT(stats.found, 0);
  EXPECT_EQ(stats.missed, 0);
  EXPECT_EQ(stats.found, stats.expected);
  std::printf("border: %d found, %d skipped, %d detections dropped\n", stats.found,
              stats.skipped_border, stats.dropped_skipped);
}

TEST(MatchDetectionsTest, GrazingTagsAreSkippedAndCounted) {
  EnsureDisplay();
  const TargetScene scene = SceneOf(FrontBoard(3, 4, 2.0));
  const CameraTool cam = TestCamera(true);
  const Eigen::Vector3d centre = scene.boards[0].CentreInRef();
  // 72 degrees off the normal, from 1 m: libapriltag still decodes some of
  // these foreshortened tags; they must be dropped, not reported.
  const double angle = 72.0 * M_PI / 180.0;
  const Eigen::Vector3d eye = centre + 1.0 * Eigen::Vector3d(std::sin(angle), 0, -std::cos(angle));
  const Rigid3 pose = AimAt(eye, centre, 640, 480, 0, cam);
  ShotStats stats;
  ExpectOnlyGoodCorners(scene, pose, cam, &stats);
  // From this close the view angle varies over the board (~66-78 degrees):
  // most tags are beyond the 70 degree limit, the nearest-to-normal may not be.
  EXPECT_GE(stats.skipped_grazing, 10);
  EXPECT_EQ(stats.found, stats.expected);
  EXPECT_GT(stats.dropped_skipped, 0);  // libapriltag did decode grazing tags
  std::printf("grazing: %d skipped, %d detections dropped\n", stats.skipped_grazing,
              stats.dropped_skipped);
}

TEST(MatchDetectionsTest, CountsUnknownDuplicateAndMismatchedDetections) {
  const TargetScene scene = SceneOf(FrontBoard());
  const CameraTool cam = TestCamera(false);
  const std::vector<ExpectedTag> expected = ExpectTags(scene, Rigid3(), cam);
  TagDetection good;
  good.family = "tag36h11";
  good.id = 0;
  good.refinement = detect::CornerRefinement::kEdges;
  good.corners = expected[0].uv;
  TagDetection unknown = good;
  unknown.id = 300;
  TagDetection wrong_place = good;
  wrong_place.id = 1;  // tag 1 reported at tag 0's corners
  TagDetection unrefined = good;
  unrefined.id = 2;
  unrefined.corners = expected[2].uv;
  unrefined.refinement = detect::CornerRefinement::kNone;
  ShotStats stats;
  const std::vector<MatchedTag> kept = MatchDetections(
      {good, good, unknown, wrong_place, unrefined}, expected, MatchOptions(), &stats);
  ASSERT_EQ(kept.size(), 1u);
  EXPECT_EQ(kept[0].id, 0);
  EXPECT_EQ(stats.expected, 12);
  EXPECT_EQ(stats.found, 1);
  EXPECT_EQ(stats.duplicate, 1);
  EXPECT_EQ(stats.unknown, 1);
  EXPECT_EQ(stats.mismatched, 1);
  EXPECT_EQ(stats.unrefined, 1);
  EXPECT_EQ(stats.missed, 12 - 1 - 1 - 1);
  EXPECT_EQ(stats.rms_error_px, 0.0);
}

}  // namespace
}  // namespace rtscalib::render

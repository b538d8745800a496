#include "libcalib/io/targets_io.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "tests/io/io_test_util.h"

namespace rtscalib {
namespace {

using ::testing::HasSubstr;
using testing_io::CatchInputError;
using testing_io::TempDir;

constexpr const char* kName = "targets.yaml";

InputError TargetsError(const std::string& text,
                        const std::map<std::string, int>* family_codes = nullptr) {
  return CatchInputError([&] { ParseTargets(text, kName, family_codes); });
}

// Checks key path, line and the message's form "targets.yaml:L:C: key 'K'".
void ExpectKeyError(const InputError& e, const std::string& key, int line,
                    const std::string& expected_part, const std::string& got) {
  EXPECT_EQ(e.file, kName);
  EXPECT_EQ(e.key, key);
  EXPECT_EQ(e.line, line);
  EXPECT_THAT(e.expected, HasSubstr(expected_part));
  EXPECT_EQ(e.got, got);
  EXPECT_THAT(e.what(), HasSubstr(std::string(kName) + ":" + std::to_string(line)));
  EXPECT_THAT(e.what(), HasSubstr("key '" + key + "'"));
}

constexpr const char* kTwoBoards =
    "boards:\n"
    "  - {family: tag36h11, first_id: 0, rows: 6, cols: 8, tag_size: 0.06, spacing: 0.015}\n"
    "  - family: tag25h9\n"
    "    first_id: 48\n"
    "    rows: 2\n"
    "    cols: 3\n"
    "    tag_size: 0.1\n"
    "    spacing: 0.02\n"
    "    pose: {euler: [0.1, -0.2, 0.3], t: [1, 2, 3]}\n";

TEST(Targets, ReadsBoardsWithAndWithoutPose) {
  TempDir dir;
  const TargetScene scene = ReadTargets(dir.Write("targets.yaml", kTwoBoards));
  ASSERT_EQ(scene.boards.size(), 2u);
  const TagBoard& a = scene.boards[0];
  EXPECT_EQ(a.family, "tag36h11");
  EXPECT_EQ(a.first_id, 0);
  EXPECT_EQ(a.rows, 6);
  EXPECT_EQ(a.cols, 8);
  EXPECT_EQ(a.tag_size, 0.06);
  EXPECT_EQ(a.spacing, 0.015);
  EXPECT_FALSE(a.pose_known);
  const TagBoard& b = scene.boards[1];
  EXPECT_EQ(b.family, "tag25h9");
  EXPECT_EQ(b.first_id, 48);
  EXPECT_EQ(b.LastId(), 53);
  EXPECT_TRUE(b.pose_known);
  // R = Rz(g) Ry(b) Rx(a) (SPEC 1), built independently of RotationFromEuler.
  const Eigen::Matrix3d r = (Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(-0.2, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  // Round-off of a few products of unit-size numbers.
  EXPECT_LT((b.ref_from_board.rotation - r).norm(), 1e-14);
  EXPECT_EQ(b.ref_from_board.translation, Eigen::Vector3d(1, 2, 3));
}

TEST(Targets, UnknownKeysNameTheirPath) {
  InputError e = TargetsError(
      "boards:\n"
      "  - {family: tag36h11, first_id: 0, rows: 6, cols: 8, tag_sise: 0.06, spacing: 0.01}\n");
  ExpectKeyError(e, "boards[0].tag_sise", 2, "tag_size", "tag_sise");
  EXPECT_THAT(e.expected, HasSubstr("did you mean 'tag_size'"));
  e = TargetsError(
      "boards:\n"
      "  - {family: tag36h11, first_id: 0, rows: 6, cols: 8, tag_size: 0.06, spacing: 0.01,\n"
      "     pose: {euler: [0, 0, 0], t: [0, 0, 0], scale: 1}}\n");
  ExpectKeyError(e, "boards[0].pose.scale", 3, "euler", "scale");
  e = TargetsError("boards: []\nboard: {}\n");
  ExpectKeyError(e, "board", 2, "boards", "board");
}

TEST(Targets, MissingKeysAndEmptyListsAreErrors) {
  InputError e = TargetsError("targets: 1\n");
  EXPECT_EQ(e.key, "boards");
  e = TargetsError("boards: []\n");
  ExpectKeyError(e, "boards", 1, "a list of at least one board", "[]");
  e = TargetsError("boards:\n  - {family: tag36h11, first_id: 0, rows: 6, cols: 8, spacing: 0}\n");
  EXPECT_EQ(e.key, "boards[0].tag_size");
  EXPECT_THAT(e.expected, HasSubstr("required"));
  e = TargetsError(
      "boards:\n"
      "  - {family: tag36h11, first_id: 0, rows: 6, cols: 8, tag_size: 1, spacing: 0,\n"
      "     pose: {euler: [0, 0, 0]}}\n");
  EXPECT_EQ(e.key, "boards[0].pose.t");
  e = TargetsError("boards:\n  - tag36h11\n");
  ExpectKeyError(e, "boards[0]", 2, "a board (a mapping)", "tag36h11");
}

TEST(Targets, BadValuesNameKeyExpectedAndGot) {
  const std::string head = "boards:\n  - {family: tag36h11, ";
  struct Case {
    std::string fields, key, expected, got;
  };
  const std::vector<Case> cases = {
      {"first_id: -1, rows: 1, cols: 1, tag_size: 1, spacing: 0", "boards[0].first_id",
       "a tag id >= 0", "-1"},
      {"first_id: 0, rows: 0, cols: 1, tag_size: 1, spacing: 0", "boards[0].rows",
       "a number of rows >= 1", "0"},
      {"first_id: 0, rows: 1, cols: 2.5, tag_size: 1, spacing: 0", "boards[0].cols", "an integer",
       "2.5"},
      {"first_id: 0, rows: 1, cols: 0, tag_size: 1, spacing: 0", "boards[0].cols",
       "a number of columns >= 1", "0"},
      {"first_id: 0, rows: 1, cols: 1, tag_size: 0, spacing: 0", "boards[0].tag_size",
       "a tag size > 0 [m]", "0"},
      {"first_id: 0, rows: 1, cols: 1, tag_size: 1, spacing: -0.1", "boards[0].spacing",
       "a spacing >= 0 [m]", "-0.1"},
      {"first_id: 0, rows: 1, cols: 1, tag_size: 1, spacing: 0, pose: [1]", "boards[0].pose",
       "a pose {euler: [a, b, g], t: [x, y, z]}", "[1]"},
      {"first_id: 0, rows: 1, cols: 1, tag_size: 1, spacing: 0, pose: {euler: [0, 0], t: [0, 0, "
       "0]}",
       "boards[0].pose.euler", "a list of 3 numbers", "[0, 0]"},
      {"first_id: 0, rows: 1, cols: 1, tag_size: 1, spacing: 0, pose: {euler: [0, 0, 0], t: [0, "
       "0, .nan]}",
       "boards[0].pose.t[2]", "a finite number", ".nan"},
      // Found by fuzz/targets_fuzzer (corpus/targets/huge_ids.yaml): rows x
      // cols overflowed int and the id range left it.
      {"first_id: 2147483000, rows: 100000, cols: 100000, tag_size: 1, spacing: 0",
       "boards[0].rows", "not rows x cols = 100000 x 100000", "100000"},
      {"first_id: 0, rows: 300, cols: 200, tag_size: 1, spacing: 0", "boards[0].rows",
       "a board of at most 48714 tags", "300"},
      {"first_id: 2147483000, rows: 2, cols: 2, tag_size: 1, spacing: 0", "boards[0].first_id",
       "first_id + rows cols <= 1000000", "2147483000"},
  };
  for (const Case& c : cases) {
    const InputError e = TargetsError(head + c.fields + "}\n");
    ExpectKeyError(e, c.key, 2, c.expected, c.got);
  }
  // Found by the replayed targets fuzzer (mutation 419 of seed 1): a family
  // with a comma was accepted and written back unquoted, as another key.
  ExpectKeyError(TargetsError("boards:\n  - family: (ta, g25hT9\n    first_id: 0\n    rows: 1\n"
                              "    cols: 1\n    tag_size: 1\n    spacing: 0\n"),
                 "boards[0].family", 2, "a tag family name", "(ta, g25hT9");
}

TEST(Targets, OverlappingIdRangesNameBothBoards) {
  const InputError e = TargetsError(
      "boards:\n"
      "  - {family: tag36h11, first_id: 0, rows: 6, cols: 8, tag_size: 0.06, spacing: 0.015}\n"
      "  - {family: tag16h5, first_id: 10, rows: 6, cols: 8, tag_size: 0.06, spacing: 0.015}\n");
  ExpectKeyError(e, "boards[1].first_id", 3, "boards[0] at line 2 has ids 0..47", "10");
  EXPECT_THAT(e.expected, HasSubstr("this board 10..57"));
}

TEST(Targets, FamiliesAndIdsAreCheckedAgainstTheDetectableFamilies) {
  const std::map<std::string, int> codes = {{"tag36h11", 587}, {"tag16h5", 30}};
  EXPECT_NO_THROW(ParseTargets(
      "boards: [{family: tag16h5, first_id: 24, rows: 2, cols: 3, tag_size: 1, spacing: 0}]\n",
      kName, &codes));
  InputError e = TargetsError(
      "boards: [{family: tag36h12, first_id: 0, rows: 1, cols: 1, tag_size: 1, spacing: 0}]\n",
      &codes);
  ExpectKeyError(e, "boards[0].family", 1, "one of tag16h5, tag36h11", "tag36h12");
  EXPECT_THAT(e.expected, HasSubstr("did you mean 'tag36h11'"));
  e = TargetsError(
      "boards: [{family: tag16h5, first_id: 25, rows: 2, cols: 3, tag_size: 1, spacing: 0}]\n",
      &codes);
  ExpectKeyError(e, "boards[0].first_id", 1,
                 "<= 30 (the codes of tag16h5; this board needs ids 25..30)", "25");
}

TEST(Targets, UnreadableOrInvalidYamlIsAnError) {
  InputError e = CatchInputError([] { ReadTargets("/nonexistent/targets.yaml"); });
  EXPECT_EQ(e.subject, "cannot open file");
  e = TargetsError("boards: [\n");
  EXPECT_EQ(e.subject, "YAML syntax");
}

}  // namespace
}  // namespace rtscalib

namespace rtscalib {
namespace {

// ChArUco and chessboards (targets.h, targets_io.h): boards of points whose
// targets are the inner corners first_id + k, k = r (cols - 1) + c.
TEST(Targets, CharucoAndChessboardsAreBoardsOfInnerCorners) {
  const std::string text =
      "boards:\n"
      "  - {type: charuco, dictionary: DICT_4X4_50, first_id: 100, rows: 5, cols: 7, "
      "square_size: 0.04, marker_size: 0.03}\n"
      "  - {type: chessboard, first_id: 200, rows: 6, cols: 9, square_size: 0.025,\n"
      "     pose: {euler: [0.1, 0.2, 0.3], t: [1, 2, 3]}}\n"
      "  - {family: tag36h11, first_id: 0, rows: 2, cols: 2, tag_size: 0.06, spacing: 0.01}\n";
  const TargetScene s = ParseTargets(text, kName);
  ASSERT_EQ(s.boards.size(), 3u);
  const TagBoard& c = s.boards[0];
  EXPECT_EQ(c.kind, BoardKind::kCharuco);
  EXPECT_EQ(c.family, "DICT_4X4_50");
  EXPECT_EQ(c.NumTags(), 4 * 6);
  EXPECT_EQ(c.CornersPerTarget(), 1);
  EXPECT_FALSE(c.pose_known);
  // Inner corner k = 7: row 1, column 1 of the inner corners.
  EXPECT_TRUE(c.CornersInBoard(7)[0].isApprox(Eigen::Vector3d(0.08, 0.08, 0)));
  EXPECT_DOUBLE_EQ(c.Width(), 0.28);
  const TagBoard& b = s.boards[1];
  EXPECT_EQ(b.kind, BoardKind::kChessboard);
  EXPECT_EQ(b.NumTags(), 5 * 8);
  EXPECT_TRUE(b.pose_known);
  EXPECT_TRUE(b.CornersInBoard(9)[0].isApprox(Eigen::Vector3d(0.05, 0.05, 0)));
  EXPECT_EQ(s.AllCorners().size(), 24u + 40u + 16u);  // one per point target, four per tag

  // Written and read back: the same boards.
  TempDir dir;
  const std::string path = dir.Path("t.yaml");
  WriteTargets(path, s);
  const TargetScene again = ReadTargets(path);
  ASSERT_EQ(again.boards.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(again.boards[i].kind, s.boards[i].kind);
    EXPECT_EQ(again.boards[i].family, s.boards[i].family);
    EXPECT_EQ(again.boards[i].square_size, s.boards[i].square_size);
    EXPECT_EQ(again.boards[i].marker_size, s.boards[i].marker_size);
    EXPECT_EQ(again.boards[i].pose_known, s.boards[i].pose_known);
  }
}

TEST(Targets, PointBoardErrorsNameTheKey) {
  const std::string head = "boards:\n  - {";
  ExpectKeyError(TargetsError(head + "type: charucco, first_id: 0}\n"), "boards[0].type", 2,
                 "one of apriltag, charuco, chessboard", "charucco");
  // An AprilTag key on a chessboard is a typo of the chessboard's keys.
  EXPECT_EQ(TargetsError(head + "type: chessboard, first_id: 0, rows: 3, cols: 4, "
                                "square_size: 0.02, tag_size: 0.02}\n")
                .key,
            "boards[0].tag_size");
  ExpectKeyError(TargetsError(head + "type: chessboard, first_id: 0, rows: 1, cols: 4, "
                                     "square_size: 0.02}\n"),
                 "boards[0].rows", 2, "a number of rows of squares >= 4", "1");
  // OpenCV's chessboard detector takes no fewer than 3 x 3 inner corners: a
  // board of 3 rows of squares is refused here, not by OpenCV later.
  ExpectKeyError(TargetsError(head + "type: chessboard, first_id: 0, rows: 3, cols: 7, "
                                     "square_size: 0.02}\n"),
                 "boards[0].rows", 2, "3 inner corners", "3");
  ExpectKeyError(TargetsError(head + "type: chessboard, first_id: 0, rows: 5, cols: 2, "
                                     "square_size: 0.02}\n"),
                 "boards[0].cols", 2, "a number of columns of squares >= 4", "2");
  ExpectKeyError(TargetsError(head + "type: charuco, dictionary: DICT_4X4_50, first_id: 0, rows: 3, "
                                     "cols: 4, square_size: 0.02, marker_size: 0.02}\n"),
                 "boards[0].marker_size", 2, "a marker size > 0 and < square_size", "0.02");
  ExpectKeyError(TargetsError(head + "type: charuco, dictionary: 'DICT 4X4', first_id: 0, rows: 3, "
                                     "cols: 4, square_size: 0.02, marker_size: 0.01}\n"),
                 "boards[0].dictionary", 2, "an ArUco dictionary name", "DICT 4X4");
}

}  // namespace
}  // namespace rtscalib

namespace rtscalib {
namespace {

// SPEC 7.2: tag boards with a 2-bit border, Kalibr's id layout.
TEST(Targets, TagBoardsTakeBorderBitsAndWhereTheirIdsStart) {
  const std::string text =
      "boards:\n"
      "  - {family: tag36h11, first_id: 0, rows: 2, cols: 3, tag_size: 0.1, spacing: 0.03,\n"
      "     border_bits: 2, ids_from: bottom_left}\n"
      "  - {family: tag36h11, first_id: 10, rows: 2, cols: 3, tag_size: 0.1, spacing: 0.03}\n";
  const std::map<std::string, int> codes = {{"tag36h11", 587},
                                            {WideBorderKey("tag36h11"), 587},
                                            {"tagStandard41h12", 2115}};
  const TargetScene s = ParseTargets(text, kName, &codes);
  ASSERT_EQ(s.boards.size(), 2u);
  const TagBoard& kalibr = s.boards[0];
  EXPECT_EQ(kalibr.border_bits, 2);
  EXPECT_EQ(kalibr.ids_from, IdOrigin::kBottomLeft);
  EXPECT_EQ(s.boards[1].border_bits, 1);
  EXPECT_EQ(s.boards[1].ids_from, IdOrigin::kTopLeft);
  // Tag 0 is the bottom row's first (row 1 from the top), tag 3 above it.
  EXPECT_TRUE(kalibr.CornersInBoard(0)[3].isApprox(Eigen::Vector3d(0, 0.13, 0)));
  EXPECT_TRUE(kalibr.CornersInBoard(3)[3].isApprox(Eigen::Vector3d(0, 0, 0), 1e-12));
  EXPECT_TRUE(s.boards[1].CornersInBoard(0)[3].isApprox(Eigen::Vector3d(0, 0, 0), 1e-12));

  // Written and read back.
  TempDir dir;
  const std::string path = dir.Path("t.yaml");
  WriteTargets(path, s);
  const TargetScene again = ReadTargets(path, &codes);
  EXPECT_EQ(again.boards[0].border_bits, 2);
  EXPECT_EQ(again.boards[0].ids_from, IdOrigin::kBottomLeft);
  EXPECT_EQ(again.boards[1].border_bits, 1);

  const std::string head = "boards:\n  - {family: tag36h11, first_id: 0, rows: 1, cols: 1, "
                           "tag_size: 0.1, spacing: 0, ";
  ExpectKeyError(TargetsError(head + "border_bits: 3}\n"), "boards[0].border_bits", 2,
                 "a black border of 1 or 2 code bits", "3");
  ExpectKeyError(TargetsError(head + "ids_from: bottom}\n"), "boards[0].ids_from", 2,
                 "one of top_left, bottom_left", "bottom");
  // A family whose quad is not a black border's edge takes no wider border.
  ExpectKeyError(TargetsError("boards:\n  - {family: tagStandard41h12, first_id: 0, rows: 1, "
                              "cols: 1, tag_size: 0.1, spacing: 0, border_bits: 2}\n",
                              &codes),
                 "boards[0].border_bits", 2, "1 for family tagStandard41h12", "2");
  // A point board has no border_bits: a typo of its own keys.
  EXPECT_EQ(TargetsError("boards:\n  - {type: chessboard, first_id: 0, rows: 5, cols: 5, "
                         "square_size: 0.02, border_bits: 2}\n")
                .key,
            "boards[0].border_bits");
}

// Kalibr's own target files (SPEC 7.2), read wherever a targets.yaml is.
TEST(Targets, KalibrAprilGridIsOneTag36h11BoardWithKalibrsLayout) {
  const std::string text =
      "target_type: 'aprilgrid' #gridtype\n"
      "tagCols: 6               #number of apriltags\n"
      "tagRows: 5               #number of apriltags\n"
      "tagSize: 0.088           #size of apriltag, edge to edge [m]\n"
      "tagSpacing: 0.3          #ratio of space between tags to tagSize\n";
  const std::map<std::string, int> codes = {{"tag36h11", 587}, {WideBorderKey("tag36h11"), 587}};
  const TargetScene s = ParseTargets(text, kName, &codes);
  ASSERT_EQ(s.boards.size(), 1u);
  const TagBoard& b = s.boards[0];
  EXPECT_EQ(b.kind, BoardKind::kAprilTag);
  EXPECT_EQ(b.family, "tag36h11");
  EXPECT_EQ(b.border_bits, 2);
  EXPECT_EQ(b.first_id, 0);
  EXPECT_EQ(b.rows, 5);
  EXPECT_EQ(b.cols, 6);
  EXPECT_EQ(b.tag_size, 0.088);
  EXPECT_NEAR(b.spacing, 0.0264, 1e-15);
  EXPECT_FALSE(b.pose_known);
  // Kalibr's frame: tag 0 at the origin, the printed target's bottom-left,
  // ids to the right along a row, then up; corner 0 = (x0, y0), 1 = (x0 +
  // s, y0), 2 = (x0 + s, y0 + s), 3 = (x0, y0 + s) with y up. In SPEC 7's
  // frame (y down from the top row) the same corners are y_spec = H - y:
  // a rigid turn by 180 degrees about x, so every tag keeps its shape.
  const double pitch = 0.088 + 0.0264, height = b.Height();
  for (int id = 0; id < b.NumTags(); ++id) {
    const double x0 = pitch * (id % 6), y0 = pitch * (id / 6);  // Kalibr
    const Eigen::Vector3d kalibr[4] = {{x0, y0, 0}, {x0 + 0.088, y0, 0},
                                       {x0 + 0.088, y0 + 0.088, 0}, {x0, y0 + 0.088, 0}};
    const std::array<Eigen::Vector3d, 4> spec = b.CornersInBoard(id);
    for (int k = 0; k < 4; ++k) {
      EXPECT_NEAR(spec[k].x(), kalibr[k].x(), 1e-12) << id << " " << k;
      EXPECT_NEAR(spec[k].y(), height - kalibr[k].y(), 1e-12) << id << " " << k;
    }
  }

  // Other Kalibr keys (the checkerboard's, a typo) are errors naming the key.
  ExpectKeyError(TargetsError(text + "targetRows: 5\n"), "targetRows", 6, "", "targetRows");
  ExpectKeyError(TargetsError("target_type: aprilgrid\ntagCols: 6\ntagRows: 6\ntagSize: 0.088\n"
                              "tagSpaceing: 0.3\n"),
                 "tagSpaceing", 5, "did you mean 'tagSpacing'", "tagSpaceing");
  EXPECT_EQ(TargetsError("target_type: aprilgrid\ntagCols: 6\ntagRows: 6\ntagSize: 0.088\n").key,
            "tagSpacing");
  ExpectKeyError(TargetsError("target_type: aprilgrid\ntagCols: 6\ntagRows: 6\ntagSize: -1\n"
                              "tagSpacing: 0.3\n"),
                 "tagSize", 4, "a tag size > 0", "-1");
  ExpectKeyError(TargetsError("target_type: circlegrid\ntargetCols: 6\n"), "target_type", 1,
                 "aprilgrid or checkerboard", "circlegrid");
  // More tags than tag36h11 has codes.
  ExpectKeyError(TargetsError("target_type: aprilgrid\ntagCols: 30\ntagRows: 20\n"
                              "tagSize: 0.02\ntagSpacing: 0.3\n",
                              &codes),
                 "tagRows", 3, "at most 587 tags", "20");
}

TEST(Targets, KalibrCheckerboardIsAChessboardOfSquareSquares) {
  const std::string text =
      "target_type: 'checkerboard' #gridtype\n"
      "targetCols: 6               #number of internal chessboard corners\n"
      "targetRows: 7               #number of internal chessboard corners\n"
      "rowSpacingMeters: 0.06      #size of one chessboard square [m]\n"
      "colSpacingMeters: 0.06      #size of one chessboard square [m]\n";
  const TargetScene s = ParseTargets(text, kName);
  ASSERT_EQ(s.boards.size(), 1u);
  const TagBoard& b = s.boards[0];
  EXPECT_EQ(b.kind, BoardKind::kChessboard);
  EXPECT_EQ(b.rows, 8);
  EXPECT_EQ(b.cols, 7);
  EXPECT_EQ(b.NumTags(), 42);
  EXPECT_EQ(b.square_size, 0.06);
  EXPECT_FALSE(b.pose_known);
  // One square_size: row and column spacings that differ are refused.
  std::string other = text;
  other.replace(other.find("colSpacingMeters: 0.06"), 22, "colSpacingMeters: 0.05");
  ExpectKeyError(TargetsError(other), "colSpacingMeters", 5, "the same spacing as rowSpacingMeters",
                 "0.05");
  // Fewer than 3 inner corners: OpenCV's detector would refuse them.
  other = text;
  other.replace(other.find("targetRows: 7"), 13, "targetRows: 2");
  ExpectKeyError(TargetsError(other), "targetRows", 3, "inner corners along a column >= 3", "2");
  // The aprilgrid's keys are unknown here.
  ExpectKeyError(TargetsError(text + "tagSize: 0.1\n"), "tagSize", 6, "", "tagSize");
}

}  // namespace
}  // namespace rtscalib

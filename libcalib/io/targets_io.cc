#include "libcalib/io/targets_io.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "libcalib/geometry/rotation.h"
#include "libcalib/text/errors.h"
#include "libcalib/text/number_text.h"
#include "libcalib/io/safe_write.h"
#include "libcalib/io/yaml_reader.h"

namespace rtscalib {
namespace {

// ArUco dictionaries in the family_codes map (ArucoCodesKey).
const std::string kArucoPrefix = "aruco:";
// Tag families that may be printed with a wider black border (WideBorderKey).
const std::string kWideBorderPrefix = "wide_border:";
// The widest black border a tag board may have [code bits]: Kalibr's 2.
constexpr int kMaxBorderBits = 2;
// OpenCV's chessboard detector needs at least 3 x 3 inner corners
// (findChessboardCornersSB refuses smaller patterns).
constexpr int kMinChessboardSquares = 4;

const std::vector<std::pair<std::string, IdOrigin>> kIdOrigins = {
    {"top_left", IdOrigin::kTopLeft}, {"bottom_left", IdOrigin::kBottomLeft}};

// Bounds that no AprilTag board reaches (see ReadScene).
constexpr long long kMaxTagsPerBoard = 48714;
constexpr long long kMaxTagId = 999999;

const std::vector<std::pair<std::string, BoardKind>> kKinds = {
    {"apriltag", BoardKind::kAprilTag},
    {"charuco", BoardKind::kCharuco},
    {"chessboard", BoardKind::kChessboard}};

// The keys of a board of each kind (besides `type` and `pose`).
std::vector<const char*> KeysOf(BoardKind kind) {
  switch (kind) {
    case BoardKind::kCharuco:
      return {"dictionary", "first_id", "rows", "cols", "square_size", "marker_size"};
    case BoardKind::kChessboard:
      return {"first_id", "rows", "cols", "square_size"};
    case BoardKind::kAprilTag:
      break;
  }
  return {"family", "first_id", "rows", "cols", "tag_size", "spacing", "border_bits", "ids_from"};
}

// A name (tag36h11, tagStandard41h12, DICT_4X4_50): letters, digits and '_',
// so that it is written back without quoting (WriteTargets).
std::string ReadName(const YamlNode& node, const std::string& what) {
  const std::string text = node.AsString();
  const bool name = !text.empty() && text.size() <= 64 &&
                    std::all_of(text.begin(), text.end(), [](char c) {
                      return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
                    });
  if (!name) node.Fail(what);
  return text;
}

double ReadLength(const YamlNode& item, const char* key, bool zero_ok, const std::string& what) {
  const YamlNode node = item.Require(key);
  const double x = node.AsDouble();
  if (!(zero_ok ? x >= 0 : x > 0)) node.Fail(what);
  return x;
}

}  // namespace

std::string ArucoCodesKey(const std::string& dictionary) { return kArucoPrefix + dictionary; }

std::string WideBorderKey(const std::string& family) { return kWideBorderPrefix + family; }

TagBoard ReadBoardLayout(const YamlNode& item, const std::map<std::string, int>* family_codes) {
  TagBoard b;
  item.ReadEnum("type", kKinds, &b.kind);
  if (b.kind == BoardKind::kAprilTag) {
    const YamlNode family = item.Require("family");
    b.family = ReadName(family, "a tag family name (letters, digits, '_'), e.g. tag36h11");
    if (family_codes != nullptr && family_codes->count(b.family) == 0) {
      std::vector<std::string> known;
      for (const auto& entry : *family_codes) known.push_back(entry.first);
      family.FailChoice(known);
    }
  } else if (b.kind == BoardKind::kCharuco) {
    const YamlNode dictionary = item.Require("dictionary");
    b.family = ReadName(dictionary, "an ArUco dictionary name (letters, digits, '_'), e.g. DICT_4X4_50");
    if (family_codes != nullptr && family_codes->count(ArucoCodesKey(b.family)) == 0) {
      std::vector<std::string> known;
      for (const auto& entry : *family_codes) {
        if (entry.first.rfind(kArucoPrefix, 0) == 0) known.push_back(entry.first.substr(kArucoPrefix.size()));
      }
      dictionary.FailChoice(known);
    }
  } else {
    b.family = "chessboard";
  }
  const YamlNode first_id = item.Require("first_id");
  b.first_id = first_id.AsInt();
  if (b.first_id < 0) first_id.Fail("a tag id >= 0");
  const int min_squares = b.kind == BoardKind::kChessboard ? kMinChessboardSquares
                          : b.IsPointBoard()                ? 2
                                                            : 1;
  const std::string why_min = b.kind == BoardKind::kChessboard
                                  ? " (3 inner corners: OpenCV's chessboard detector takes no fewer)"
                                  : "";
  const YamlNode rows = item.Require("rows");
  b.rows = rows.AsInt();
  if (b.rows < min_squares) {
    rows.Fail(b.IsPointBoard()
                  ? "a number of rows of squares >= " + std::to_string(min_squares) + why_min
                  : "a number of rows >= 1");
  }
  const YamlNode cols = item.Require("cols");
  b.cols = cols.AsInt();
  if (b.cols < min_squares) {
    cols.Fail(b.IsPointBoard()
                  ? "a number of columns of squares >= " + std::to_string(min_squares) + why_min
                  : "a number of columns >= 1");
  }
  // Memory and the tag ids stay bounded by what a tag family can hold (the
  // largest AprilTag family, tagStandard52h13, has 48,714 codes), not by a
  // value in the file: rows cols and first_id + rows cols must fit.
  const long long tags = static_cast<long long>(b.rows) * b.cols;
  if (tags > kMaxTagsPerBoard) {
    (b.rows >= b.cols ? rows : cols)
        .Fail("a board of at most " + std::to_string(kMaxTagsPerBoard) +
              " tags (the largest tag family's codes), not rows x cols = " +
              std::to_string(b.rows) + " x " + std::to_string(b.cols));
  }
  if (b.first_id > kMaxTagId - tags + 1) {
    first_id.Fail("a first_id with first_id + rows cols <= " + std::to_string(kMaxTagId + 1) +
                  " (no tag family has more codes)");
  }
  if (family_codes != nullptr && b.kind == BoardKind::kCharuco) {
    // The markers fill the white squares: rows cols / 2 of them, ids 0, 1, ...
    const int codes = family_codes->at(ArucoCodesKey(b.family));
    if (b.rows * b.cols / 2 > codes) {
      rows.Fail("a board whose " + std::to_string(b.rows * b.cols / 2) +
                " markers (rows cols / 2) fit in " + b.family + "'s " + std::to_string(codes) +
                " codes");
    }
  }
  if (family_codes != nullptr && b.kind == BoardKind::kAprilTag) {
    const int codes = family_codes->at(b.family);
    if (static_cast<long long>(b.first_id) + b.NumTags() > codes) {
      first_id.Fail("a first_id with first_id + rows cols <= " + std::to_string(codes) +
                    " (the codes of " + b.family + "; this board needs ids " +
                    std::to_string(b.first_id) + ".." +
                    std::to_string(static_cast<long long>(b.first_id) + b.NumTags() - 1) + ")");
    }
  }
  if (b.kind == BoardKind::kAprilTag) {
    b.tag_size = ReadLength(item, "tag_size", false, "a tag size > 0 [m]");
    b.spacing = ReadLength(item, "spacing", true, "a spacing >= 0 [m]");
    if (const std::optional<YamlNode> border = item.Find("border_bits")) {
      b.border_bits = border->AsInt();
      if (b.border_bits < 1 || b.border_bits > kMaxBorderBits) {
        border->Fail("a black border of 1 or " + std::to_string(kMaxBorderBits) +
                     " code bits (2: Kalibr's AprilGrid)");
      }
      if (b.border_bits > 1 && family_codes != nullptr &&
          family_codes->count(WideBorderKey(b.family)) == 0) {
        std::string known;
        for (const auto& entry : *family_codes) {
          if (entry.first.rfind(kWideBorderPrefix, 0) == 0) {
            known += (known.empty() ? "" : ", ") + entry.first.substr(kWideBorderPrefix.size());
          }
        }
        border->Fail("1 for family " + b.family + " (" +
                     (known.empty() ? std::string("no family detected here takes a wider border")
                                    : "a wider border is printed only on " + known) +
                     ")");
      }
    }
    item.ReadEnum("ids_from", kIdOrigins, &b.ids_from);
  } else {
    b.square_size = ReadLength(item, "square_size", false, "a square size > 0 [m]");
  }
  if (b.kind == BoardKind::kCharuco) {
    const YamlNode marker = item.Require("marker_size");
    b.marker_size = marker.AsDouble();
    if (!(b.marker_size > 0 && b.marker_size < b.square_size)) {
      marker.Fail("a marker size > 0 and < square_size (" + FormatDouble(b.square_size) +
                  ") [m]");
    }
  }
  return b;
}

namespace {

// A positive number at `key` of a Kalibr target file.
double ReadPositive(const YamlNode& root, const char* key, const std::string& what) {
  const YamlNode node = root.Require(key);
  const double x = node.AsDouble();
  if (!(x > 0)) node.Fail(what);
  return x;
}

// An integer >= `min` at `key` of a Kalibr target file.
int ReadCount(const YamlNode& root, const char* key, int min, const std::string& what) {
  const YamlNode node = root.Require(key);
  const int n = node.AsInt();
  if (n < min) node.Fail(what);
  return n;
}

// Kalibr's own target file (SPEC 7.2), `target_type` at its top:
//   aprilgrid:    tagCols, tagRows, tagSize [m], tagSpacing (gap / tagSize)
//   checkerboard: targetCols, targetRows (inner corners), rowSpacingMeters,
//                 colSpacingMeters [m]
// as one board of unknown pose. The AprilGrid is tag36h11 with a 2-bit
// border, ids from 0 at the bottom-left tag, rows counted upwards (Kalibr's
// target frame has y up the printed page; targets.h maps it onto SPEC 7's
// frame). Kalibr's checkerboard may give different row and column spacings;
// rtscalib's chessboards have square squares (one square_size), so two
// spacings that differ are an error naming colSpacingMeters.
TargetScene ReadKalibrTarget(const YamlDocument& doc, const YamlNode& type,
                             const std::map<std::string, int>* family_codes) {
  const YamlNode root = doc.Root();
  const std::string kind = type.AsString();
  const bool aprilgrid = kind == "aprilgrid";
  if (!aprilgrid && kind != "checkerboard") {
    type.Fail("a Kalibr target rtscalib detects: aprilgrid or checkerboard");
  }
  // Typos first (as in a targets.yaml): the other type's keys are unknown here.
  const std::vector<const char*> keys =
      aprilgrid ? std::vector<const char*>{"tagCols", "tagRows", "tagSize", "tagSpacing"}
                : std::vector<const char*>{"targetCols", "targetRows", "rowSpacingMeters",
                                           "colSpacingMeters"};
  for (const char* key : keys) root.Find(key);
  doc.CheckAllKeysUsed();

  TagBoard b;
  b.first_id = 0;
  b.pose_known = false;
  if (aprilgrid) {
    b.kind = BoardKind::kAprilTag;
    b.family = "tag36h11";
    b.border_bits = 2;
    b.ids_from = IdOrigin::kBottomLeft;
    if (family_codes != nullptr && family_codes->count(WideBorderKey(b.family)) == 0) {
      type.Fail("a target this program detects (no tag36h11 tags of a 2-bit border here)");
    }
    b.cols = ReadCount(root, "tagCols", 1, "a number of tag columns >= 1");
    b.rows = ReadCount(root, "tagRows", 1, "a number of tag rows >= 1");
    b.tag_size = ReadPositive(root, "tagSize", "a tag size > 0 [m] (the black border's outer edge)");
    b.spacing = b.tag_size * ReadPositive(root, "tagSpacing",
                                          "a gap between tags > 0, as a fraction of tagSize");
    // Ids 0 .. rows cols - 1 must be codes of the family (587 for tag36h11).
    long long max_tags = kMaxTagsPerBoard;
    if (family_codes != nullptr && family_codes->count(b.family) > 0) {
      max_tags = std::min<long long>(max_tags, family_codes->at(b.family));
    }
    if (static_cast<long long>(b.rows) * b.cols > max_tags) {
      root.Require("tagRows")
          .Fail("a grid of at most " + std::to_string(max_tags) + " tags (the codes of " +
                b.family + "), not tagRows x tagCols = " + std::to_string(b.rows) + " x " +
                std::to_string(b.cols));
    }
  } else {
    b.kind = BoardKind::kChessboard;
    b.family = "chessboard";
    const std::string corners = " >= 3 (OpenCV's chessboard detector takes no fewer)";
    b.cols = 1 + ReadCount(root, "targetCols", kMinChessboardSquares - 1,
                           "a number of inner corners along a row" + corners);
    b.rows = 1 + ReadCount(root, "targetRows", kMinChessboardSquares - 1,
                           "a number of inner corners along a column" + corners);
    if (static_cast<long long>(b.rows) * b.cols > kMaxTagsPerBoard) {
      root.Require("targetRows")
          .Fail("a board of at most " + std::to_string(kMaxTagsPerBoard) + " squares");
    }
    b.square_size = ReadPositive(root, "rowSpacingMeters", "a square size > 0 [m]");
    const YamlNode col = root.Require("colSpacingMeters");
    const double col_spacing = col.AsDouble();
    if (!(std::abs(col_spacing - b.square_size) <= 1e-9 * b.square_size)) {
      col.Fail("the same spacing as rowSpacingMeters (" + FormatDouble(b.square_size) +
               " m): rtscalib's chessboards have square squares");
    }
  }
  TargetScene scene;
  scene.boards.push_back(b);
  return scene;
}

TargetScene ReadScene(const YamlDocument& doc, const std::map<std::string, int>* family_codes) {
  const YamlNode root = doc.Root();
  if (const std::optional<YamlNode> type = root.Find("target_type")) {
    return ReadKalibrTarget(doc, *type, family_codes);
  }
  const YamlNode boards = root.Require("boards");
  if (!boards.IsSequence()) boards.Fail("a list of at least one board");
  // Typos first: a misspelt key must be named as such, not reported as the
  // correct key missing.
  for (const YamlNode& item : boards.Items()) {
    if (!item.IsMap()) item.Fail("a board (a mapping)");
    BoardKind kind = BoardKind::kAprilTag;
    item.ReadEnum("type", kKinds, &kind);
    for (const char* key : KeysOf(kind)) item.Find(key);
    if (const std::optional<YamlNode> pose = item.Find("pose"); pose && pose->IsMap()) {
      pose->Find("euler");
      pose->Find("t");
    }
  }
  doc.CheckAllKeysUsed();
  if (boards.Items().empty()) boards.Fail("a list of at least one board");

  TargetScene scene;
  std::vector<YamlNode> first_id_nodes;
  for (const YamlNode& item : boards.Items()) {
    TagBoard b = ReadBoardLayout(item, family_codes);
    const YamlNode first_id = item.Require("first_id");
    b.pose_known = false;
    if (const std::optional<YamlNode> pose = item.Find("pose")) {
      if (!pose->IsMap()) pose->Fail("a pose {euler: [a, b, g], t: [x, y, z]}");
      const std::vector<double> euler = pose->Require("euler").AsDoubles(3);
      const std::vector<double> t = pose->Require("t").AsDoubles(3);
      b.ref_from_board = Rigid3::FromEuler(Eigen::Vector3d(euler[0], euler[1], euler[2]),
                                           Eigen::Vector3d(t[0], t[1], t[2]));
      b.pose_known = true;
    }
    // Overlapping ids would make a pixels.csv `target` ambiguous.
    for (size_t j = 0; j < scene.boards.size(); ++j) {
      const TagBoard& o = scene.boards[j];
      if (b.first_id <= o.LastId() && o.first_id <= b.LastId()) {
        first_id.Fail("tag ids not used by another board (boards[" + std::to_string(j) +
                      "] at line " + std::to_string(first_id_nodes[j].line()) + " has ids " +
                      std::to_string(o.first_id) + ".." + std::to_string(o.LastId()) +
                      ", this board " + std::to_string(b.first_id) + ".." +
                      std::to_string(b.LastId()) + ")");
      }
    }
    first_id_nodes.push_back(first_id);
    scene.boards.push_back(b);
  }
  return scene;
}

}  // namespace

TargetScene ReadTargets(const std::string& path, const std::map<std::string, int>* family_codes) {
  // Boards take a few lines each: 4 MiB bounds what a runaway file costs.
  return ReadScene(YamlDocument::Load(path, std::uintmax_t{4} << 20, "a targets file"),
                   family_codes);
}

TargetScene ParseTargets(const std::string& text, const std::string& name,
                         const std::map<std::string, int>* family_codes) {
  return ReadScene(YamlDocument::Parse(text, name), family_codes);
}

void WriteTargets(const std::string& path, const TargetScene& scene, bool with_poses,
                  const std::string& comment) {
  std::ostringstream o;
  if (!comment.empty()) {
    std::istringstream lines(comment);
    for (std::string line; std::getline(lines, line);) o << "# " << line << "\n";
  }
  o << "boards:\n";
  for (const TagBoard& b : scene.boards) {
    o << "  - {";
    switch (b.kind) {
      case BoardKind::kAprilTag:
        o << "family: " << b.family;
        break;
      case BoardKind::kCharuco:
        o << "type: charuco, dictionary: " << b.family;
        break;
      case BoardKind::kChessboard:
        o << "type: chessboard";
        break;
    }
    o << ", first_id: " << b.first_id << ", rows: " << b.rows << ", cols: " << b.cols;
    if (b.IsPointBoard()) {
      o << ", square_size: " << FormatDouble(b.square_size);
      if (b.kind == BoardKind::kCharuco) o << ", marker_size: " << FormatDouble(b.marker_size);
    } else {
      o << ", tag_size: " << FormatDouble(b.tag_size) << ", spacing: " << FormatDouble(b.spacing);
      if (b.border_bits != 1) o << ", border_bits: " << b.border_bits;
      if (b.ids_from == IdOrigin::kBottomLeft) o << ", ids_from: bottom_left";
    }
    if (with_poses && b.pose_known) {
      const Eigen::Vector3d e = EulerFromRotation(b.ref_from_board.rotation);
      const Eigen::Vector3d& t = b.ref_from_board.translation;
      o << ",\n     pose: {euler: [" << FormatDouble(e[0]) << ", " << FormatDouble(e[1]) << ", "
        << FormatDouble(e[2]) << "], t: [" << FormatDouble(t[0]) << ", " << FormatDouble(t[1])
        << ", " << FormatDouble(t[2]) << "]}";
    }
    o << "}\n";
  }
  WriteFileAtomic(path, o.str());
}

}  // namespace rtscalib

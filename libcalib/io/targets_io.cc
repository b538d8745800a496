#include "libcalib/io/targets_io.h"

#include <algorithm>
#include <cctype>
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
  return {"family", "first_id", "rows", "cols", "tag_size", "spacing"};
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
  const int min_squares = b.IsPointBoard() ? 2 : 1;
  const YamlNode rows = item.Require("rows");
  b.rows = rows.AsInt();
  if (b.rows < min_squares) {
    rows.Fail(b.IsPointBoard() ? "a number of rows of squares >= 2" : "a number of rows >= 1");
  }
  const YamlNode cols = item.Require("cols");
  b.cols = cols.AsInt();
  if (b.cols < min_squares) {
    cols.Fail(b.IsPointBoard() ? "a number of columns of squares >= 2"
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

TargetScene ReadScene(const YamlDocument& doc, const std::map<std::string, int>* family_codes) {
  const YamlNode root = doc.Root();
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

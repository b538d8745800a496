#include "libcalib/io/targets_io.h"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "libcalib/geometry/rotation.h"
#include "libcalib/io/errors.h"
#include "libcalib/io/number_text.h"
#include "libcalib/io/yaml_reader.h"

namespace rtscalib {
namespace {

// Bounds that no AprilTag board reaches (see ReadScene).
constexpr long long kMaxTagsPerBoard = 48714;
constexpr long long kMaxTagId = 999999;

TargetScene ReadScene(const YamlDocument& doc, const std::map<std::string, int>* family_codes) {
  const YamlNode root = doc.Root();
  const YamlNode boards = root.Require("boards");
  if (!boards.IsSequence()) boards.Fail("a list of at least one board");
  // Typos first: a misspelt key must be named as such, not reported as the
  // correct key missing.
  for (const YamlNode& item : boards.Items()) {
    if (!item.IsMap()) item.Fail("a board (a mapping)");
    for (const char* key : {"family", "first_id", "rows", "cols", "tag_size", "spacing"}) {
      item.Find(key);
    }
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
    TagBoard b;
    const YamlNode family = item.Require("family");
    b.family = family.AsString();
    // A family is a name (tag36h11, tagStandard41h12): letters, digits and
    // '_', so that it is written back without quoting (WriteTargets).
    const bool name = !b.family.empty() && b.family.size() <= 64 &&
                      std::all_of(b.family.begin(), b.family.end(), [](char c) {
                        return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
                      });
    if (!name) family.Fail("a tag family name (letters, digits, '_'), e.g. tag36h11");
    if (family_codes != nullptr && family_codes->count(b.family) == 0) {
      std::vector<std::string> known;
      for (const auto& entry : *family_codes) known.push_back(entry.first);
      family.FailChoice(known);
    }
    const YamlNode first_id = item.Require("first_id");
    b.first_id = first_id.AsInt();
    if (b.first_id < 0) first_id.Fail("a tag id >= 0");
    const YamlNode rows = item.Require("rows");
    b.rows = rows.AsInt();
    if (b.rows < 1) rows.Fail("a number of rows >= 1");
    const YamlNode cols = item.Require("cols");
    b.cols = cols.AsInt();
    if (b.cols < 1) cols.Fail("a number of columns >= 1");
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
    if (family_codes != nullptr) {
      const int codes = family_codes->at(b.family);
      if (static_cast<long long>(b.first_id) + b.NumTags() > codes) {
        first_id.Fail("a first_id with first_id + rows cols <= " + std::to_string(codes) +
                      " (the codes of " + b.family + "; this board needs ids " +
                      std::to_string(b.first_id) + ".." +
                      std::to_string(static_cast<long long>(b.first_id) + b.NumTags() - 1) + ")");
      }
    }
    const YamlNode tag_size = item.Require("tag_size");
    b.tag_size = tag_size.AsDouble();
    if (!(b.tag_size > 0)) tag_size.Fail("a tag size > 0 [m]");
    const YamlNode spacing = item.Require("spacing");
    b.spacing = spacing.AsDouble();
    if (!(b.spacing >= 0)) spacing.Fail("a spacing >= 0 [m]");
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
  return ReadScene(YamlDocument::Load(path), family_codes);
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
    o << "  - {family: " << b.family << ", first_id: " << b.first_id << ", rows: " << b.rows
      << ", cols: " << b.cols << ", tag_size: " << FormatDouble(b.tag_size)
      << ", spacing: " << FormatDouble(b.spacing);
    if (with_poses && b.pose_known) {
      const Eigen::Vector3d e = EulerFromRotation(b.ref_from_board.rotation);
      const Eigen::Vector3d& t = b.ref_from_board.translation;
      o << ",\n     pose: {euler: [" << FormatDouble(e[0]) << ", " << FormatDouble(e[1]) << ", "
        << FormatDouble(e[2]) << "], t: [" << FormatDouble(t[0]) << ", " << FormatDouble(t[1])
        << ", " << FormatDouble(t[2]) << "]}";
    }
    o << "}\n";
  }
  std::ofstream f(path);
  f << o.str();
  f.close();
  if (!f) throw std::runtime_error("could not write " + path);
}

}  // namespace rtscalib

// Strict access to a YAML document (yaml-cpp underneath).
//
// Every key that the code asks for is remembered; at the end
// `YamlDocument::CheckAllKeysUsed()` reports every key that was never asked
// for, with its full path ("model.efects"), file, line and column, and the keys
// that are valid at that place (SPEC 5: a typo must never be silently
// ignored). Typed getters fail with an InputError naming file, key path,
// line/column, what was expected and what came.
//
// Usage:
//   YamlDocument doc = YamlDocument::Load(path);
//   YamlNode root = doc.Root();
//   if (auto model = root.Find("model")) model->Read("kinematics", &kinematics_name);
//   doc.CheckAllKeysUsed();
//
// A mapping or list that is present but empty (`simulate:`) reads as empty.
// A subtree owned by someone else (the render section) is taken whole with
// `ConsumeAll()`; its keys are then that owner's to check.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "libcalib/text/errors.h"

namespace rtscalib {

namespace yaml_internal {
struct State;
}

class YamlNode {
 public:
  const std::string& path() const { return path_; }  // "" for the document root
  const std::string& file() const;
  int line() const;    // 1-based, 0 if unknown
  int column() const;  // 1-based, 0 if unknown

  bool IsMap() const { return node_.IsMap() || node_.IsNull(); }
  bool IsSequence() const { return node_.IsSequence() || node_.IsNull(); }
  bool IsScalar() const { return node_.IsScalar(); }

  // --- mappings -----------------------------------------------------------
  // The child at `key`, or nullopt when absent. Either way `key` becomes a
  // known key here; a present child counts as used.
  std::optional<YamlNode> Find(const std::string& key) const;
  // Like Find, but the key must be present.
  YamlNode Require(const std::string& key) const;
  // A file type's header: `format: <format>` and `version: <version>` must
  // be present and equal (model.yaml, covariance.yaml).
  void RequireFormat(const std::string& format, int version) const;
  // Reads the child at `key` into *value if present; returns whether it was.
  bool Read(const std::string& key, double* value) const;
  bool Read(const std::string& key, int* value) const;
  bool Read(const std::string& key, bool* value) const;
  bool Read(const std::string& key, std::string* value) const;
  bool Read(const std::string& key, std::vector<double>* value) const;
  bool Read(const std::string& key, std::vector<int>* value) const;
  template <typename E>
  bool ReadEnum(const std::string& key, const std::vector<std::pair<std::string, E>>& names,
                E* value) const {
    const std::optional<YamlNode> child = Find(key);
    if (child) *value = child->AsEnum(names);
    return child.has_value();
  }
  // Entries in document order, for mappings whose keys are data (effect
  // names): `key` is the key as a node (AsString() is its text, errors point
  // at it), `value` its value; each counts as used.
  struct Entry;
  std::vector<Entry> Entries() const;

  // --- lists --------------------------------------------------------------
  std::vector<YamlNode> Items() const;

  // --- scalars ------------------------------------------------------------
  double AsDouble() const;       // finite
  double AsDoubleOrNan() const;  // finite, or .nan/.inf (uncertainties)
  int AsInt() const;
  std::uint64_t AsUint64() const;
  bool AsBool() const;  // true/false (and YAML 1.1 yes/no/on/off)
  std::string AsString() const;
  std::vector<double> AsDoubles() const;             // a list of finite numbers
  std::vector<double> AsDoubles(size_t size) const;  // ... of exactly `size`
  std::vector<int> AsInts() const;
  template <typename E>
  E AsEnum(const std::vector<std::pair<std::string, E>>& names) const {
    const std::string text = AsString();
    for (const auto& [name, value] : names) {
      if (text == name) return value;
    }
    std::vector<std::string> valid;
    for (const auto& entry : names) valid.push_back(entry.first);
    FailChoice(valid);
  }

  // Marks this whole subtree as used (its keys are checked by its owner).
  void ConsumeAll() const;
  // This subtree as YAML text.
  std::string Dump() const;

  // An InputError at this node: "expected `expected`, got <this value>".
  InputError Error(const std::string& expected) const;
  [[noreturn]] void Fail(const std::string& expected) const;
  // "expected one of a, b, c" (with a close match suggested).
  [[noreturn]] void FailChoice(const std::vector<std::string>& valid) const;

 private:
  friend class YamlDocument;
  YamlNode(std::shared_ptr<yaml_internal::State> state, YAML::Node node, std::string path,
           YAML::Mark mark)
      : state_(std::move(state)), node_(std::move(node)), path_(std::move(path)), mark_(mark) {}
  std::string ChildPath(const std::string& key) const;
  void RequireMap() const;
  const std::string& ScalarText(const std::string& expected) const;

  std::shared_ptr<yaml_internal::State> state_;
  YAML::Node node_;
  std::string path_;
  YAML::Mark mark_;  // of the value, or of the key when the value has none
};

struct YamlNode::Entry {
  YamlNode key;
  YamlNode value;
};

class YamlDocument {
 public:
  // Throws InputError when the file cannot be read or is not valid YAML, or
  // when its top level is not a mapping. A file larger than `max_bytes` is
  // refused before it is parsed: yaml-cpp holds a parsed document at ~50
  // times its size, so a runaway list under a mistyped key would cost
  // gigabytes before the key could be named. `what` names the kind of file
  // in that message ("a config").
  static YamlDocument Load(const std::string& path,
                           std::uintmax_t max_bytes = std::numeric_limits<std::uintmax_t>::max(),
                           const std::string& what = "a YAML file");
  // `name` names the text in messages.
  static YamlDocument Parse(const std::string& text, const std::string& name);

  YamlNode Root() const;
  // Every key never asked for (and duplicate keys), in document order.
  std::vector<InputError> UnusedKeys() const;
  // Throws all UnusedKeys() as one InputError (the first one's fields).
  void CheckAllKeysUsed() const;

 private:
  explicit YamlDocument(std::shared_ptr<yaml_internal::State> state) : state_(std::move(state)) {}
  std::shared_ptr<yaml_internal::State> state_;
};

// Fails naming `node` unless q = [x, y, z, w] has unit length to 1e-9: a
// quaternion off unit length (a hand edit) would scale every prediction;
// one taken as it is reads back bit for bit.
void RequireUnitQuaternion(const YamlNode& node, const double* q);

}  // namespace rtscalib

#include "libcalib/io/yaml_reader.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/parser.h>

#include "libcalib/text/number_text.h"

namespace rtscalib {
namespace yaml_internal {

struct State {
  std::string file;
  YAML::Node root;
  std::set<std::string> used;   // paths of mapping entries that were read
  std::set<std::string> whole;  // subtrees consumed whole (keys checked elsewhere)
  std::map<std::string, std::vector<std::string>> known;  // mapping path -> keys asked for
};

}  // namespace yaml_internal

namespace {

using yaml_internal::State;

int Line(const YAML::Mark& m) { return m.is_null() ? 0 : m.line + 1; }
int Column(const YAML::Mark& m) { return m.is_null() ? 0 : m.column + 1; }

std::string ChildOf(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

// A short one-line rendering of a value for "got '...'".
std::string Brief(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "";
  if (node.IsScalar()) return node.Scalar();
  YAML::Emitter e;
  e << YAML::Flow << node;
  std::string text = e.c_str();
  constexpr size_t kMaxChars = 60;
  if (text.size() > kMaxChars) text = text.substr(0, kMaxChars - 3) + "...";
  return text;
}

size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] != b[j - 1] ? 1 : 0)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

// "one of a, b, c" plus "(did you mean 'b'?)" when a typo is likely.
std::string OneOf(const std::vector<std::string>& valid, const std::string& got) {
  std::string out = "one of " + Join(valid);
  const std::string* best = nullptr;
  size_t best_distance = std::numeric_limits<size_t>::max();
  for (const std::string& v : valid) {
    const size_t d = EditDistance(v, got);
    if (d < best_distance) {
      best_distance = d;
      best = &v;
    }
  }
  if (best && best_distance > 0 && best_distance <= std::max<size_t>(1, best->size() / 3)) {
    out += " (did you mean '" + *best + "'?)";
  }
  return out;
}

void CollectUnused(const State& s, const YAML::Node& node, const std::string& path,
                   std::vector<InputError>* out) {
  if (s.whole.count(path)) return;
  if (node.IsMap()) {
    std::set<std::string> seen;
    const auto known = s.known.find(path);
    const std::vector<std::string> valid =
        known == s.known.end() ? std::vector<std::string>{} : known->second;
    for (auto it = node.begin(); it != node.end(); ++it) {
      const YAML::Mark mark = it->first.Mark();
      if (!it->first.IsScalar()) {
        out->push_back(InputError::Key(s.file, path.empty() ? "(top level)" : path, Line(mark),
                                       Column(mark), "a plain key", Brief(it->first)));
        continue;
      }
      const std::string& key = it->first.Scalar();
      const std::string key_path = ChildOf(path, key);
      if (!seen.insert(key).second) {
        out->push_back(InputError::Key(s.file, key_path, Line(mark), Column(mark),
                                       "each key once in its mapping (this one is repeated)", key));
        continue;
      }
      if (!s.used.count(key_path)) {
        const std::string where = path.empty() ? "the top level" : "'" + path + "'";
        const std::string expected =
            valid.empty() ? "no keys in " + where : "a key of " + where + ", " + OneOf(valid, key);
        out->push_back(InputError::Key(s.file, key_path, Line(mark), Column(mark), expected, key));
        continue;
      }
      CollectUnused(s, it->second, key_path, out);
    }
  } else if (node.IsSequence()) {
    for (size_t i = 0; i < node.size(); ++i) {
      CollectUnused(s, node[i], path + "[" + std::to_string(i) + "]", out);
    }
  }
}

}  // namespace

// ---------------------------------------------------------------------------
// YamlNode

const std::string& YamlNode::file() const { return state_->file; }
int YamlNode::line() const { return Line(mark_); }
int YamlNode::column() const { return Column(mark_); }

std::string YamlNode::ChildPath(const std::string& key) const { return ChildOf(path_, key); }

InputError YamlNode::Error(const std::string& expected) const {
  return InputError::Key(state_->file, path_.empty() ? "(top level)" : path_, line(), column(),
                         expected, Brief(node_));
}

void YamlNode::Fail(const std::string& expected) const { throw Error(expected); }

void YamlNode::FailChoice(const std::vector<std::string>& valid) const {
  Fail(OneOf(valid, node_.IsScalar() ? node_.Scalar() : ""));
}

void YamlNode::RequireMap() const {
  if (!IsMap()) Fail("a mapping (key: value pairs)");
}

std::optional<YamlNode> YamlNode::Find(const std::string& key) const {
  RequireMap();
  std::vector<std::string>& known = state_->known[path_];
  if (std::find(known.begin(), known.end(), key) == known.end()) known.push_back(key);
  if (node_.IsNull()) return std::nullopt;
  for (auto it = node_.begin(); it != node_.end(); ++it) {
    if (!it->first.IsScalar() || it->first.Scalar() != key) continue;
    const std::string child_path = ChildPath(key);
    state_->used.insert(child_path);
    // An empty value (`key:`) has no useful mark of its own; point at the key.
    const YAML::Mark mark =
        it->second.IsNull() || it->second.Mark().is_null() ? it->first.Mark() : it->second.Mark();
    return YamlNode(state_, it->second, child_path, mark);
  }
  return std::nullopt;
}

YamlNode YamlNode::Require(const std::string& key) const {
  std::optional<YamlNode> child = Find(key);
  if (!child) {
    throw InputError::Key(state_->file, ChildPath(key), line(), column(),
                          "a value (this key is required)", "nothing");
  }
  return *child;
}

void YamlNode::RequireFormat(const std::string& format, int version) const {
  const YamlNode f = Require("format");
  if (f.AsString() != format) f.Fail(format);
  const YamlNode v = Require("version");
  if (v.AsInt() != version) v.Fail("version " + std::to_string(version));
}

std::vector<YamlNode::Entry> YamlNode::Entries() const {
  RequireMap();
  std::vector<Entry> out;
  if (node_.IsNull()) return out;
  for (auto it = node_.begin(); it != node_.end(); ++it) {
    const YamlNode key(state_, it->first, path_, it->first.Mark());
    if (!it->first.IsScalar()) key.Fail("a plain key");
    YamlNode value = *Find(it->first.Scalar());
    out.push_back({YamlNode(state_, it->first, value.path(), it->first.Mark()), value});
  }
  return out;
}

std::vector<YamlNode> YamlNode::Items() const {
  if (!IsSequence()) Fail("a list");
  std::vector<YamlNode> out;
  if (node_.IsNull()) return out;
  for (size_t i = 0; i < node_.size(); ++i) {
    const YAML::Node item = node_[i];
    const YAML::Mark mark = item.Mark().is_null() ? mark_ : item.Mark();
    out.push_back(YamlNode(state_, item, path_ + "[" + std::to_string(i) + "]", mark));
  }
  return out;
}

const std::string& YamlNode::ScalarText(const std::string& expected) const {
  if (!node_.IsScalar()) Fail(expected);
  return node_.Scalar();
}

double YamlNode::AsDouble() const {
  const std::optional<double> value = ParseFiniteDouble(ScalarText("a finite number"));
  if (!value) Fail("a finite number");
  return *value;
}

double YamlNode::AsDoubleOrNan() const {
  const std::string& text = ScalarText("a number");
  // YAML's own spellings of the special values (what yaml-cpp writes).
  static const std::map<std::string, double> kSpecial = {
      {".nan", std::numeric_limits<double>::quiet_NaN()},
      {".NaN", std::numeric_limits<double>::quiet_NaN()},
      {".NAN", std::numeric_limits<double>::quiet_NaN()},
      {".inf", std::numeric_limits<double>::infinity()},
      {".Inf", std::numeric_limits<double>::infinity()},
      {"+.inf", std::numeric_limits<double>::infinity()},
      {"-.inf", -std::numeric_limits<double>::infinity()},
      {"-.Inf", -std::numeric_limits<double>::infinity()}};
  const auto special = kSpecial.find(text);
  if (special != kSpecial.end()) return special->second;
  const std::optional<double> value = ParseDouble(text);
  if (!value) Fail("a number");
  return *value;
}

int YamlNode::AsInt() const {
  const std::optional<long long> value = ParseInteger(ScalarText("an integer"));
  if (!value || *value < std::numeric_limits<int>::min() ||
      *value > std::numeric_limits<int>::max()) {
    Fail("an integer");
  }
  return static_cast<int>(*value);
}

std::uint64_t YamlNode::AsUint64() const {
  const std::optional<long long> value = ParseInteger(ScalarText("an integer >= 0"));
  if (!value || *value < 0) Fail("an integer >= 0");
  return static_cast<std::uint64_t>(*value);
}

bool YamlNode::AsBool() const {
  ScalarText("true or false");
  bool value = false;
  if (!YAML::convert<bool>::decode(node_, value)) Fail("true or false");
  return value;
}

std::string YamlNode::AsString() const { return ScalarText("a text value"); }

std::vector<double> YamlNode::AsDoubles() const {
  if (!IsSequence()) Fail("a list of numbers");
  std::vector<double> out;
  for (const YamlNode& item : Items()) out.push_back(item.AsDouble());
  return out;
}

std::vector<double> YamlNode::AsDoubles(size_t size) const {
  const std::string expected = "a list of " + std::to_string(size) + " numbers";
  if (!IsSequence() || node_.size() != size) Fail(expected);
  return AsDoubles();
}

std::vector<int> YamlNode::AsInts() const {
  if (!IsSequence()) Fail("a list of integers");
  std::vector<int> out;
  for (const YamlNode& item : Items()) out.push_back(item.AsInt());
  return out;
}

bool YamlNode::Read(const std::string& key, double* value) const {
  const std::optional<YamlNode> child = Find(key);
  if (child) *value = child->AsDouble();
  return child.has_value();
}
bool YamlNode::Read(const std::string& key, int* value) const {
  const std::optional<YamlNode> child = Find(key);
  if (child) *value = child->AsInt();
  return child.has_value();
}
bool YamlNode::Read(const std::string& key, bool* value) const {
  const std::optional<YamlNode> child = Find(key);
  if (child) *value = child->AsBool();
  return child.has_value();
}
bool YamlNode::Read(const std::string& key, std::string* value) const {
  const std::optional<YamlNode> child = Find(key);
  if (child) *value = child->AsString();
  return child.has_value();
}
bool YamlNode::Read(const std::string& key, std::vector<double>* value) const {
  const std::optional<YamlNode> child = Find(key);
  if (child) *value = child->AsDoubles();
  return child.has_value();
}
bool YamlNode::Read(const std::string& key, std::vector<int>* value) const {
  const std::optional<YamlNode> child = Find(key);
  if (child) *value = child->AsInts();
  return child.has_value();
}

void YamlNode::ConsumeAll() const { state_->whole.insert(path_); }

std::string YamlNode::Dump() const {
  YAML::Emitter e;
  e << node_;
  return e.c_str();
}

// ---------------------------------------------------------------------------
// YamlDocument

YamlDocument YamlDocument::Load(const std::string& path, std::uintmax_t max_bytes,
                                const std::string& what) {
  // A folder opens as a stream that reads nothing: it would pass as an
  // empty document and be reported as its first missing key.
  std::error_code folder_ec;
  if (std::filesystem::is_directory(path, folder_ec)) {
    throw InputError::File(path, 0, "is a folder",
                           what == "a YAML file" ? what : what + " (a YAML file)", "a folder");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw InputError::File(path, 0, "cannot open file", "a readable YAML file",
                           std::strerror(errno));
  }
  std::error_code ec;
  const std::uintmax_t bytes = std::filesystem::file_size(path, ec);
  if (!ec && bytes > max_bytes) {
    throw InputError::File(path, 0, "file size",
                           what + " of at most " + std::to_string(max_bytes >> 20) + " MiB",
                           std::to_string(bytes >> 20) + " MiB");
  }
  std::stringstream text;
  text << in.rdbuf();
  return Parse(text.str(), path);
}

namespace {

// Where a document's first content is (a scalar, a collection or an alias);
// a document without content (a trailing `---`) has none.
class FirstContent : public YAML::EventHandler {
 public:
  std::optional<YAML::Mark> mark;
  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark& m, YAML::anchor_t) override { Seen(m); }
  void OnScalar(const YAML::Mark& m, const std::string&, YAML::anchor_t,
                const std::string&) override {
    Seen(m);
  }
  void OnSequenceStart(const YAML::Mark& m, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {
    Seen(m);
  }
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark& m, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {
    Seen(m);
  }
  void OnMapEnd() override {}

 private:
  void Seen(const YAML::Mark& m) {
    if (!mark) mark = m;
  }
};

// Documents looked at after the first. yaml-cpp 0.7's LoadAll never returns
// on some malformed text (", 2]" : the parser hands out empty documents
// without advancing, and LoadAll collects them until memory runs out; found
// by fuzz/yaml_fuzzer.cc), so the documents are walked with a bound.
constexpr int kMaxDocuments = 16;

}  // namespace

YamlDocument YamlDocument::Parse(const std::string& text, const std::string& name) {
  auto state = std::make_shared<State>();
  state->file = name;
  try {
    state->root = YAML::Load(text);
    // A second document (after `---`) would be silently ignored by a reader
    // that takes the first: its keys would never take effect. An empty one
    // (a trailing `---`) holds no keys.
    std::stringstream stream(text);
    YAML::Parser parser(stream);
    for (int i = 0; i < kMaxDocuments; ++i) {
      FirstContent content;
      if (!parser.HandleNextDocument(content)) break;
      if (i == 0 || !content.mark) continue;
      // What the document holds, parsed from where its content starts.
      std::string got;
      try {
        got = Brief(YAML::Load(text.substr(std::min<size_t>(content.mark->pos, text.size()))));
      } catch (const YAML::Exception&) {
        got = "a document at line " + std::to_string(Line(*content.mark));
      }
      throw InputError::File(name, Line(*content.mark), "second YAML document",
                             "one YAML document per file (remove the '---' line before it)", got,
                             Column(*content.mark));
    }
  } catch (const YAML::Exception& e) {
    throw InputError::File(name, Line(e.mark), "YAML syntax", "valid YAML", e.msg, Column(e.mark));
  }
  // yaml-cpp reads some malformed text as an empty document (", 2]" is
  // null): text beyond comments and document markers that gave no value is
  // an error, not an empty config.
  if (state->root.IsNull()) {
    std::istringstream lines(text);
    std::string line;
    for (int number = 1; std::getline(lines, line); ++number) {
      const size_t first = line.find_first_not_of(" \t\r");
      if (first == std::string::npos || line[first] == '#') continue;
      const std::string content = line.substr(first);
      if (content.rfind("---", 0) == 0 || content.rfind("...", 0) == 0) continue;
      throw InputError::File(name, number, "YAML syntax", "a YAML mapping (key: value lines)",
                             content.substr(0, 60), static_cast<int>(first) + 1);
    }
  }
  YamlDocument doc(state);
  doc.Root().RequireMap();
  return doc;
}

YamlNode YamlDocument::Root() const {
  return YamlNode(state_, state_->root, "", state_->root.Mark());
}

std::vector<InputError> YamlDocument::UnusedKeys() const {
  std::vector<InputError> out;
  CollectUnused(*state_, state_->root, "", &out);
  return out;
}

void YamlDocument::CheckAllKeysUsed() const {
  const std::vector<InputError> unused = UnusedKeys();
  if (!unused.empty()) throw InputError::Combine(unused);
}

void RequireUnitQuaternion(const YamlNode& node, const double* q) {
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (!(std::fabs(norm - 1.0) <= 1e-9)) {
    node.Fail("a unit quaternion [x, y, z, w] (norm " + FormatShortestDouble(norm) + ")");
  }
}

}  // namespace rtscalib

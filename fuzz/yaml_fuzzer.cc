// The generic strict YAML access (libcalib/io/yaml_reader.h): parse any text,
// then walk the whole tree asking every node for every type. Each getter
// either returns a value of its documented kind or throws a clean InputError.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "fuzz/fuzz_util.h"
#include "libcalib/text/errors.h"
#include "libcalib/io/yaml_reader.h"

namespace {

using rtscalib::InputError;
using rtscalib::YamlNode;
using rtscalib::fuzz::Require;
using rtscalib::fuzz::RequireFinite;

constexpr char kName[] = "fuzz.yaml";
// Deeper or bigger trees are legal YAML but only repeat the same code paths;
// the node budget also keeps aliases of aliases ("billion laughs") from
// turning the walk exponential.
constexpr int kMaxDepth = 64;
constexpr int kMaxNodes = 1000;
int visited = 0;

// Runs one getter; a clean InputError naming the document is fine.
template <typename F>
void Try(F&& getter) {
  try {
    getter();
  } catch (const InputError& e) {
    Require(e.file == kName, std::string("an InputError naming the document: ") + e.what());
  }
}

void Walk(const YamlNode& node, int depth) {
  if (depth > kMaxDepth || ++visited > kMaxNodes) return;
  Try([&] { node.Dump(); });
  if (node.IsScalar()) {
    Try([&] { RequireFinite(node.AsDouble(), "AsDouble() at " + node.path()); });
    Try([&] { node.AsDoubleOrNan(); });
    Try([&] { node.AsInt(); });
    Try([&] { node.AsUint64(); });
    Try([&] { node.AsBool(); });
    Try([&] { node.AsString(); });
    Try([&] { node.AsEnum<int>({{"a", 1}, {"dh", 2}, {"spherical", 3}}); });
  }
  if (node.IsSequence()) {
    Try([&] {
      for (double x : node.AsDoubles()) RequireFinite(x, "AsDoubles() at " + node.path());
    });
    Try([&] {
      const std::vector<double> three = node.AsDoubles(3);
      Require(three.size() == 3, "AsDoubles(3) gives 3 numbers");
      for (double x : three) RequireFinite(x, "AsDoubles(3) at " + node.path());
    });
    Try([&] { node.AsInts(); });
    Try([&] {
      for (const YamlNode& item : node.Items()) Walk(item, depth + 1);
    });
  }
  if (node.IsMap()) {
    Try([&] {
      for (const YamlNode::Entry& entry : node.Entries()) {
        Try([&] { entry.key.AsString(); });
        Walk(entry.value, depth + 1);
      }
    });
    // Typed reads of keys the project uses, present or not.
    Try([&] {
      double x = 0;
      if (node.Read("x", &x)) RequireFinite(x, "Read(double) at " + node.path());
    });
    Try([&] {
      std::vector<double> v;
      if (node.Read("q", &v)) {
        for (double x : v) RequireFinite(x, "Read(vector<double>) at " + node.path());
      }
    });
    Try([&] { node.Require("model"); });
  }
}

// Number of nodes of the tree with aliases expanded, counted up to `limit`.
// The key check walks the expanded tree; the readers only ever accept trees
// whose expansion is about the file's size (they read lists of numbers), but
// this fuzzer marks every key as used, so on an alias bomb it would spend
// exponential time in a walk no reader can reach.
int ExpandedSize(const YAML::Node& node, int limit, int depth = 0) {
  // An anchor used inside itself makes the tree infinite.
  if (depth > kMaxDepth) return limit;
  int count = 1;
  if (node.IsMap() || node.IsSequence()) {
    for (auto it = node.begin(); it != node.end() && count < limit; ++it) {
      count += ExpandedSize(node.IsMap() ? it->second : *it, limit - count, depth + 1);
    }
  }
  return count;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return rtscalib::fuzz::RunTextReader(data, size, kName, [](const std::string& text) {
    const rtscalib::YamlDocument doc = rtscalib::YamlDocument::Parse(text, kName);
    visited = 0;
    Walk(doc.Root(), 0);
    constexpr int kMaxExpanded = 20000;
    if (ExpandedSize(YAML::Load(text), kMaxExpanded) >= kMaxExpanded) return;
    Try([&] { doc.UnusedKeys(); });
    doc.CheckAllKeysUsed();
  });
}

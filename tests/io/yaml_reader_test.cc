#include "libcalib/io/yaml_reader.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <cmath>

#include "tests/io/io_test_util.h"

namespace rtscalib {
namespace {

using ::testing::HasSubstr;
using testing_io::CatchInputError;

enum class Colour { kRed, kGreen };
const std::vector<std::pair<std::string, Colour>> kColours = {{"red", Colour::kRed},
                                                              {"green", Colour::kGreen}};

TEST(YamlReader, TypedGetters) {
  const YamlDocument doc = YamlDocument::Parse(
      "a: {x: 1.5, n: 3, flag: true, name: hello, list: [1, 2.5, -3e-2], ints: [1, 2],"
      " colour: green, seed: 12345678901, s: .nan}\n",
      "t.yaml");
  const YamlNode a = doc.Root().Require("a");
  double x = 0;
  int n = 0;
  bool flag = false;
  std::string name;
  std::vector<double> list;
  std::vector<int> ints;
  Colour colour = Colour::kRed;
  EXPECT_TRUE(a.Read("x", &x));
  EXPECT_TRUE(a.Read("n", &n));
  EXPECT_TRUE(a.Read("flag", &flag));
  EXPECT_TRUE(a.Read("name", &name));
  EXPECT_TRUE(a.Read("list", &list));
  EXPECT_TRUE(a.Read("ints", &ints));
  EXPECT_TRUE(a.ReadEnum("colour", kColours, &colour));
  EXPECT_FALSE(a.Read("absent", &x));
  EXPECT_EQ(x, 1.5);
  EXPECT_EQ(n, 3);
  EXPECT_TRUE(flag);
  EXPECT_EQ(name, "hello");
  EXPECT_EQ(list, (std::vector<double>{1, 2.5, -3e-2}));
  EXPECT_EQ(ints, (std::vector<int>{1, 2}));
  EXPECT_EQ(colour, Colour::kGreen);
  EXPECT_EQ(a.Require("seed").AsUint64(), 12345678901ULL);
  EXPECT_TRUE(std::isnan(a.Require("s").AsDoubleOrNan()));
  doc.CheckAllKeysUsed();
}

TEST(YamlReader, TypeErrorsNameFileKeyLineAndValue) {
  const YamlDocument doc = YamlDocument::Parse(
      "fit:\n"
      "  max_iterations: many\n"
      "  sigma: .inf\n"
      "  colour: blue\n"
      "  list: [1, x]\n"
      "  flag: maybe\n"
      "  map: {a: 1}\n",
      "run.yaml");
  const YamlNode fit = doc.Root().Require("fit");
  const InputError e1 = CatchInputError([&] { fit.Require("max_iterations").AsInt(); });
  EXPECT_STREQ(e1.what(),
               "run.yaml:2:19: key 'fit.max_iterations': expected an integer, got 'many'");
  EXPECT_EQ(e1.key, "fit.max_iterations");
  EXPECT_EQ(e1.line, 2);
  EXPECT_EQ(e1.position, 19);

  const InputError e2 = CatchInputError([&] { fit.Require("sigma").AsDouble(); });
  EXPECT_EQ(e2.got, ".inf");
  EXPECT_EQ(e2.expected, "a finite number");

  const InputError e3 = CatchInputError([&] { fit.Require("colour").AsEnum<Colour>(kColours); });
  EXPECT_EQ(e3.expected, "one of red, green");

  const InputError e4 = CatchInputError([&] { fit.Require("list").AsDoubles(); });
  EXPECT_EQ(e4.key, "fit.list[1]");
  EXPECT_EQ(e4.line, 5);

  const InputError e5 = CatchInputError([&] { fit.Require("flag").AsBool(); });
  EXPECT_EQ(e5.expected, "true or false");

  const InputError e6 = CatchInputError([&] { fit.Require("map").AsDouble(); });
  EXPECT_EQ(e6.got, "{a: 1}");

  const InputError e7 = CatchInputError([&] { fit.Require("absent"); });
  EXPECT_EQ(e7.key, "fit.absent");
  EXPECT_THAT(e7.what(), HasSubstr("required"));

  const InputError e8 = CatchInputError([&] { fit.Require("list").AsDoubles(3); });
  EXPECT_EQ(e8.expected, "a list of 3 numbers");
}

TEST(YamlReader, EnumSuggestsCloseName) {
  const YamlDocument doc = YamlDocument::Parse("c: gren\n", "t.yaml");
  const InputError e = CatchInputError([&] { doc.Root().Require("c").AsEnum(kColours); });
  EXPECT_THAT(e.expected, HasSubstr("did you mean 'green'?"));
}

TEST(YamlReader, UnknownKeysAreReportedWithPathLineAndKnownKeys) {
  const YamlDocument doc = YamlDocument::Parse(
      "model:\n"
      "  kinematics: dh\n"
      "  efects: [a]\n"
      "colour: red\n"
      "list:\n"
      "  - {a: 1, b: 2}\n",
      "run.yaml");
  const YamlNode root = doc.Root();
  const YamlNode model = root.Require("model");
  model.Require("kinematics").AsString();
  model.Find("effects");
  for (const YamlNode& item : root.Require("list").Items()) item.Require("a").AsInt();

  const std::vector<InputError> unused = doc.UnusedKeys();
  ASSERT_EQ(unused.size(), 3u);
  EXPECT_EQ(unused[0].key, "model.efects");
  EXPECT_EQ(unused[0].line, 3);
  EXPECT_EQ(unused[0].position, 3);
  EXPECT_THAT(unused[0].what(), HasSubstr("run.yaml:3:3: key 'model.efects'"));
  EXPECT_THAT(unused[0].expected, HasSubstr("kinematics, effects"));
  EXPECT_THAT(unused[0].expected, HasSubstr("did you mean 'effects'?"));
  EXPECT_EQ(unused[1].key, "colour");
  EXPECT_EQ(unused[1].line, 4);
  EXPECT_EQ(unused[2].key, "list[0].b");
  EXPECT_EQ(unused[2].line, 6);

  const InputError all = CatchInputError([&] { doc.CheckAllKeysUsed(); });
  EXPECT_EQ(all.key, "model.efects");
  EXPECT_THAT(all.what(), HasSubstr("'list[0].b'"));
  EXPECT_THAT(all.what(), HasSubstr("'colour'"));
}

TEST(YamlReader, UnusedSectionIsOneErrorNotOnePerKey) {
  const YamlDocument doc = YamlDocument::Parse("extra: {a: 1, b: 2}\n", "t.yaml");
  const std::vector<InputError> unused = doc.UnusedKeys();
  ASSERT_EQ(unused.size(), 1u);
  EXPECT_EQ(unused[0].key, "extra");
}

TEST(YamlReader, DuplicateKeysAreErrors) {
  const YamlDocument doc = YamlDocument::Parse("a: 1\nb: 2\na: 3\n", "t.yaml");
  doc.Root().Require("a");
  doc.Root().Require("b");
  const std::vector<InputError> unused = doc.UnusedKeys();
  ASSERT_EQ(unused.size(), 1u);
  EXPECT_EQ(unused[0].key, "a");
  EXPECT_EQ(unused[0].line, 3);
}

TEST(YamlReader, ConsumedSubtreeIsNotChecked) {
  const YamlDocument doc =
      YamlDocument::Parse("render: {width: 640, anything: [1, 2]}\n", "t.yaml");
  const YamlNode render = doc.Root().Require("render");
  render.ConsumeAll();
  doc.CheckAllKeysUsed();
  EXPECT_THAT(render.Dump(), HasSubstr("anything"));
}

TEST(YamlReader, EntriesKeepOrderAndPointAtKeys) {
  const YamlDocument doc = YamlDocument::Parse("m:\n  b: 1\n  a: 2\n", "t.yaml");
  const std::vector<YamlNode::Entry> entries = doc.Root().Require("m").Entries();
  ASSERT_EQ(entries.size(), 2u);
  EXPECT_EQ(entries[0].key.AsString(), "b");
  EXPECT_EQ(entries[0].value.AsInt(), 1);
  EXPECT_EQ(entries[1].key.path(), "m.a");
  EXPECT_EQ(entries[1].key.line(), 3);
  doc.CheckAllKeysUsed();
}

TEST(YamlReader, EmptySectionsReadAsEmpty) {
  const YamlDocument doc = YamlDocument::Parse("a:\nb:\n", "t.yaml");
  EXPECT_FALSE(doc.Root().Require("a").Find("x").has_value());
  EXPECT_TRUE(doc.Root().Require("b").Items().empty());
  doc.CheckAllKeysUsed();
  YamlDocument::Parse("", "empty.yaml").CheckAllKeysUsed();
}

TEST(YamlReader, SyntaxErrorsAndBadRoot) {
  const InputError syntax =
      CatchInputError([] { YamlDocument::Parse("a: [1, 2\nb: 3\n", "s.yaml"); });
  EXPECT_EQ(syntax.file, "s.yaml");
  EXPECT_GT(syntax.line, 0);
  EXPECT_THAT(syntax.what(), HasSubstr("YAML syntax"));
  const InputError root = CatchInputError([] { YamlDocument::Parse("- 1\n- 2\n", "r.yaml"); });
  EXPECT_THAT(root.expected, HasSubstr("mapping"));
  const InputError missing = CatchInputError([] { YamlDocument::Load("/nonexistent/c.yaml"); });
  EXPECT_EQ(missing.file, "/nonexistent/c.yaml");
}

// A folder opens as a stream that reads nothing; read as an empty document it
// was reported as the config's first missing key (`data`).
TEST(YamlReader, AFolderIsNamedAsAFolder) {
  const std::string folder = ::testing::TempDir();
  const InputError e =
      CatchInputError([&] { YamlDocument::Load(folder, std::uintmax_t{4} << 20, "a config"); });
  EXPECT_EQ(e.file, folder);
  EXPECT_EQ(e.expected, "a config (a YAML file)");
  EXPECT_EQ(e.got, "a folder");
  EXPECT_THAT(e.what(), HasSubstr("is a folder"));
  const InputError plain = CatchInputError([&] { YamlDocument::Load(folder); });
  EXPECT_EQ(plain.expected, "a YAML file");
}

// yaml-cpp 0.7's LoadAll never returns on this text (the parser hands out
// empty documents without advancing; found by fuzz/yaml_fuzzer.cc, which ate
// 24 GB): the reader walks the documents with a bound. yaml-cpp reads the
// text as an empty document, which is no config: an error naming the first
// line that gave no value. A memory limit keeps a regression
// from taking the machine down (not under ASan, whose shadow memory needs
// the address space).
TEST(YamlReader, TextOnWhichLoadAllNeverReturnsIsAnError) {
#ifndef __SANITIZE_ADDRESS__
  const rlimit two_gb{2L << 30, 2L << 30};
  ASSERT_EQ(setrlimit(RLIMIT_AS, &two_gb), 0);
#endif
  const InputError e = CatchInputError(
      [] { YamlDocument::Parse(", 2, 3]}\nother: *a\nmerge: {<<: *a, y: 2}\n", "f.yaml"); });
  EXPECT_EQ(std::string(e.what()),
            "f.yaml:1:1: YAML syntax: expected a YAML mapping (key: value lines), got ', 2, 3]}'");
}

// A second document would be ignored by a reader that takes the first, so
// none of its keys would take effect.
TEST(YamlReader, SecondDocumentIsAnError) {
  const InputError e = CatchInputError(
      [] { YamlDocument::Parse("model: {kinematics: dh}\n---\nfit: {threads: 2}\n", "d.yaml"); });
  EXPECT_EQ(std::string(e.what()),
            "d.yaml:3:1: second YAML document: expected one YAML document per file (remove the "
            "'---' line before it), got 'fit: {threads: 2}'");
  // A leading `---` and a trailing empty document hold nothing else.
  const YamlDocument doc = YamlDocument::Parse("---\na: 1\n---\n", "ok.yaml");
  double a = 0;
  EXPECT_TRUE(doc.Root().Read("a", &a));
  EXPECT_EQ(a, 1.0);
}

TEST(YamlReader, MappingExpected) {
  const YamlDocument doc = YamlDocument::Parse("model: dh\n", "t.yaml");
  const InputError e = CatchInputError([&] { doc.Root().Require("model").Find("kinematics"); });
  EXPECT_EQ(e.key, "model");
  EXPECT_THAT(e.expected, HasSubstr("mapping"));
  EXPECT_EQ(e.got, "dh");
}

}  // namespace
}  // namespace rtscalib

#include "libcalib/io/csv.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include <sstream>

#include "tests/io/io_test_util.h"

namespace rtscalib {
namespace {

using ::testing::HasSubstr;
using testing_io::CatchInputError;

CsvTable ParseText(const std::string& text, const CsvTable::Columns& columns) {
  std::istringstream in(text);
  return CsvTable::Parse(in, "t.csv", columns);
}

TEST(Csv, HeaderCommentsBlanksTrimmingAndQuotes) {
  const CsvTable t = ParseText(
      "\xEF\xBB\xBF# leading comment\n"
      "\n"
      " b , a ,note\r\n"
      "  # indented comment\n"
      "2, 1 , \"x, \"\"y\"\" \"\r\n"
      "\n"
      "4,3,\n",
      {{"a", "b"}, {"note"}});
  ASSERT_EQ(t.NumRows(), 2);
  EXPECT_EQ(t.Line(0), 5);
  EXPECT_EQ(t.Line(1), 7);
  EXPECT_EQ(t.Number(0, "a"), 1.0);
  EXPECT_EQ(t.Integer(1, "b"), 4);
  EXPECT_EQ(t.Text(0, "note"), "x, \"y\" ");
  EXPECT_TRUE(t.Empty(1, "note"));
  EXPECT_TRUE(t.notes().empty());
}

TEST(Csv, AbsentOptionalColumnReadsEmpty) {
  const CsvTable t = ParseText("a\n1\n", {{"a"}, {"set"}});
  EXPECT_FALSE(t.Has("set"));
  EXPECT_EQ(t.Text(0, "set"), "");
}

TEST(Csv, ExtraColumnsAreNoted) {
  const CsvTable t = ParseText("a,zz,yy\n1,2,3\n", {{"a"}, {}});
  ASSERT_EQ(t.notes().size(), 1u);
  EXPECT_THAT(t.notes()[0], HasSubstr("t.csv:1"));
  EXPECT_THAT(t.notes()[0], HasSubstr("yy, zz"));
}

// A reader that keeps covariates keeps the extra columns whose every
// non-empty cell is a number (in header order; an empty cell is NaN) and
// still ignores the others, naming both.
TEST(Csv, NumericExtraColumnsAreCovariatesWhenAsked) {
  const CsvTable t =
      ParseText("a,temp,label,time,blank\n1,20.5,x,,\n2,,y,3,\n", {{"a"}, {}, true});
  EXPECT_EQ(t.covariates(), (std::vector<std::string>{"temp", "time"}));
  EXPECT_EQ(t.Covariate(0, 0), 20.5);
  EXPECT_TRUE(std::isnan(t.Covariate(1, 0)));
  EXPECT_TRUE(std::isnan(t.Covariate(0, 1)));
  EXPECT_EQ(t.Covariate(1, 1), 3.0);
  ASSERT_EQ(t.notes().size(), 2u);
  EXPECT_THAT(t.notes()[0], HasSubstr("temp, time kept as covariates"));
  EXPECT_THAT(t.notes()[1], HasSubstr("ignored columns blank, label"));
  // Without the request every extra column is ignored.
  const CsvTable plain = ParseText("a,temp\n1,2\n", {{"a"}, {}});
  EXPECT_TRUE(plain.covariates().empty());
  EXPECT_THAT(plain.notes().at(0), HasSubstr("ignored column temp"));
}

// A UTF-16 or UTF-32 file would read as one field of odd bytes per line;
// its byte-order mark (or its NUL bytes) names the encoding instead.
TEST(Csv, WideEncodingsAreErrorsThatSayHowToFixThem) {
  const std::string utf16le(
      "\xFF\xFE"
      "a\0,\0b\0\n\0"
      "1\0,\0"
      "2\0\n\0",
      16);
  const InputError e16 = CatchInputError([&] { ParseText(utf16le, {{"a"}, {}}); });
  EXPECT_EQ(std::string(e16.what()),
            "t.csv:1: encoding: expected a UTF-8 text file (save it as UTF-8), got 'file is "
            "UTF-16 (little-endian BOM)'");
  const InputError e16be = CatchInputError([] {
    ParseText(std::string("\xFE\xFF\0a\0\n", 6), {{"a"}, {}});
  });
  EXPECT_EQ(e16be.got, "file is UTF-16 (big-endian BOM)");
  const InputError e32 = CatchInputError([] {
    ParseText(std::string("\xFF\xFE\0\0"
                          "a\0\0\0\n",
                          9),
              {{"a"}, {}});
  });
  EXPECT_EQ(e32.got, "file is UTF-32 (little-endian BOM)");
  const InputError nul = CatchInputError([] {
    ParseText(std::string("a\n1\0\n", 5), {{"a"}, {}});
  });
  EXPECT_EQ(nul.line, 2);
  EXPECT_EQ(nul.got, "file is UTF-16 or UTF-32 (NUL bytes)");
  // A UTF-8 byte-order mark is skipped.
  const CsvTable t = ParseText(
      "\xEF\xBB\xBF"
      "a\n1\n",
      {{"a"}, {}});
  EXPECT_EQ(t.Number(0, "a"), 1.0);
}

TEST(Csv, RaggedRowIsAnError) {
  const InputError e = CatchInputError([] { ParseText("a,b\n1,2\n1,2,3\n", {{"a"}, {}}); });
  EXPECT_EQ(e.line, 3);
  EXPECT_THAT(e.what(), HasSubstr("t.csv:3: row: expected 2 fields"));
}

TEST(Csv, UnclosedQuoteIsAnError) {
  const InputError e = CatchInputError([] { ParseText("a\n\"oops\n", {{"a"}, {}}); });
  EXPECT_EQ(e.line, 2);
}

TEST(Csv, DuplicateColumnIsAnError) {
  const InputError e = CatchInputError([] { ParseText("a,b,a\n1,2,3\n", {{"a"}, {}}); });
  EXPECT_EQ(e.column, "a");
  EXPECT_EQ(e.line, 1);
}

TEST(Csv, MissingFileNamesThePath) {
  const InputError e = CatchInputError([] {
    CsvTable::Read("/nonexistent/dir/x.csv", {{"a"}, {}});
  });
  EXPECT_EQ(e.file, "/nonexistent/dir/x.csv");
  EXPECT_THAT(e.what(), HasSubstr("cannot open"));
}

TEST(Csv, WriterQuotesWhatTheReaderWouldChange) {
  testing_io::TempDir dir;
  const std::string path = dir.Path("w.csv");
  {
    CsvWriter w(path, {"a", "b"});
    w.Row({"x,y", " padded "});
    w.Row({"#hash", "say \"hi\""});
    w.Close();
  }
  const CsvTable t = CsvTable::Read(path, {{"a", "b"}, {}});
  ASSERT_EQ(t.NumRows(), 2);
  EXPECT_EQ(t.Text(0, "a"), "x,y");
  EXPECT_EQ(t.Text(0, "b"), " padded ");
  EXPECT_EQ(t.Text(1, "a"), "#hash");
  EXPECT_EQ(t.Text(1, "b"), "say \"hi\"");
}

}  // namespace
}  // namespace rtscalib

#include "libcalib/text/errors.h"

#include <gtest/gtest.h>

namespace rtscalib {
namespace {

TEST(InputError, CellMessageNamesFileLineAndColumn) {
  const InputError e = InputError::Cell("records.csv", 12, "face", "1 or 2", "3");
  EXPECT_STREQ(e.what(), "records.csv:12: column 'face': expected 1 or 2, got '3'");
  EXPECT_EQ(e.file, "records.csv");
  EXPECT_EQ(e.line, 12);
  EXPECT_EQ(e.column, "face");
  EXPECT_EQ(e.expected, "1 or 2");
  EXPECT_EQ(e.got, "3");
}

TEST(InputError, KeyMessageWithAndWithoutPosition) {
  EXPECT_STREQ(InputError::Key("run.yaml", "model.effects[2]", 0, 0, "an effect name", "x").what(),
               "run.yaml: key 'model.effects[2]': expected an effect name, got 'x'");
  EXPECT_STREQ(InputError::Key("run.yaml", "model.efects", 4, 3, "a known key", "efects").what(),
               "run.yaml:4:3: key 'model.efects': expected a known key, got 'efects'");
}

TEST(InputError, FileMessageAndCombine) {
  const InputError a = InputError::File("p.csv", 1, "no rows", "a data row", "header only");
  EXPECT_STREQ(a.what(), "p.csv:1: no rows: expected a data row, got 'header only'");
  const InputError b = InputError::Key("c.yaml", "x", 2, 1, "a known key", "x");
  const InputError both = InputError::Combine({a, b});
  EXPECT_EQ(std::string(both.what()), std::string(a.what()) + "\n" + b.what());
  EXPECT_EQ(both.file, "p.csv");
  EXPECT_EQ(both.subject, "no rows");
}

}  // namespace
}  // namespace rtscalib

// `rtscalib compare` as a user runs it: exit codes (docs/conventions.md),
// the files --output writes, messages that name the file.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "libcalib/io/model_io.h"
#include "libcalib/sim/simulator.h"
#include "tests/app/read_file.h"

namespace rtscalib {
namespace {

namespace fs = std::filesystem;
using testing_files::ReadFile;

class CompareCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(RTSCALIB_BINARY_DIR) / "test_tmp" / "compare_command";
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  // `rtscalib ARGS`; returns the exit code, stderr in *err.
  int Run(const std::string& args, std::string* err) {
    const fs::path log = dir_ / "stderr.txt";
    const std::string cmd = std::string("'") + RTSCALIB_BINARY_DIR + "/app/rtscalib' " + args +
                            " > /dev/null 2> '" + log.string() + "'";
    const int status = std::system(cmd.c_str());
    *err = ReadFile(log);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  fs::path dir_;
};

TEST_F(CompareCommand, ExitCodesFilesAndMessages) {
  const fs::path a = dir_ / "a.yaml", b = dir_ / "b.yaml";
  WriteModelYaml(a.string(), PaperTruth(2));
  WriteModelYaml(b.string(), PaperTruth(3));
  std::string err;
  // A model with itself: exit 0, files written, zero differences.
  const fs::path out = dir_ / "cmp";
  EXPECT_EQ(Run("compare '" + a.string() + "' '" + a.string() + "' --output '" + out.string() + "'",
                &err),
            0)
      << err;
  const nlohmann::json j = nlohmann::json::parse(ReadFile(out / "compare.json"));
  ASSERT_EQ(j["zooms"].size(), 2u);
  for (const auto& z : j["zooms"]) EXPECT_EQ(z["max_px"].get<double>(), 0.0);
  EXPECT_TRUE(fs::exists(out / "compare.txt"));
  EXPECT_TRUE(fs::exists(out / "figures" / "compare_zoom0.vg.json"));
  // The same --output again: files exist, never replaced (exit 1).
  EXPECT_EQ(Run("compare '" + a.string() + "' '" + a.string() + "' --output '" + out.string() + "'",
                &err),
            1);
  EXPECT_NE(err.find("compare.txt"), std::string::npos) << err;
  // Missing file: exit 1 naming it.
  const fs::path missing = dir_ / "nowhere" / "model.yaml";
  EXPECT_EQ(Run("compare '" + a.string() + "' '" + missing.string() + "'", &err), 1);
  EXPECT_NE(err.find(missing.string()), std::string::npos) << err;
  // Different zoom sets: exit 1 naming the second file.
  EXPECT_EQ(Run("compare '" + a.string() + "' '" + b.string() + "'", &err), 1);
  EXPECT_NE(err.find(b.string()), std::string::npos) << err;
  EXPECT_NE(err.find("zoom"), std::string::npos) << err;
  // One model only: usage error.
  EXPECT_EQ(Run("compare '" + a.string() + "'", &err), 2);
}

}  // namespace
}  // namespace rtscalib

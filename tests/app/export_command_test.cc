// `rtscalib export`, run in-process on a model.yaml: each format writes its
// files into the model's folder + export/, and a second run refuses to
// replace them (naming the file) unless --force, leaving them untouched.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "app/commands.h"
#include "libcalib/io/model_io.h"
#include "libcalib/sim/simulator.h"
#include "tests/app/read_file.h"

namespace rtscalib {
namespace {

namespace fs = std::filesystem;
using testing_files::ReadFile;

TEST(ExportCommand, WritesEachFormatAndNeverOverwritesWithoutForce) {
  const fs::path dir = fs::path(RTSCALIB_BINARY_DIR) / "test_tmp" / "export_command";
  fs::remove_all(dir);
  fs::create_directories(dir);
  InstrumentModel m = PaperTruth(2);
  m.effects.Add(Effect::kRadialDistortion);
  WriteModelYaml((dir / "model.yaml").string(), m);

  app::ExportArgs args;
  args.model = (dir / "model.yaml").string();
  const std::map<std::string, std::vector<std::string>> expected = {
      {"opencv", {"camera_zoom0.yaml", "camera_zoom1.yaml"}},
      {"urdf", {"instrument.urdf"}},
      {"surveyor", {"surveyor.txt", "surveyor.json"}}};
  for (const auto& [format, files] : expected) {
    args.format = format;
    args.force = false;
    ASSERT_EQ(app::RunExport(args), 0) << format;
    for (const std::string& f : files) {
      EXPECT_TRUE(fs::exists(dir / "export" / f)) << f;
      EXPECT_GT(fs::file_size(dir / "export" / f), 0u) << f;
    }
    // A file of the user's in the way: refused, named, and left as it was.
    const fs::path last = dir / "export" / files.back();
    { std::ofstream(last) << "mine"; }
    try {
      app::RunExport(args);
      ADD_FAILURE() << format << ": export replaced " << last;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(last.string()), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("--force"), std::string::npos) << e.what();
    }
    EXPECT_EQ(ReadFile(last), "mine");
    args.force = true;
    ASSERT_EQ(app::RunExport(args), 0) << format;
    EXPECT_NE(ReadFile(last), "mine");
  }
  // --out puts the files elsewhere.
  args.format = "urdf";
  args.force = false;
  args.out = (dir / "elsewhere").string();
  ASSERT_EQ(app::RunExport(args), 0);
  EXPECT_TRUE(fs::exists(dir / "elsewhere" / "instrument.urdf"));
}

}  // namespace
}  // namespace rtscalib

// `rtscalib plan` as a user runs it (docs/plan.md): the files it writes,
// plan.csv read back as a shots.csv once its image column is filled, and
// an existing plan never replaced.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "libcalib/io/shots.h"
#include "tests/app/read_file.h"

namespace rtscalib {
namespace {

namespace fs = std::filesystem;
using testing_files::ReadFile;

int RunRtscalib(const std::string& args, const fs::path& dir, std::string* err) {
  const fs::path log = dir / "stderr.txt";
  const std::string cmd = std::string("'") + RTSCALIB_BINARY_DIR + "/app/rtscalib' " + args +
                          " > /dev/null 2> '" + log.string() + "'";
  const int status = std::system(cmd.c_str());
  *err = ReadFile(log);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// A fresh folder test_tmp/<name> and in it run/, the output of rtscalib
// run on configs/<config> (the earlier run of `plan --from`).
fs::path CalibratedRun(const std::string& name, const std::string& config, fs::path* dir) {
  *dir = fs::path(RTSCALIB_BINARY_DIR) / "test_tmp" / name;
  fs::remove_all(*dir);
  fs::create_directories(*dir);
  const fs::path run = *dir / "run";
  std::string err;
  EXPECT_EQ(RunRtscalib("--quiet --config '" + std::string(RTSCALIB_SOURCE_DIR) + "/configs/" +
                            config + "' --output '" + run.string() + "'",
                        *dir, &err),
            0)
      << err;
  return run;
}

// plan.csv with its image column filled as a user fills it (an empty file
// photo<k>.png per row in `dir`, the reader checks that it exists),
// written to dir/shots.csv; `header` sees the column names.
fs::path FilledShotsCsv(const fs::path& plan_csv, const fs::path& dir,
                        const std::function<void(const std::string&)>& header) {
  std::istringstream csv(ReadFile(plan_csv));
  std::ostringstream filled;
  std::string line;
  int row = 0;
  while (std::getline(csv, line)) {
    if (!line.empty() && line[0] != '#') {
      if (line.rfind("shot,", 0) == 0) {
        header(line);
      } else {
        const std::string image = "photo" + std::to_string(++row) + ".png";
        std::ofstream(dir / image) << "";
        line += image;
      }
    }
    filled << line << "\n";
  }
  const fs::path shots = dir / "shots.csv";
  std::ofstream(shots) << filled.str();
  return shots;
}

TEST(PlanCommand, WritesAPlanThatReadsAsAShotsCsvAndNeverReplacesIt) {
  const fs::path dir = fs::path(RTSCALIB_BINARY_DIR) / "test_tmp" / "plan_command";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path out = dir / "plan";
  const std::string config = std::string(RTSCALIB_SOURCE_DIR) + "/configs/plan.yaml";
  std::string err;
  ASSERT_EQ(RunRtscalib("plan --quiet --config '" + config + "' --output '" + out.string() + "'",
                        dir, &err),
            0)
      << err;
  const nlohmann::json j = nlohmann::json::parse(ReadFile(out / "plan.json"));
  EXPECT_TRUE(j["goal_met"].get<bool>());
  const size_t n = j["plan"].size();
  ASSERT_GT(n, 0u);
  EXPECT_EQ(j["shots"].get<size_t>(), n);
  EXPECT_TRUE(fs::exists(out / "figures" / "plan.vg.json"));
  // The user fills the image column: a shots.csv (SPEC 7) with the plan's
  // readings in the plan's order.
  const ShotsFile read =
      ReadShots(FilledShotsCsv(out / "plan.csv", dir, [](const std::string&) {}).string());
  ASSERT_EQ(read.shots.size(), n);
  for (size_t k = 0; k < n; ++k) {
    EXPECT_EQ(read.shots[k].face, j["plan"][k]["face"].get<int>());
    EXPECT_EQ(read.shots[k].zoom, j["plan"][k]["zoom"].get<int>());
    EXPECT_DOUBLE_EQ(read.shots[k].phi, j["plan"][k]["phi"].get<double>());
    EXPECT_DOUBLE_EQ(read.shots[k].theta, j["plan"][k]["theta"].get<double>());
    EXPECT_EQ(read.shots[k].image, "photo" + std::to_string(k + 1) + ".png");
  }
  // A second plan into the same folder: refused, naming the file, the
  // first plan untouched.
  const std::string before = ReadFile(out / "plan.csv");
  EXPECT_EQ(RunRtscalib("plan --quiet --config '" + config + "' --output '" + out.string() + "'",
                        dir, &err),
            1);
  EXPECT_NE(err.find("plan.csv"), std::string::npos) << err;
  EXPECT_EQ(ReadFile(out / "plan.csv"), before);
}

// `--from OUT`: a calibration of configs/plan.yaml's session, then the
// shots to add. Its diagnosis ranks effects it could not determine
// (v_eccentricity among them, whose signature these boards and records do
// not show): plan.json names them and says what limits them.
TEST(PlanCommand, FromAnEarlierRunNamesWhatItsDiagnosisCouldNotDetermine) {
  fs::path dir;
  const fs::path run = CalibratedRun("plan_from", "plan.yaml", &dir);
  ASSERT_FALSE(::testing::Test::HasFailure());
  std::string err;
  ASSERT_EQ(RunRtscalib("plan --quiet --from '" + run.string() + "'", dir, &err), 0) << err;
  const nlohmann::json j = nlohmann::json::parse(ReadFile(run / "plan" / "plan.json"));
  const nlohmann::json report = nlohmann::json::parse(ReadFile(run / "report.json"));
  std::vector<std::string> expected;
  for (const auto& e : report["diagnosis"]["ranking"]) {
    const std::string name = e["effect"].get<std::string>();
    if (e.value("identifiable", true)) continue;
    if (name == "collimation" || name == "tilting_axis" || name == "vertical_index" ||
        name == "edm_offset")
      continue;  // contained in the dh kinematics
    for (const std::string kinematic : {"hz_eccentricity", "v_eccentricity", "hz_scale", "v_scale",
                                        "axis_wobble", "edm_scale", "edm_cyclic"}) {
      if (name == kinematic) expected.push_back(name);
    }
  }
  ASSERT_FALSE(expected.empty());
  EXPECT_EQ(j["effects_not_identifiable"].get<std::vector<std::string>>(), expected);
  // Every such effect's amplitude is a goal of the plan, and each one that
  // is not met is named among the limits.
  for (const std::string& effect : expected) {
    bool goal = false, met = false;
    for (const auto& c : j["constants"]) {
      if (c["name"].get<std::string>().rfind(effect + ".", 0) != 0 || !c.contains("goal")) continue;
      goal = true;
      met = c["sigma"].is_number() && c["sigma"].get<double>() <= c["goal"].get<double>();
    }
    EXPECT_TRUE(goal) << effect;
    if (met) continue;
    bool named = false;
    for (const auto& l : j["limits"]) named = named || l.get<std::string>().rfind(effect, 0) == 0;
    EXPECT_TRUE(named) << effect;
  }
}

// configs/plan_camera.yaml: a camera planned from scratch, its board a
// chessboard from a targets.yaml (plan.board): the goal met, every photo a
// board pose of its own.
TEST(PlanCommand, ACameraIsPlannedFromScratchWithItsChessboard) {
  const fs::path dir = fs::path(RTSCALIB_BINARY_DIR) / "test_tmp" / "plan_camera";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::string err;
  ASSERT_EQ(RunRtscalib("plan --quiet --config '" + std::string(RTSCALIB_SOURCE_DIR) +
                            "/configs/plan_camera.yaml' --output '" + (dir / "plan").string() + "'",
                        dir, &err),
            0)
      << err;
  const nlohmann::json j = nlohmann::json::parse(ReadFile(dir / "plan" / "plan.json"));
  EXPECT_TRUE(j["goal_met"].get<bool>());
  ASSERT_GE(j["plan"].size(), 16u);  // a camera starting from its photos alone
  for (const nlohmann::json& shot : j["plan"]) {
    EXPECT_TRUE(shot.contains("board")) << shot.dump();
    EXPECT_EQ(shot["points"].get<int>(), 54);  // the chessboard whole
  }
  // An instrument's boards are its simulate section's: plan.board is refused
  // there, by name.
  std::string instrument = ReadFile(fs::path(RTSCALIB_SOURCE_DIR) / "configs" / "plan.yaml");
  const size_t at = instrument.find("\nplan:\n");
  ASSERT_NE(at, std::string::npos);
  instrument.insert(
      at + 7, "  board: " + std::string(RTSCALIB_SOURCE_DIR) + "/configs/bench/targets.yaml\n");
  std::ofstream(dir / "instrument.yaml") << instrument;
  EXPECT_EQ(RunRtscalib("plan --quiet --config '" + (dir / "instrument.yaml").string() +
                            "' --output '" + (dir / "refused").string() + "'",
                        dir, &err),
            1);
  EXPECT_NE(err.find("plan.board"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir / "refused" / "plan.csv"));
}

// A camera on its own (configs/bench.yaml, model.kinematics: none) does not
// turn: `plan --from` its run says where to hold the board for the photos
// to add (docs/plan.md), toward the goals given on the command line.
// plan.csv, its image column filled, reads as a shots.csv with empty
// readings and one placement per photo; a goal that is not NAME=SIGMA is
// a usage error.
TEST(PlanCommand, ACameraOnItsOwnIsToldWhereToHoldTheBoard) {
  fs::path dir;
  const fs::path run = CalibratedRun("plan_bench", "bench.yaml", &dir);
  ASSERT_FALSE(::testing::Test::HasFailure());
  // The run's report, whose photos leave the image's corners empty, names
  // the command.
  EXPECT_NE(ReadFile(run / "report.txt").find("rtscalib plan --from " + run.string()),
            std::string::npos);
  std::string err;
  ASSERT_EQ(RunRtscalib("plan --quiet --from '" + run.string() +
                            "' --goal 'cam[0].fx=0.2' --projection-px 0.3",
                        dir, &err),
            0)
      << err;
  const nlohmann::json j = nlohmann::json::parse(ReadFile(run / "plan" / "plan.json"));
  EXPECT_TRUE(j["goal_met"].get<bool>());
  EXPECT_DOUBLE_EQ(j["goal"]["sigmas"]["cam[0].fx"].get<double>(), 0.2);
  // The photos to add are as noisy as the run's: its a-posteriori pixel
  // sigma (above bench.yaml's a-priori 0.1 px on these photos).
  const nlohmann::json report = nlohmann::json::parse(ReadFile(run / "report.json"));
  EXPECT_GT(report["fit"]["sigma_pixel_px"].get<double>(), 0.1);
  EXPECT_EQ(j["observed_sigmas"]["sigma_pixel_px"]["observed"], report["fit"]["sigma_pixel_px"]);
  const size_t n = j["plan"].size();
  ASSERT_GT(n, 0u);
  for (const nlohmann::json& shot : j["plan"]) {
    ASSERT_TRUE(shot.contains("board")) << shot.dump();
    EXPECT_GT(shot["board"]["distance_m"].get<double>(), 0.1);
  }
  EXPECT_TRUE(fs::exists(run / "plan" / "figures" / "plan.png"));
  const ShotsFile read =
      ReadShots(FilledShotsCsv(run / "plan" / "plan.csv", dir, [](const std::string& header) {
                  EXPECT_NE(header.find("board_distance_m"), std::string::npos) << header;
                }).string());
  ASSERT_EQ(read.shots.size(), n);
  for (size_t k = 0; k < n; ++k) {
    EXPECT_FALSE(read.shots[k].has_reading);
    EXPECT_EQ(read.shots[k].placement, j["plan"][k]["placement"].get<std::string>());
  }
  EXPECT_EQ(RunRtscalib("plan --quiet --from '" + run.string() + "' --goal fx", dir, &err), 2);
  EXPECT_NE(err.find("NAME=SIGMA"), std::string::npos) << err;
}

}  // namespace
}  // namespace rtscalib

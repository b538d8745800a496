// Failure is an exit code, and what the data cannot determine is said: the
// rtscalib binary on configs/paper.yaml and on small broken inputs. Every
// number in model.yaml and report.json must be finite; a fit failure exits 3
// naming the row and leaves the top of the output folder as it was; a tool
// without data is written as not determined and `predict` refuses it.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "libcalib/eval/error_measures.h"
#include "libcalib/io/records.h"
#include "libcalib/model/critical_region.h"
#include "libcalib/sim/simulator.h"
#include "tests/app/read_file.h"

namespace rtscalib {
namespace {

namespace fs = std::filesystem;
using testing_files::ReadFile;

void Put(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary) << text;
}

// Every scalar of a YAML document: no null, no nan/inf, every number finite.
void ExpectFiniteYaml(const YAML::Node& n, const std::string& path, std::vector<std::string>* bad) {
  if (n.IsMap()) {
    for (const auto& kv : n)
      ExpectFiniteYaml(kv.second, path + "." + kv.first.as<std::string>(), bad);
  } else if (n.IsSequence()) {
    for (size_t i = 0; i < n.size(); ++i)
      ExpectFiniteYaml(n[i], path + "[" + std::to_string(i) + "]", bad);
  } else if (n.IsNull()) {
    bad->push_back(path + ": null");
  } else if (n.IsScalar()) {
    std::string s = n.Scalar();
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    static const std::set<std::string> kNonFinite = {".nan", ".inf", "-.inf", "+.inf", "nan",
                                                     "-nan", "inf",  "-inf",  "+inf"};
    if (kNonFinite.count(s)) {
      bad->push_back(path + ": " + n.Scalar());
      return;
    }
    char* end = nullptr;
    const double x = std::strtod(s.c_str(), &end);
    if (!s.empty() && end == s.c_str() + s.size() && !std::isfinite(x)) {
      bad->push_back(path + ": " + n.Scalar());
    }
  }
}

// Every JSON number finite (nlohmann writes NaN and inf as null); null only
// where docs/conventions.md section 6 allows it (never for a number).
void ExpectFiniteJson(const nlohmann::json& j, const std::string& path,
                      std::vector<std::string>* bad) {
  static const std::set<std::string> kMayBeNull = {".table5.cross", ".diagnosis.next"};
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it)
      ExpectFiniteJson(*it, path + "." + it.key(), bad);
  } else if (j.is_array()) {
    for (size_t i = 0; i < j.size(); ++i)
      ExpectFiniteJson(j[i], path + "[" + std::to_string(i) + "]", bad);
  } else if (j.is_null()) {
    // A map cell the model cannot predict (docs/conventions.md section 6).
    const bool map_cell =
        path.rfind(".uncertainty.zooms[", 0) == 0 && path.find("].sigma_px[") != std::string::npos;
    if (!kMayBeNull.count(path) && !map_cell) bad->push_back(path + ": null");
  } else if (j.is_number_float() && !std::isfinite(j.get<double>())) {
    bad->push_back(path + ": " + j.dump());
  }
}

void ExpectAllFinite(const fs::path& dir) {
  std::vector<std::string> bad;
  ExpectFiniteYaml(YAML::LoadFile((dir / "model.yaml").string()), "", &bad);
  ExpectFiniteJson(nlohmann::json::parse(ReadFile(dir / "report.json")), "", &bad);
  std::string all;
  for (const std::string& b : bad) all += b + "\n";
  EXPECT_TRUE(bad.empty()) << dir << ":\n" << all;
}

class Failure : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("rtscalib_failure_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    root_ = dir_ / "out";
  }
  void TearDown() override { fs::remove_all(dir_); }

  // `rtscalib ARGS` with stdout discarded; returns the exit code, stderr in *err.
  int Run(const std::string& args, std::string* err) {
    const fs::path log = dir_ / "stderr.txt";
    const std::string cmd = std::string("'") + RTSCALIB_BINARY_DIR + "/app/rtscalib' " + args +
                            " > /dev/null 2> '" + log.string() + "'";
    const int status = std::system(cmd.c_str());
    *err = ReadFile(log);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  int RunConfig(const fs::path& config, std::string* err) {
    return Run("--config '" + config.string() + "' --output '" + root_.string() + "' --quiet", err);
  }

  // Klug's sweeps and a grid of the paper's truth, 5 um point noise against
  // the config's 1e-5 m sigmas, as records.csv (lines: header = 1).
  std::vector<Record> Records() {
    SimulationOptions sim;
    sim.seed = 9;
    sim.truth = PaperTruth(1);
    sim.plan.grid_phi_steps = 10;
    sim.plan.grid_theta_steps = 6;
    sim.noise.point_m = 5e-6;
    truth_ = sim.truth;
    return Simulate(sim).obs.records;
  }
  // A config reading `records` (written to dir_/name) with the truth's camera.
  fs::path Config(const std::vector<Record>& records, const std::string& name) {
    const fs::path csv = dir_ / name;
    WriteRecords(csv.string(), records);
    const CameraTool& c = truth_.cams[0];
    std::ostringstream y;
    y << "model:\n  kinematics: dh\n  cameras:\n    - {width: " << c.width
      << ", height: " << c.height << ", fx: " << c.intrinsics[0] << ", fy: " << c.intrinsics[1]
      << ", cx: " << c.intrinsics[2] << ", cy: " << c.intrinsics[3]
      << "}\nfit:\n  sigmas: {edm_m: 1.0e-5, cam_m: 1.0e-5, pixel_px: 0.5}\ndata:\n  records: "
      << csv.string() << "\n";
    const fs::path config = dir_ / (name + ".yaml");
    Put(config, y.str());
    return config;
  }
  // The same without the gross-error handling (docs/refinement.md): the
  // protections of a single fit must hold on their own.
  fs::path ConfigWithoutGrossErrors(const std::vector<Record>& records, const std::string& name) {
    const fs::path config = Config(records, name);
    std::string text = ReadFile(config);
    text.replace(text.find("fit:\n"), 5, "fit:\n  gross_errors: {enabled: false}\n");
    Put(config, text + "screen: {gross_errors: {enabled: false}}\n");
    return config;
  }
  // Index of the last grid row of `tool` outside the default critical
  // regions (in the first grid rows a huge value breaks the sweep search
  // instead, an input error).
  static int GridRow(const std::vector<Record>& records, Tool tool) {
    for (size_t k = 0; k < records.size(); ++k) {
      const size_t i = records.size() - 1 - k;
      const Record& r = records[i];
      if (r.tool == tool && r.set == "grid" &&
          !CriticalRegion().Contains(r.theta))
        return static_cast<int>(i);
    }
    ADD_FAILURE() << "no grid row";
    return 0;
  }

  fs::path dir_, root_;
  InstrumentModel truth_;
};

TEST_F(Failure, PaperRunWritesOnlyFiniteNumbers) {
  std::string err;
  ASSERT_EQ(RunConfig(fs::path(RTSCALIB_SOURCE_DIR) / "configs/paper.yaml", &err), 0) << err;
  ExpectAllFinite(root_);
  const YAML::Node model = YAML::LoadFile((root_ / "model.yaml").string());
  EXPECT_FALSE(model["edm"]["determined"]) << "determined: false only for undetermined tools";
  EXPECT_TRUE(model["edm"]["sigma"]);
}

// One EDM grid row with z = 1e308 m (it aborted in a glog CHECK, exit 134)
// and one camera row with d = 1e300 m (it published `camera inf +- nan`):
// by default gross rows, taken out and listed in the report with their
// lines (exit 0, every number finite).
TEST_F(Failure, BrokenRowIsAGrossRowListedInTheReport) {
  const std::vector<Record> good = Records();
  for (const Tool tool : {Tool::kEdm, Tool::kCam}) {
    std::vector<Record> broken = good;
    const int row = GridRow(broken, tool);
    if (tool == Tool::kEdm) {
      broken[row].x.z() = 1e308;
    } else {
      broken[row].d = 1e300;
    }
    std::string err;
    ASSERT_EQ(RunConfig(Config(broken, "broken.csv"), &err), 0) << err;
    ExpectAllFinite(root_);
    const std::string text = ReadFile(root_ / "report.txt");
    EXPECT_NE(text.find("Gross errors: 1 rows taken out before the fit"), std::string::npos)
        << text;
    EXPECT_NE(text.find((dir_ / "broken.csv").string() + ":" + std::to_string(row + 2) + ": " +
                        (tool == Tool::kEdm ? "EDM row" : "camera row")),
              std::string::npos)
        << text;
    const nlohmann::json report = nlohmann::json::parse(ReadFile(root_ / "report.json"));
    ASSERT_EQ(report["gross_errors"].size(), 1u);
    EXPECT_EQ(report["gross_errors"][0]["line"], row + 2);
  }
}

// The same rows without the gross-error handling: exit 3 (or 1) naming the
// row's file and line; the top still shows the good run.
TEST_F(Failure, BrokenRowExitsThreeNamesTheRowAndLeavesTheTopAlone) {
  std::string err;
  const std::vector<Record> good = Records();
  ASSERT_EQ(RunConfig(Config(good, "good.csv"), &err), 0) << err;
  ExpectAllFinite(root_);
  const std::string model = ReadFile(root_ / "model.yaml");
  const std::string report = ReadFile(root_ / "report.json");
  const fs::path latest = fs::read_symlink(root_ / "latest");

  // A coordinate of 1e308 is caught by the screening before any fit (an input
  // error, exit 1); a ray length of 1e300 passes the screening (the camera
  // row's point is not compared with d) and fails the fit (exit 3).
  struct Case {
    Tool tool;
    const char* name;
    int exit_code;
    const char* says;
  };
  for (const Case c : {Case{Tool::kEdm, "z_1e308.csv", 1, "expected a point in metres"},
                       Case{Tool::kCam, "d_1e300.csv", 3, "calibration failed"}}) {
    std::vector<Record> broken = good;
    const int row = GridRow(broken, c.tool);
    if (c.tool == Tool::kEdm) {
      broken[row].x.z() = 1e308;
    } else {
      broken[row].d = 1e300;
    }
    EXPECT_EQ(RunConfig(ConfigWithoutGrossErrors(broken, c.name), &err), c.exit_code) << err;
    EXPECT_NE(err.find(c.says), std::string::npos) << err;
    // Line = index + 2 (header on line 1).
    EXPECT_NE(err.find(c.name + std::string(":") + std::to_string(row + 2) + ":"),
              std::string::npos)
        << err;
    EXPECT_EQ(fs::read_symlink(root_ / "latest"), latest);
    EXPECT_EQ(ReadFile(root_ / "model.yaml"), model);
    EXPECT_EQ(ReadFile(root_ / "report.json"), report);
  }
  // Both failed entries say so.
  int failed = 0;
  for (const auto& e : fs::directory_iterator(root_ / "history")) {
    if (ReadFile(e.path() / "status").rfind("failed: ", 0) == 0) ++failed;
  }
  EXPECT_EQ(failed, 2);
}

// One EDM row 0.5 m off among rows at 1e-5 m, without the gross-error
// handling: its residual cannot be absorbed, EDM sigma0 ~ 0.5 / 1e-5 /
// sqrt(3 n) >> 100 (fit.max_sigma0): exit 3 naming the row first.
TEST_F(Failure, ResidualsFarBeyondTheSigmasExitThreeNamingTheRow) {
  std::vector<Record> records = Records();
  const int row = GridRow(records, Tool::kEdm);
  records[row].x.z() += 0.5;
  std::string err;
  EXPECT_EQ(RunConfig(ConfigWithoutGrossErrors(records, "gross.csv"), &err), 3) << err;
  EXPECT_NE(err.find("calibration failed (residuals far beyond the sigmas)"), std::string::npos)
      << err;
  EXPECT_NE(err.find("\n  " + (dir_ / "gross.csv").string() + ":" + std::to_string(row + 2) +
                     ": EDM residual"),
            std::string::npos)
      << err;
  EXPECT_FALSE(fs::exists(root_ / "model.yaml"));
}

// One iteration cannot reach convergence from the extraction: exit 3, not a
// model "NOT converged" published.
TEST_F(Failure, NotConvergedExitsThree) {
  const fs::path config = Config(Records(), "records.csv");
  std::string text = ReadFile(config);
  text.replace(text.find("fit:\n"), 5, "fit:\n  max_iterations: 1\n");
  Put(config, text);
  std::string err;
  EXPECT_EQ(RunConfig(config, &err), 3) << err;
  EXPECT_NE(err.find("calibration failed (not converged)"), std::string::npos) << err;
  EXPECT_NE(err.find("Maximum number of iterations"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(root_ / "model.yaml"));
}

// Camera rows only: the EDM tool is written as not determined (no sigma),
// the report says so, and `predict` refuses EDM rows naming file and line.
TEST_F(Failure, ToolWithoutDataIsNotDeterminedAndPredictRefusesIt) {
  std::vector<Record> cam;
  std::vector<Record> edm;
  for (const Record& r : Records()) (r.tool == Tool::kCam ? cam : edm).push_back(r);
  std::string err;
  ASSERT_EQ(RunConfig(Config(cam, "cam_only.csv"), &err), 0) << err;
  ExpectAllFinite(root_);
  const YAML::Node model = YAML::LoadFile((root_ / "model.yaml").string());
  EXPECT_FALSE(model["edm"]["determined"].as<bool>());
  EXPECT_FALSE(model["edm"]["sigma"]) << "no sigma for a tool that was not estimated";
  EXPECT_TRUE(model["cameras"][0]["flange_from_cam"]["sigma"]);
  const nlohmann::json report = nlohmann::json::parse(ReadFile(root_ / "report.json"));
  EXPECT_EQ(report["model"]["edm"]["determined"], false);
  EXPECT_FALSE(report["model"]["edm"].contains("t_sigma"));
  EXPECT_NE(ReadFile(root_ / "report.txt").find("not determined by the data"), std::string::npos);

  const fs::path in = dir_ / "edm_rows.csv";
  WriteRecords(in.string(), {cam[0], edm[0]});
  EXPECT_EQ(Run("predict --model '" + (root_ / "model.yaml").string() + "' --records '" +
                    in.string() + "' --out '" + (dir_ / "pred.csv").string() + "'",
                &err),
            1);
  EXPECT_NE(err.find(in.string() + ":3: column 'tool'"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir_ / "pred.csv"));
  // Camera rows are predicted as before.
  WriteRecords(in.string(), {cam[0]});
  EXPECT_EQ(Run("predict --model '" + (root_ / "model.yaml").string() + "' --records '" +
                    in.string() + "' --out '" + (dir_ / "pred.csv").string() + "'",
                &err),
            0)
      << err;
}

// A records.csv joined to itself: a notice names the file and the line
// pairs, the copies are taken out (listed with the gross rows), and the fit
// is the single file's: the same errors and a-posteriori sigmas (the copies
// would shrink each sigma by 1/sqrt(2); 1e-9 relative allows for the
// summation order of a multithreaded fit).
TEST_F(Failure, RecordsJoinedToThemselvesGetANoticeAndCountOnce) {
  const std::vector<Record> once = Records();
  std::vector<Record> twice = once;
  twice.insert(twice.end(), once.begin(), once.end());
  std::string err;
  ASSERT_EQ(RunConfig(Config(once, "once.csv"), &err), 0) << err;
  const nlohmann::json a = nlohmann::json::parse(ReadFile(root_ / "report.json"));
  ASSERT_EQ(RunConfig(Config(twice, "twice.csv"), &err), 0) << err;
  const nlohmann::json b = nlohmann::json::parse(ReadFile(root_ / "report.json"));
  const std::string n = std::to_string(once.size());
  const std::string first_copy = std::to_string(once.size() + 2);
  bool noticed = false;
  for (const auto& note : b["notes"]) {
    noticed = noticed ||
              note.get<std::string>().find("twice.csv: " + n +
                                           " rows repeat an earlier row exactly (every "
                                           "column equal): line " +
                                           first_copy + " repeats line 2, ") != std::string::npos;
  }
  EXPECT_TRUE(noticed) << b["notes"].dump(1);
  size_t copies = 0;
  for (const auto& g : b["gross_errors"]) {
    copies += g["reason"].get<std::string>().rfind("an exact copy of line ", 0) == 0;
  }
  EXPECT_EQ(copies, once.size());
  EXPECT_EQ(b["gross_errors"].size(), a["gross_errors"].size() + once.size());
  EXPECT_EQ(a["final"]["records"]["edm"]["n"], b["final"]["records"]["edm"]["n"]);
  for (const char* sigma : {"sigma_edm_m", "sigma_cam_m"}) {
    const double sa = a["fit"][sigma].get<double>(), sb = b["fit"][sigma].get<double>();
    EXPECT_NEAR(sb, sa, 1e-9 * sa) << sigma;
  }
}

// A one-row pixels.csv beside records without camera rows: its zoom's camera
// comes from the pixels alone, which need shots of at least 4 points; the
// error names pixels.csv and what was needed, not a failed fit of records.csv.
TEST_F(Failure, OneRowPixelsCsvIsAnInputErrorNamingIt) {
  std::vector<Record> edm, cam;
  for (const Record& r : Records()) (r.tool == Tool::kCam ? cam : edm).push_back(r);
  ASSERT_FALSE(cam.empty());
  const Record& c = cam.front();
  const fs::path pixels = dir_ / "one_row_pixels.csv";
  std::ostringstream row;
  row.precision(17);
  row << "face,zoom,phi,theta,shot,target,corner,X,Y,Z,u,v\n"
      << c.face << "," << c.zoom << "," << c.phi << "," << c.theta << ",s1,0,0," << c.x.x() << ","
      << c.x.y() << "," << c.x.z() << "," << c.u << "," << c.v << "\n";
  Put(pixels, row.str());
  const fs::path config = Config(edm, "edm_only.csv");
  Put(config, ReadFile(config) + "  pixels: " + pixels.string() + "\n");
  std::string err;
  EXPECT_EQ(RunConfig(config, &err), 1) << err;
  EXPECT_NE(err.find(pixels.string() + ": zoom 0 (pixels from line 2)"), std::string::npos) << err;
  EXPECT_NE(err.find("fewer than min_points_per_shot = 4 points"), std::string::npos) << err;
  EXPECT_EQ(err.find("non-finite"), std::string::npos) << err;
  EXPECT_EQ(err.find("edm_only.csv:"), std::string::npos) << err;
}

// A config path that is a folder: said so, not read as an empty config
// whose first missing key is `data`.
TEST_F(Failure, ConfigThatIsAFolderIsNamedAsAFolder) {
  std::string err;
  EXPECT_EQ(RunConfig(dir_, &err), 1) << err;
  EXPECT_NE(err.find(dir_.string() + ": is a folder: expected a config (a YAML file), got 'a "
                                     "folder'"),
            std::string::npos)
      << err;
  EXPECT_EQ(err.find("'data'"), std::string::npos) << err;
}

// Pixels all in the critical region: nothing to start from, said with the
// config, the file, its row count and the window that took them out.
TEST_F(Failure, NothingToFitNamesTheConfigAndTheFile) {
  std::vector<Record> cam;
  for (const Record& r : Records()) {
    if (r.tool == Tool::kCam) cam.push_back(r);
  }
  const fs::path pixels = dir_ / "critical_pixels.csv";
  std::ostringstream rows;
  rows.precision(17);
  rows << "face,zoom,phi,theta,shot,target,corner,X,Y,Z,u,v\n";
  for (size_t i = 0; i < 8; ++i) {
    const Record& c = cam[i];
    rows << c.face << "," << c.zoom << "," << c.phi << "," << c.theta << ",s" << i / 4 << ",0,"
         << i % 4 << "," << c.x.x() << "," << c.x.y() << "," << c.x.z() << "," << c.u << "," << c.v
         << "\n";
  }
  Put(pixels, rows.str());
  // The fixture's config with the pixels instead of records and a critical
  // region that holds every row.
  const fs::path config = Config({}, "critical.csv");
  std::string text = ReadFile(config);
  text.replace(text.find("fit:\n"), 5,
               "fit:\n  critical_region: {min_zenith_deg: 170, max_zenith_deg: 175}\n");
  text.replace(text.find("  records: "), std::string::npos, "  pixels: " + pixels.string() + "\n");
  Put(config, text);
  std::string err;
  EXPECT_EQ(RunConfig(config, &err), 1) << err;
  EXPECT_NE(err.find(config.string() + ": nothing to start from: " + pixels.string() +
                     " gave 8 pixel observations; 8 of them lie in the critical region (zenith "
                     "angle outside fit.critical_region's 170 to 175 deg)"),
            std::string::npos)
      << err;
}

TEST_F(Failure, ExitCodesOfUsageAndInputErrorsAndHelp) {
  std::string err;
  EXPECT_EQ(Run("--no-such-option", &err), 2) << err;
  EXPECT_EQ(Run("", &err), 2) << err;  // no --config, no subcommand
  EXPECT_EQ(Run("--config '" + (dir_ / "missing.yaml").string() + "'", &err), 1) << err;
  const fs::path log = dir_ / "help.txt";
  const std::string cmd = std::string("'") + RTSCALIB_BINARY_DIR + "/app/rtscalib' --help > '" +
                          log.string() + "' 2>&1";
  const int status = std::system(cmd.c_str());
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  const std::string help = ReadFile(log);
  EXPECT_NE(help.find("Exit codes"), std::string::npos) << help;
  EXPECT_NE(help.find("3  fit failure"), std::string::npos) << help;
}

}  // namespace
}  // namespace rtscalib

// The output folder (SPEC 5, docs/output.md): checked atomic writes, entries
// unique across processes, a top that always shows one complete run, users'
// files never touched, killed runs listed as killed. Kills are real
// (SIGKILL in a forked child) at every step of a run and of publishing.
#include "app/output_folder.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "app/reports.h"
#include "libcalib/io/safe_write.h"
#include "libcalib/text/errors.h"
#include "tests/app/read_file.h"

namespace rtscalib::app {
namespace {

namespace fs = std::filesystem;
using testing_files::ReadFile;

void Put(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary) << text;
}

bool Exists(const fs::path& p) {
  std::error_code ec;
  return fs::symlink_status(p, ec).type() != fs::file_type::not_found;
}

class OutputFolderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("rtscalib_outdir_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    root_ = dir_ / "out";
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path dir_;
  fs::path root_;
};

// The content a fake run writes into `name`, so that a reader can tell
// which run a file came from.
std::string Content(const std::string& name, const std::string& run) {
  if (name == "report.json") return "{\"rtscalib\": {\"run\": \"" + run + "\"}}\n";
  return name + " of " + run + "\n";
}

const std::vector<std::string> kFiguresA = {"a.png", "b.png"};
const std::vector<std::string> kFiguresB = {"b.png", "c.png"};

// A run's files, as run_command writes them (through the checked writer).
// `point` is called after each step (the kill test stops there).
void WriteFakeRun(
    const OutputFolder& out, const std::vector<std::string>& figures,
    const std::function<void()>& point = [] {}) {
  for (const std::string& name : OutputFolder::TopFiles()) {
    out.Write(name, Content(name, out.run().name));
    point();
  }
  fs::create_directories(fs::path(out.run_dir()) / "figures");
  for (const std::string& f : figures) {
    out.Write("figures/" + f, Content(f, out.run().name));
    point();
  }
}

std::string FakeRun(const fs::path& root, const std::vector<std::string>& figures) {
  OutputFolder out(root.string());
  WriteFakeRun(out, figures);
  out.MarkComplete();
  EXPECT_TRUE(out.Publish().empty());
  return out.run().name;
}

// The top shows exactly one run, which is returned: `latest` names it, every
// top file and every figure that resolves is that run's, and all of its
// figures resolve.
std::string TopRun(const fs::path& root) {
  const std::string latest = fs::read_symlink(root / "latest").string();
  EXPECT_EQ(latest.rfind("history/", 0), 0u) << latest;
  const std::string run = latest.substr(8);
  for (const std::string& name : OutputFolder::TopFiles()) {
    EXPECT_EQ(ReadFile(root / name), Content(name, run)) << name;
  }
  std::set<std::string> resolving;
  for (const auto& e : fs::directory_iterator(root / "figures")) {
    const std::string f = e.path().filename().string();
    if (!e.is_symlink() || !fs::exists(e.path())) continue;
    resolving.insert(f);
    EXPECT_EQ(ReadFile(e.path()), Content(f, run)) << f;
  }
  std::set<std::string> of_run;
  for (const auto& e : fs::directory_iterator(root / "history" / run / "figures")) {
    const std::string f = e.path().filename().string();
    if (f.find(".tmp") == std::string::npos) of_run.insert(f);
  }
  EXPECT_EQ(resolving, of_run);
  return run;
}

// A soft file size limit for the duration of a scope: writes beyond it fail
// with EFBIG as on a full disk (SIGXFSZ ignored so that write returns the
// error). Works as root, unlike a read-only folder.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    getrlimit(RLIMIT_FSIZE, &old_);
    old_handler_ = std::signal(SIGXFSZ, SIG_IGN);
    rlimit lim = old_;
    lim.rlim_cur = bytes;
    setrlimit(RLIMIT_FSIZE, &lim);
  }
  ~FileSizeLimit() {
    setrlimit(RLIMIT_FSIZE, &old_);
    std::signal(SIGXFSZ, old_handler_);
  }

 private:
  rlimit old_{};
  void (*old_handler_)(int) = nullptr;
};

// --- the checked writer --------------------------------------------------

TEST_F(OutputFolderTest, WriterReplacesAFileWholeAndLeavesNoTmp) {
  const fs::path p = dir_ / "report.json";
  WriteFileAtomic(p.string(), "old");
  WriteFileAtomic(p.string(), "new content");
  EXPECT_EQ(ReadFile(p), "new content");
  EXPECT_FALSE(Exists(dir_ / "report.json.tmp"));
}

TEST_F(OutputFolderTest, WriterFailureNamesTheFileAndTheOsReasonAndKeepsTheOldFile) {
  const fs::path p = dir_ / "report.json";
  WriteFileAtomic(p.string(), "the previous good copy");
  const std::string big(64 * 1024, 'x');
  try {
    const FileSizeLimit limit(20480);  // the size the broken version cut report.json at
    WriteFileAtomic(p.string(), big);
    FAIL() << "no error for a write beyond the file size limit";
  } catch (const WriteError& e) {
    EXPECT_EQ(e.path, p.string());
    EXPECT_NE(std::string(e.what()).find(p.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(std::strerror(EFBIG)), std::string::npos) << e.what();
  }
  EXPECT_EQ(ReadFile(p), "the previous good copy");
  EXPECT_FALSE(Exists(dir_ / "report.json.tmp"));
}

TEST_F(OutputFolderTest, WriterWithAPathWriterReportsItsFailureWithErrno) {
  // Like libcalib's WriteModelYaml: an ofstream that throws a bare message.
  const fs::path p = dir_ / "model.yaml";
  auto write = [](const std::string& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    out << std::string(64 * 1024, 'y');
    out.close();
    if (!out) throw std::runtime_error("cannot write " + tmp);
  };
  try {
    const FileSizeLimit limit(4096);
    WriteFileAtomicWith(p.string(), write);
    FAIL() << "no error";
  } catch (const WriteError& e) {
    EXPECT_EQ(e.path, p.string());
    EXPECT_NE(e.reason.find(std::strerror(EFBIG)), std::string::npos) << e.what();
  }
  EXPECT_FALSE(Exists(p));
  EXPECT_FALSE(Exists(dir_ / "model.yaml.tmp"));
  WriteFileAtomicWith(p.string(), [](const std::string& tmp) { std::ofstream(tmp) << "ok"; });
  EXPECT_EQ(ReadFile(p), "ok");
}

TEST_F(OutputFolderTest, WriterFailsOnAMissingFolderAndOnAFolderInTheWay) {
  const fs::path missing = dir_ / "no_such_folder" / "report.txt";
  try {
    WriteFileAtomic(missing.string(), "x");
    FAIL() << "no error";
  } catch (const WriteError& e) {
    EXPECT_NE(e.reason.find(std::strerror(ENOENT)), std::string::npos) << e.what();
  }
  fs::create_directories(dir_ / "report.html");
  try {
    WriteFileAtomic((dir_ / "report.html").string(), "x");
    FAIL() << "no error";
  } catch (const WriteError& e) {
    EXPECT_NE(e.reason.find(std::strerror(EISDIR)), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_directory(dir_ / "report.html"));
  EXPECT_FALSE(Exists(dir_ / "report.html.tmp"));
}

TEST_F(OutputFolderTest, WriterKeepModeNeverReplacesAnExistingFile) {
  const fs::path p = dir_ / "my.yaml";
  Put(p, "the user's");
  EXPECT_THROW(WriteFileAtomic(p.string(), "ours", Existing::kKeep), WriteError);
  EXPECT_EQ(ReadFile(p), "the user's");
  EXPECT_FALSE(Exists(dir_ / "my.yaml.tmp"));
  WriteFileAtomic((dir_ / "new.yaml").string(), "ours", Existing::kKeep);
  EXPECT_EQ(ReadFile(dir_ / "new.yaml"), "ours");
}

// --- history and publishing ----------------------------------------------

TEST_F(OutputFolderTest, TopShowsTheLatestRunAndHistoryKeepsTheEarlierOne) {
  Put(root_ / "history" / "2024-notes" / "x.txt", "the user's, not a run");
  const std::string a = FakeRun(root_, kFiguresA);
  EXPECT_EQ(TopRun(root_), a);
  const std::string b = FakeRun(root_, kFiguresB);
  EXPECT_EQ(TopRun(root_), b);
  // a.png was only in run A: its link is gone from figures/, its file kept.
  EXPECT_FALSE(Exists(root_ / "figures" / "a.png"));
  EXPECT_EQ(ReadFile(root_ / "history" / a / "figures" / "a.png"), Content("a.png", a));
  for (const std::string& name : OutputFolder::TopFiles()) {
    EXPECT_EQ(ReadFile(root_ / "history" / a / name), Content(name, a));
  }
  const nlohmann::json manifest = nlohmann::json::parse(ReadFile(root_ / ".rtscalib-published"));
  EXPECT_EQ(manifest["run"], b);

  const OutputFolder next(root_.string());
  ASSERT_EQ(next.earlier().size(), 2u);
  EXPECT_EQ(next.earlier()[0].name, a);
  EXPECT_EQ(next.earlier()[1].name, b);
  EXPECT_EQ(next.earlier()[1].state, RunState::kComplete);
  EXPECT_EQ(next.run().number, 3);
  EXPECT_EQ(ReadFile(root_ / "history" / "2024-notes" / "x.txt"), "the user's, not a run");
}

TEST_F(OutputFolderTest, UsersFilesUnderPublishedNamesStopTheRunBeforeItStarts) {
  Put(root_ / "model.yaml", "my model");
  Put(root_ / "report.txt", "my report");
  Put(root_ / "figures" / "notes.txt", "my notes");
  try {
    OutputFolder out(root_.string());
    FAIL() << "no error for the user's files";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find((root_ / "model.yaml").string()), std::string::npos) << what;
    EXPECT_NE(what.find((root_ / "report.txt").string()), std::string::npos) << what;
  }
  EXPECT_EQ(ReadFile(root_ / "model.yaml"), "my model");
  EXPECT_EQ(ReadFile(root_ / "report.txt"), "my report");
  EXPECT_EQ(ReadFile(root_ / "figures" / "notes.txt"), "my notes");
  EXPECT_FALSE(Exists(root_ / "history"));  // nothing was written
}

TEST_F(OutputFolderTest, UsersOtherFilesSurviveRunsAndPublishing) {
  Put(root_ / "README.md", "my readme");
  Put(root_ / "figures" / "notes.txt", "my notes");
  Put(root_ / "figures" / "c.png", "my picture");  // a name run B publishes
  FakeRun(root_, kFiguresA);
  OutputFolder out(root_.string());
  WriteFakeRun(out, kFiguresB);
  out.MarkComplete();
  EXPECT_EQ(out.Publish(), std::vector<std::string>{"c.png"});
  EXPECT_EQ(ReadFile(root_ / "README.md"), "my readme");
  EXPECT_EQ(ReadFile(root_ / "figures" / "notes.txt"), "my notes");
  EXPECT_EQ(ReadFile(root_ / "figures" / "c.png"), "my picture");
  EXPECT_EQ(ReadFile(root_ / "figures" / "b.png"), Content("b.png", out.run().name));
  EXPECT_EQ(ReadFile(root_ / "model.yaml"), Content("model.yaml", out.run().name));
  const nlohmann::json manifest = nlohmann::json::parse(ReadFile(root_ / ".rtscalib-published"));
  EXPECT_EQ(manifest["kept_user_files"], nlohmann::json::array({"figures/c.png"}));
}

TEST_F(OutputFolderTest, AUsersFileAppearingDuringARunIsKeptAndTheOldRunStaysShown) {
  const std::string a = FakeRun(root_, kFiguresA);
  OutputFolder out(root_.string());
  WriteFakeRun(out, kFiguresB);
  out.MarkComplete();
  fs::remove(root_ / "report.html");  // the user replaces rtscalib's link by a file
  Put(root_ / "report.html", "my page");
  EXPECT_THROW(out.Publish(), InputError);
  EXPECT_EQ(ReadFile(root_ / "report.html"), "my page");
  EXPECT_EQ(fs::read_symlink(root_ / "latest").string(), "history/" + a);
  EXPECT_EQ(ReadFile(root_ / "model.yaml"), Content("model.yaml", a));
}

TEST_F(OutputFolderTest, PlainCopiesOfAnEarlierVersionAreAdoptedWithoutLoss) {
  // An output folder of the version before `latest`: a history entry without
  // a status file and plain copies of it at the top.
  const std::string old = "001-20250101-120000";
  for (const std::string& name : OutputFolder::TopFiles()) {
    Put(root_ / "history" / old / name, Content(name, old));
    Put(root_ / name, Content(name, old));
  }
  for (const std::string& f : kFiguresA) {
    Put(root_ / "history" / old / "figures" / f, Content(f, old));
    Put(root_ / "figures" / f, Content(f, old));
  }
  OutputFolder out(root_.string());
  ASSERT_EQ(out.earlier().size(), 1u);
  EXPECT_EQ(out.earlier()[0].state, RunState::kComplete);
  std::vector<std::string> kept;
  const std::vector<OutputFolder::PublishStep> steps = out.PlanPublish(&kept);
  ASSERT_FALSE(steps.empty());
  steps[0].run();  // adopting: the top still shows the old run, now through latest
  EXPECT_EQ(fs::read_symlink(root_ / "latest").string(), "history/" + old);
  for (const std::string& name : OutputFolder::TopFiles()) {
    EXPECT_EQ(ReadFile(root_ / name), Content(name, old));
  }
  WriteFakeRun(out, kFiguresB);
  out.MarkComplete();
  out.Publish();
  EXPECT_EQ(TopRun(root_), out.run().name);
  EXPECT_FALSE(Exists(root_ / "figures" / "a.png"));  // the old copy, not in this run
  for (const std::string& name : OutputFolder::TopFiles()) {
    EXPECT_EQ(ReadFile(root_ / "history" / old / name), Content(name, old));
  }
  EXPECT_EQ(ReadFile(root_ / "history" / old / "figures" / "a.png"), Content("a.png", old));
}

TEST_F(OutputFolderTest, ConcurrentProcessesGetDistinctEntries) {
  constexpr int kProcesses = 8;
  int gate[2];
  ASSERT_EQ(::pipe(gate), 0);
  std::vector<pid_t> children;
  for (int i = 0; i < kProcesses; ++i) {
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      ::close(gate[1]);
      char c;
      while (::read(gate[0], &c, 1) < 0 && errno == EINTR) {
      }
      try {
        OutputFolder out(root_.string());
        out.Write("who", std::to_string(::getpid()));
        out.MarkComplete();
        out.Publish();
      } catch (...) {
        ::_exit(1);
      }
      ::_exit(0);
    }
    children.push_back(pid);
  }
  ::close(gate[0]);
  ::close(gate[1]);  // all start at once, within one second
  std::set<std::string> pids;
  for (pid_t pid : children) {
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    pids.insert(std::to_string(pid));
  }
  const OutputFolder after(root_.string());
  ASSERT_EQ(after.earlier().size(), static_cast<size_t>(kProcesses));
  std::set<std::string> writers;
  for (int i = 0; i < kProcesses; ++i) {
    const HistoryEntry& e = after.earlier()[i];
    EXPECT_EQ(e.number, i + 1) << e.name;
    EXPECT_EQ(e.state, RunState::kComplete) << e.name;
    writers.insert(ReadFile(fs::path(e.dir) / "who"));
  }
  EXPECT_EQ(writers, pids);  // one entry per process
  const std::string shown = fs::read_symlink(root_ / "latest").string();
  EXPECT_TRUE(fs::is_regular_file(root_ / shown / "who")) << shown;
}

// Run B is killed (SIGKILL) after step `kill_at` of: making its entry,
// writing each file, marking it complete, each publishing step. Whatever the
// step, the top shows run A or run B whole; B is listed as killed unless it
// was complete; the next run publishes normally.
TEST_F(OutputFolderTest, AKillAtAnyStepLeavesOneWholeRunAtTheTopAndIsListedAsKilled) {
  // Steps before MarkComplete: the entry, the four files, B's figures.
  const int complete_step =
      1 + static_cast<int>(OutputFolder::TopFiles().size() + kFiguresB.size());
  bool finished = false;
  std::set<std::string> shown;
  for (int kill_at = 0; !finished && kill_at < 100; ++kill_at) {
    SCOPED_TRACE("killed after step " + std::to_string(kill_at));
    const fs::path root = dir_ / ("out" + std::to_string(kill_at));
    const std::string a = FakeRun(root, kFiguresA);
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      int step = 0;
      auto point = [&] {
        if (step++ == kill_at) ::raise(SIGKILL);
      };
      try {
        OutputFolder out(root.string());
        point();
        WriteFakeRun(out, kFiguresB, point);
        out.MarkComplete();
        point();
        std::vector<std::string> kept;
        for (const OutputFolder::PublishStep& s : out.PlanPublish(&kept)) {
          s.run();
          point();
        }
      } catch (...) {
        ::_exit(1);
      }
      ::_exit(0);
    }
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    if (WIFEXITED(status)) {
      ASSERT_EQ(WEXITSTATUS(status), 0);
      finished = true;
    } else {
      ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
    }
    const std::string top = TopRun(root);
    shown.insert(top == a ? "A" : "B");
    // The manifest at the top names the run the top shows, whatever step
    // the kill came at (it switches with `latest`).
    if (fs::exists(root / ".rtscalib-published")) {
      const nlohmann::json manifest = nlohmann::json::parse(ReadFile(root / ".rtscalib-published"));
      EXPECT_EQ(manifest["run"], top) << "killed at step " << kill_at;
    }

    OutputFolder next(root.string());
    ASSERT_EQ(next.earlier().size(), 2u);
    const HistoryEntry& b = next.earlier()[1];
    EXPECT_EQ(next.earlier()[0].state, RunState::kComplete);
    EXPECT_EQ(b.state, kill_at < complete_step ? RunState::kKilled : RunState::kComplete)
        << RunStateName(b.state) << " " << b.reason;
    if (b.state == RunState::kKilled) {
      EXPECT_EQ(top, a);
    }
    const nlohmann::json history = HistoryJson(next);
    EXPECT_EQ(history[1]["status"], RunStateName(b.state));
    EXPECT_EQ(history[1].contains("final"), false);  // fake reports carry no numbers
    if (b.state == RunState::kKilled) {
      EXPECT_NE(HistoryText(history).find("killed"), std::string::npos) << HistoryText(history);
    }
    WriteFakeRun(next, kFiguresA);
    next.MarkComplete();
    next.Publish();
    EXPECT_EQ(TopRun(root), next.run().name);
  }
  EXPECT_TRUE(finished) << "the child never ran to its end";
  EXPECT_EQ(shown, (std::set<std::string>{"A", "B"}));  // kills before and after the switch
}

TEST_F(OutputFolderTest, AFailedRunIsListedAsFailedWithItsReason) {
  {
    OutputFolder out(root_.string());
    out.MarkFailed("cannot write 'x': No space left on device\nsecond line");
  }
  const OutputFolder next(root_.string());
  ASSERT_EQ(next.earlier().size(), 1u);
  EXPECT_EQ(next.earlier()[0].state, RunState::kFailed);
  EXPECT_EQ(next.earlier()[0].reason, "cannot write 'x': No space left on device second line");
  const nlohmann::json history = HistoryJson(next);
  EXPECT_EQ(history[0]["status"], "failed");
  EXPECT_NE(HistoryText(history).find("failed"), std::string::npos);
}

// A run that fails when nothing can be written any more (a full disk; here
// a file size limit of 0): its entry still says failed, through the status
// written while there was room, never `running`.
TEST_F(OutputFolderTest, ARunFailingOnAFullDiskIsListedAsFailed) {
  {
    OutputFolder out(root_.string());
    const FileSizeLimit none(0);
    out.MarkFailed("cannot write 'model.yaml': File too large");
  }
  const OutputFolder next(root_.string());
  ASSERT_EQ(next.earlier().size(), 1u);
  EXPECT_EQ(next.earlier()[0].state, RunState::kFailed);
  EXPECT_NE(next.earlier()[0].reason.find("could not write why"), std::string::npos)
      << next.earlier()[0].reason;
  // A run that completes leaves no spare status behind.
  OutputFolder ok(root_.string());
  ok.MarkComplete();
  EXPECT_FALSE(Exists(fs::path(ok.run_dir()) / "status.failed"));
}

TEST_F(OutputFolderTest, AnotherLiveProcessesEntryIsListedAsRunning) {
  const OutputFolder first(root_.string());  // this process, alive
  const OutputFolder second(root_.string());
  ASSERT_EQ(second.earlier().size(), 1u);
  EXPECT_EQ(second.earlier()[0].state, RunState::kRunning);
}

// --- the real binary -------------------------------------------------------

class RtscalibBinary : public OutputFolderTest {
 protected:
  // Runs `rtscalib --config small.yaml --output root` in bash after
  // `prefix`; returns the exit code, stderr in *err. small.yaml is
  // configs/paper.yaml with a coarse grid of records (8 x 4 instead of
  // 24 x 12): what is tested here is the output folder, not the
  // calibration, and the paper's grid would make each sanitized run slow.
  int Run(const fs::path& root, const std::string& prefix, std::string* err) {
    const fs::path config = dir_ / "small.yaml";
    if (!fs::exists(config)) {
      std::ofstream(config) << "model:\n  kinematics: dh\n  effects: []\n  cameras:\n"
                               "    - {width: 1280, height: 960, fx: 1500, fy: 1500, cx: 637.5, "
                               "cy: 481.5}\n"
                               "fit:\n  sigmas: {edm_m: 1.0e-5, cam_m: 1.0e-5, pixel_px: 0.5}\n"
                               "simulate:\n  seed: 2018\n"
                               "  noise: {angle_arcsec: 1.0, distance_m: 1.0e-5, point_m: 5.0e-6}\n"
                               "  plan:\n    sweep_points: 15\n    edm_distances: [1, 2]\n"
                               "    cam_ray_length: 1\n    pixel_offset: 1\n"
                               "    grid: {phi_steps: 8, theta_steps: 4}\n"
                               "    faces: [1]\n    zooms: [0]\n";
    }
    const fs::path log = dir_ / "stderr.txt";
    const std::string cmd = "bash -c \"" + prefix + " '" + RTSCALIB_BINARY_DIR +
                            "/app/rtscalib' --config '" + config.string() + "' --output '" +
                            root.string() + "' --quiet > /dev/null 2> '" + log.string() + "'\"";
    const int status = std::system(cmd.c_str());
    *err = ReadFile(log);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
};

TEST_F(RtscalibBinary, TwoRunsAFullDiskAndAUsersFile) {
  std::string err;
  ASSERT_EQ(Run(root_, "", &err), 0) << err;
  ASSERT_EQ(Run(root_, "", &err), 0) << err;
  const nlohmann::json report = nlohmann::json::parse(ReadFile(root_ / "report.json"));
  const std::string second = report["rtscalib"]["run"];
  EXPECT_EQ(second.substr(0, 4), "002-");
  EXPECT_EQ(fs::read_symlink(root_ / "latest").string(), "history/" + second);
  ASSERT_EQ(report["history"].size(), 1u);
  EXPECT_EQ(report["history"][0]["status"], "complete");
  EXPECT_TRUE(report["history"][0].contains("final"));
  EXPECT_TRUE(fs::exists(root_ / "history" / report["history"][0]["run"] / "model.yaml"));
  const std::string model = ReadFile(root_ / "model.yaml");

  // A full disk (the file size limit gives the same failed writes): a
  // non-zero exit naming the file and the OS reason; the top is untouched;
  // the entry says failed.
  EXPECT_EQ(Run(root_, "trap '' XFSZ; ulimit -f 20;", &err), 1);
  EXPECT_NE(err.find("cannot write '" + root_.string() + "/history/003-"), std::string::npos)
      << err;
  EXPECT_NE(err.find(std::strerror(EFBIG)), std::string::npos) << err;
  EXPECT_EQ(ReadFile(root_ / "model.yaml"), model);
  EXPECT_EQ(ReadFile(root_ / "latest" / "status").substr(0, 8), "complete");
  ASSERT_EQ(Run(root_, "", &err), 0) << err;
  const nlohmann::json fourth = nlohmann::json::parse(ReadFile(root_ / "report.json"));
  ASSERT_EQ(fourth["history"].size(), 3u);
  EXPECT_EQ(fourth["history"][2]["status"], "failed");

  // A folder with the user's files under published names: exit 1 naming
  // them, nothing deleted.
  const fs::path mine = dir_ / "mine";
  Put(mine / "model.yaml", "my model");
  Put(mine / "report.txt", "my report");
  Put(mine / "figures" / "notes.txt", "my notes");
  EXPECT_EQ(Run(mine, "", &err), 1);
  EXPECT_NE(err.find((mine / "model.yaml").string()), std::string::npos) << err;
  EXPECT_EQ(ReadFile(mine / "model.yaml"), "my model");
  EXPECT_EQ(ReadFile(mine / "report.txt"), "my report");
  EXPECT_EQ(ReadFile(mine / "figures" / "notes.txt"), "my notes");
  // Only figures/notes.txt: the run goes ahead and keeps it.
  fs::remove(mine / "model.yaml");
  fs::remove(mine / "report.txt");
  ASSERT_EQ(Run(mine, "", &err), 0) << err;
  EXPECT_EQ(ReadFile(mine / "figures" / "notes.txt"), "my notes");
  EXPECT_TRUE(fs::exists(mine / "report.html"));
}

}  // namespace
}  // namespace rtscalib::app

#include "app/output_folder.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <csignal>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "libcalib/io/safe_write.h"
#include "libcalib/text/errors.h"

namespace fs = std::filesystem;

namespace rtscalib::app {
namespace {

constexpr const char* kHistory = "history";
constexpr const char* kLatest = "latest";
constexpr const char* kFigures = "figures";
constexpr const char* kManifest = ".rtscalib-published";
constexpr const char* kStatus = "status";
// Written beside `status` when the entry is made, while there is room: a
// run that fails on a full disk renames it onto `status` (a rename needs no
// free space), so that its entry never stays `running`.
constexpr const char* kStatusFailed = "status.failed";
constexpr const char* kLock = ".lock";

// An exclusive flock on history/.lock for as long as it lives. The kernel
// drops it when the process dies, so a killed run never blocks the next.
class FolderLock {
 public:
  explicit FolderLock(const fs::path& file) {
    fd_ = ::open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0644);
    if (fd_ < 0) throw WriteError(file.string(), ErrnoText(errno) + " (opening the lock file)");
    while (::flock(fd_, LOCK_EX) != 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      ::close(fd_);
      throw WriteError(file.string(), ErrnoText(err) + " (flock)");
    }
  }
  ~FolderLock() { ::close(fd_); }  // closing releases the lock
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int fd_ = -1;
};

std::string HostName() {
  char buf[256] = {};
  if (::gethostname(buf, sizeof(buf) - 1) != 0) return "?";
  return buf;
}

// Start time of a process in clock ticks since boot (/proc/<pid>/stat field
// 22), to tell a live run from a later process that reuses its pid; "" when
// unknown.
std::string ProcessStart(long pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string stat;
  if (!std::getline(in, stat)) return "";
  const size_t close = stat.rfind(')');  // the command name may hold spaces
  if (close == std::string::npos) return "";
  std::istringstream rest(stat.substr(close + 1));
  std::string field;
  for (int i = 3; i <= 22 && rest >> field; ++i) {
    if (i == 22) return field;
  }
  return "";
}

std::string Now(const char* format) {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  localtime_r(&now, &tm);
  std::ostringstream s;
  s << std::put_time(&tm, format);
  return s.str();
}

std::string OneLine(std::string s) {
  std::replace(s.begin(), s.end(), '\n', ' ');
  std::replace(s.begin(), s.end(), '\r', ' ');
  return s;
}

// The status file: first line the state, then `key: value` lines.
std::string StatusText(const std::string& state) {
  const long pid = static_cast<long>(::getpid());
  return state + "\npid: " + std::to_string(pid) + "\nhost: " + HostName() +
         "\nprocess_start: " + ProcessStart(pid) + "\ntime: " + Now("%Y-%m-%dT%H:%M:%S%z") + "\n";
}

RunState ReadState(const fs::path& dir, std::string* reason) {
  std::ifstream in(dir / kStatus);
  std::string first;
  if (!in || !std::getline(in, first)) {
    // Entries of rtscalib versions before the status file: complete when
    // their report.json is there.
    std::error_code ec;
    if (fs::exists(dir / "report.json", ec) && fs::exists(dir / "model.yaml", ec)) {
      return RunState::kComplete;
    }
    *reason = "no status file and no report.json";
    return RunState::kIncomplete;
  }
  if (first == "complete") return RunState::kComplete;
  if (first.rfind("failed", 0) == 0) {
    const std::string prefix = "failed: ";
    *reason = first.rfind(prefix, 0) == 0 ? first.substr(prefix.size()) : "";
    return RunState::kFailed;
  }
  std::string line, pid_text, host, start;
  while (std::getline(in, line)) {
    const size_t colon = line.find(": ");
    if (colon == std::string::npos) continue;
    const std::string key = line.substr(0, colon), value = line.substr(colon + 2);
    if (key == "pid") pid_text = value;
    if (key == "host") host = value;
    if (key == "process_start") start = value;
  }
  if (host != HostName()) {
    *reason = "running on host " + host + " (cannot be checked from here)";
    return RunState::kRunning;
  }
  const long pid = std::atol(pid_text.c_str());
  const bool exists = pid > 0 && (::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM);
  const std::string now_start = exists ? ProcessStart(pid) : "";
  const bool same = exists && (start.empty() || now_start.empty() || now_start == start);
  if (same) {
    *reason = "pid " + pid_text + " is still writing it";
    return RunState::kRunning;
  }
  *reason = "pid " + pid_text + " on " + host + " ended before the run was complete";
  return RunState::kKilled;
}

// The number of a history entry's name NNN-YYYYmmdd-HHMMSS (at least three
// digits, then eight and six), or 0 for any other name.
int EntryNumber(const std::string& name) {
  const size_t dash = name.find('-');
  if (dash == std::string::npos || dash < 3 || name.size() != dash + 16 || name[dash + 9] != '-') {
    return 0;
  }
  for (size_t i = 0; i < name.size(); ++i) {
    if (i != dash && i != dash + 9 && !std::isdigit(static_cast<unsigned char>(name[i]))) return 0;
  }
  return std::atoi(name.substr(0, dash).c_str());
}

// Entries of history/ (NNN-YYYYmmdd-HHMMSS; hidden `.new-<pid>` folders are
// entries being created).
std::vector<HistoryEntry> ScanHistory(const fs::path& history) {
  std::vector<HistoryEntry> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(history, ec)) {
    const std::string name = e.path().filename().string();
    // Only rtscalib's names: anything else in history/ is not a run.
    const int n = EntryNumber(name);
    if (n <= 0 || !e.is_directory(ec)) continue;
    out.push_back({e.path().string(), name, n, RunState::kComplete, ""});
  }
  std::sort(out.begin(), out.end(), [](const HistoryEntry& a, const HistoryEntry& b) {
    return a.number != b.number ? a.number < b.number : a.name < b.name;
  });
  return out;
}

bool ReadBytes(const fs::path& p, std::string* out) {
  std::ifstream in(p, std::ios::binary);
  if (!in) return false;
  std::ostringstream s;
  s << in.rdbuf();
  *out = s.str();
  return !in.bad();
}

// Who owns the name `at` at the top.
enum class Owner {
  kAbsent,
  kOurs,     // rtscalib's symlink (target as expected)
  kLegacy,   // a plain copy an earlier rtscalib version published: byte for
             // byte the same file as in a history entry, which keeps it
  kForeign,  // the user's
};
struct Found {
  Owner owner = Owner::kAbsent;
  std::string got;           // for messages: what is there
  std::string legacy_entry;  // kLegacy: the entry it is a copy of
};

Found Classify(const fs::path& root, const fs::path& at, const std::string& our_target,
               const std::string& rel) {
  std::error_code ec;
  const fs::file_status st = fs::symlink_status(at, ec);
  if (st.type() == fs::file_type::not_found) return {Owner::kAbsent, "", ""};
  if (ec) return {Owner::kForeign, "a file that cannot be inspected: " + ec.message(), ""};
  if (st.type() == fs::file_type::symlink) {
    const std::string target = fs::read_symlink(at, ec).string();
    if (!ec && target == our_target) return {Owner::kOurs, "", ""};
    return {Owner::kForeign, "a symlink to '" + target + "'", ""};
  }
  if (st.type() != fs::file_type::regular) return {Owner::kForeign, "a folder or special file", ""};
  const uintmax_t size = fs::file_size(at, ec);
  std::string mine;
  bool read = false;
  for (const HistoryEntry& e : ScanHistory(root / kHistory)) {
    const fs::path copy = fs::path(e.dir) / rel;
    std::error_code ec2;
    if (!fs::is_regular_file(copy, ec2) || fs::file_size(copy, ec2) != size) continue;
    if (!read && !(read = ReadBytes(at, &mine))) break;
    std::string theirs;
    if (ReadBytes(copy, &theirs) && theirs == mine) return {Owner::kLegacy, "", e.name};
  }
  return {Owner::kForeign, "a file rtscalib did not write", ""};
}

InputError ForeignError(const fs::path& at, const std::string& expected, const std::string& got,
                        const std::string& when) {
  return InputError::File(at.string(), 0,
                          "not written by rtscalib, which never replaces or removes it (" + when +
                              "; move it away or choose another --output)",
                          expected, got);
}

std::string TopTarget(const std::string& name) { return std::string(kLatest) + "/" + name; }
std::string FigureTarget(const std::string& name) {
  return std::string("../") + kLatest + "/" + kFigures + "/" + name;
}
bool IsOurLatest(const fs::path& at, std::string* got) {
  std::error_code ec;
  const fs::file_status st = fs::symlink_status(at, ec);
  if (st.type() == fs::file_type::not_found) return true;
  if (ec || st.type() != fs::file_type::symlink) {
    *got = "a file or folder that is not a symlink";
    return false;
  }
  const std::string target = fs::read_symlink(at, ec).string();
  if (!ec && target.rfind(std::string(kHistory) + "/", 0) == 0) return true;
  *got = "a symlink to '" + target + "'";
  return false;
}

// Makes `at` a symlink to `target` by renaming a fresh symlink onto it, so
// that `at` never goes missing in between.
void PlaceSymlink(const fs::path& at, const std::string& target) {
  const fs::path tmp =
      at.parent_path() / ("." + at.filename().string() + ".tmp-" + std::to_string(::getpid()));
  struct stat st {};
  // A leftover of a killed run with this pid; only ever a symlink.
  if (::lstat(tmp.c_str(), &st) == 0 && S_ISLNK(st.st_mode)) ::unlink(tmp.c_str());
  if (::symlink(target.c_str(), tmp.c_str()) != 0) {
    throw WriteError(at.string(), ErrnoText(errno) + " (symlink " + tmp.string() + ")");
  }
  if (::rename(tmp.c_str(), at.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    throw WriteError(at.string(), ErrnoText(err) + " (rename from " + tmp.string() + ")");
  }
}

// The checks run before a run starts: every fixed name rtscalib publishes is
// absent or rtscalib's.
void CheckTop(const fs::path& root) {
  std::error_code ec;
  if (!fs::exists(root, ec)) return;
  // Every conflict at once, so that one look at the message is enough.
  std::vector<InputError> errors;
  auto foreign = [&](const fs::path& at, const std::string& expected, const std::string& got) {
    errors.push_back(ForeignError(at, expected, got, "found before the run started"));
  };
  for (const std::string& name : OutputFolder::TopFiles()) {
    const Found f = Classify(root, root / name, TopTarget(name), name);
    if (f.owner == Owner::kForeign) {
      foreign(root / name, "no file of this name or rtscalib's symlink to " + TopTarget(name),
              f.got);
    }
  }
  std::string got;
  if (!IsOurLatest(root / kLatest, &got)) {
    foreign(root / kLatest, "no file of this name or rtscalib's symlink into history/", got);
  }
  // history/ may be a symlink to a folder elsewhere (another disk); figures/
  // holds rtscalib's relative symlinks and must be a folder here.
  const fs::file_status figures = fs::symlink_status(root / kFigures, ec);
  if (figures.type() != fs::file_type::not_found && figures.type() != fs::file_type::directory) {
    foreign(root / kFigures, "nothing or a folder", "a file or symlink");
  }
  const fs::file_status history = fs::status(root / kHistory, ec);
  if (history.type() != fs::file_type::not_found && history.type() != fs::file_type::directory) {
    foreign(root / kHistory, "nothing or a folder", "a file");
  }
  // The manifest: rtscalib's symlink through `latest`, or the plain file an
  // earlier version wrote there.
  const fs::file_status st = fs::symlink_status(root / kManifest, ec);
  const bool our_link = st.type() == fs::file_type::symlink &&
                        fs::read_symlink(root / kManifest, ec).string() == TopTarget(kManifest);
  if (st.type() != fs::file_type::not_found && st.type() != fs::file_type::regular && !our_link) {
    foreign(root / kManifest, "rtscalib's manifest (a symlink to " + TopTarget(kManifest) + ")",
            "a folder, another symlink or a special file");
  }
  if (errors.size() == 1) throw errors.front();
  if (!errors.empty()) throw InputError::Combine(errors);
}

void MakeFolder(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw WriteError(dir.string(), ec.message() + " (creating the folder)");
}

}  // namespace

const char* RunStateName(RunState state) {
  switch (state) {
    case RunState::kComplete:
      return "complete";
    case RunState::kRunning:
      return "running";
    case RunState::kKilled:
      return "killed";
    case RunState::kFailed:
      return "failed";
    case RunState::kIncomplete:
      return "incomplete";
  }
  return "?";
}

const std::vector<std::string>& OutputFolder::TopFiles() {
  static const std::vector<std::string> names = {"model.yaml",    "covariance.yaml", "report.json",
                                                 "residuals.csv", "report.txt",      "report.html"};
  return names;
}

OutputFolder::OutputFolder(const std::string& root)
    : root_(fs::absolute(root).lexically_normal().string()) {
  if (!root_.empty() && root_.size() > 1 && root_.back() == '/') root_.pop_back();
  std::error_code ec;
  if (fs::exists(root_, ec) && !fs::is_directory(root_, ec)) {
    throw InputError::File(root_, 0, "output folder", "a folder or a new name",
                           "a file that is not a folder");
  }
  CheckTop(root_);
  const fs::path history = fs::path(root_) / kHistory;
  MakeFolder(history);

  // Under the lock: read the entries, make the next number. The entry is
  // made under a hidden name with its status inside, then renamed, so that
  // every visible entry has a status file.
  const FolderLock lock(history / kLock);
  earlier_ = ScanHistory(history);
  int number = earlier_.empty() ? 1 : earlier_.back().number + 1;
  for (HistoryEntry& e : earlier_) e.state = ReadState(e.dir, &e.reason);

  std::ostringstream name;
  name << std::setw(3) << std::setfill('0') << number << "-" << Now("%Y%m%d-%H%M%S");
  const fs::path staging = history / (".new-" + std::to_string(::getpid()));
  fs::remove_all(staging, ec);  // this pid's own leftover (hidden names are rtscalib's)
  if (::mkdir(staging.c_str(), 0755) != 0) {
    throw WriteError(staging.string(), ErrnoText(errno) + " (creating the run's folder)");
  }
  WriteFileAtomic((staging / kStatus).string(), StatusText("running"));
  WriteFileAtomic((staging / kStatusFailed).string(),
                  StatusText("failed: the run stopped and could not write why (the disk may be "
                             "full); its last messages on the terminal say more"));
  fs::path dir = history / name.str();
  // Numbers are unique under the lock. An rtscalib version without the lock
  // may still have made this name meanwhile: rename() would fail on it (it
  // is not empty), so the number after is taken instead.
  for (int next = number + 1; fs::exists(dir, ec); ++next) {
    number = next;
    name.str("");
    name << std::setw(3) << std::setfill('0') << number << "-" << Now("%Y%m%d-%H%M%S");
    dir = history / name.str();
  }
  if (::rename(staging.c_str(), dir.c_str()) != 0) {
    throw WriteError(dir.string(), ErrnoText(errno) + " (rename from " + staging.string() + ")");
  }
  SyncFolder(history.string());
  run_ = {dir.string(), name.str(), number, RunState::kRunning, ""};
}

void OutputFolder::Write(const std::string& name, std::string_view bytes) const {
  WriteFileAtomic(RunFile(name), bytes);
}

void OutputFolder::MarkComplete() {
  // The renames of the run's files reach the disk first, then the status.
  std::error_code ec;
  if (fs::is_directory(fs::path(run_.dir) / kFigures, ec)) {
    SyncFolder((fs::path(run_.dir) / kFigures).string());
  }
  SyncFolder(run_.dir);
  WriteFileAtomic(RunFile(kStatus), StatusText("complete"));
  ::unlink(RunFile(kStatusFailed).c_str());
  complete_ = true;
  run_.state = RunState::kComplete;
}

void OutputFolder::MarkFailed(const std::string& reason) noexcept {
  if (complete_) return;
  try {
    WriteFileAtomic(RunFile(kStatus), StatusText("failed: " + OneLine(reason)));
    ::unlink(RunFile(kStatusFailed).c_str());
  } catch (...) {
    // No room for the reason: the status written while there was room. A
    // failing rename leaves the entry `running`, listed as killed.
    if (::rename(RunFile(kStatusFailed).c_str(), RunFile(kStatus).c_str()) == 0) {
      try {
        SyncFolder(run_.dir);
      } catch (...) {
      }
    }
  }
}

std::vector<OutputFolder::PublishStep> OutputFolder::PlanPublish(
    std::vector<std::string>* kept) const {
  const fs::path root(root_);
  const fs::path run(run_.dir);
  std::vector<PublishStep> steps;
  const std::string during = "found while publishing; this run is complete in history/" + run_.name;

  // Folders published by rtscalib versions before `latest` hold plain
  // copies: point `latest` at the run they are copies of first, so that
  // replacing them by symlinks below never changes what the top shows.
  steps.push_back({"adopt plain copies of an earlier version", [root] {
                     std::error_code ec;
                     if (fs::symlink_status(root / kLatest, ec).type() !=
                         fs::file_type::not_found) {
                       return;
                     }
                     for (const std::string& name : TopFiles()) {
                       const Found f = Classify(root, root / name, TopTarget(name), name);
                       if (f.owner == Owner::kLegacy) {
                         PlaceSymlink(root / kLatest, std::string(kHistory) + "/" + f.legacy_entry);
                         return;
                       }
                     }
                   }});
  steps.push_back({"make figures/", [root, during] {
                     std::error_code ec;
                     const fs::file_status st = fs::symlink_status(root / kFigures, ec);
                     if (st.type() == fs::file_type::not_found) {
                       MakeFolder(root / kFigures);
                     } else if (st.type() != fs::file_type::directory) {
                       throw ForeignError(root / kFigures, "nothing or a folder",
                                          "a file or symlink", during);
                     }
                   }});
  for (const std::string& name : TopFiles()) {
    std::error_code ec;
    if (!fs::exists(run / name, ec)) continue;
    steps.push_back({"link " + name, [root, name, during] {
                       const Found f = Classify(root, root / name, TopTarget(name), name);
                       if (f.owner == Owner::kForeign) {
                         throw ForeignError(
                             root / name,
                             "no file of this name or rtscalib's symlink to " + TopTarget(name),
                             f.got, during);
                       }
                       if (f.owner != Owner::kOurs) PlaceSymlink(root / name, TopTarget(name));
                     }});
  }
  std::vector<std::string> figures;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(run / kFigures, ec)) {
    if (e.is_regular_file(ec)) figures.push_back(e.path().filename().string());
  }
  std::sort(figures.begin(), figures.end());
  for (const std::string& f : figures) {
    steps.push_back({"link figures/" + f, [root, f, kept] {
                       const std::string rel = std::string(kFigures) + "/" + f;
                       const Found found = Classify(root, root / rel, FigureTarget(f), rel);
                       if (found.owner == Owner::kForeign) {
                         if (kept) kept->push_back(f);
                         return;
                       }
                       if (found.owner != Owner::kOurs) PlaceSymlink(root / rel, FigureTarget(f));
                     }});
  }
  // The manifest goes into the entry and is shown at the top through
  // `latest` like every other name, so that the one rename below switches it
  // with them: a kill at any point never leaves it naming another run than
  // the one the top shows.
  const std::string run_name = run_.name;
  steps.push_back({"write " + std::string(kManifest), [run, run_name, figures, kept] {
                     nlohmann::json m;
                     m["run"] = run_name;
                     m["latest"] = std::string(kHistory) + "/" + run_name;
                     m["files"] = TopFiles();
                     nlohmann::json figs = nlohmann::json::array();
                     nlohmann::json users = nlohmann::json::array();
                     for (const std::string& f : figures) {
                       const bool theirs = kept && std::count(kept->begin(), kept->end(), f) > 0;
                       (theirs ? users : figs).push_back(std::string(kFigures) + "/" + f);
                     }
                     m["figures"] = figs;
                     m["kept_user_files"] = users;
                     m["note"] =
                         "every listed name is a symlink resolving through `latest`; files not "
                         "listed are not rtscalib's";
                     WriteFileAtomic((run / kManifest).string(), m.dump(2) + "\n");
                   }});
  steps.push_back({"link " + std::string(kManifest), [root] {
                     // An earlier version's plain manifest is rtscalib's own
                     // (CheckTop): it becomes the symlink.
                     std::error_code ec;
                     const fs::path at = root / kManifest;
                     if (fs::symlink_status(at, ec).type() == fs::file_type::symlink &&
                         fs::read_symlink(at, ec).string() == TopTarget(kManifest)) {
                       return;
                     }
                     PlaceSymlink(at, TopTarget(kManifest));
                   }});
  // The commit point: one rename switches every name above to this run.
  const std::string entry = std::string(kHistory) + "/" + run_.name;
  steps.push_back({"switch latest", [root, entry, during] {
                     std::string got;
                     if (!IsOurLatest(root / kLatest, &got)) {
                       throw ForeignError(
                           root / kLatest,
                           "no file of this name or rtscalib's symlink into history/", got, during);
                     }
                     PlaceSymlink(root / kLatest, entry);
                     SyncFolder(root.string());
                   }});
  // Figures of the run shown before that this run lacks now dangle; they are
  // rtscalib's own symlinks, so they go. So do plain copies an earlier
  // version published that this run lacks (history keeps their originals).
  steps.push_back({"remove figures this run lacks", [root, figures] {
                     std::error_code ec2;
                     std::vector<fs::path> stale;
                     for (const auto& e : fs::directory_iterator(root / kFigures, ec2)) {
                       const std::string f = e.path().filename().string();
                       const std::string rel = std::string(kFigures) + "/" + f;
                       const Found found = Classify(root, e.path(), FigureTarget(f), rel);
                       const bool dangling =
                           found.owner == Owner::kOurs && !fs::exists(e.path(), ec2);
                       const bool old_copy =
                           found.owner == Owner::kLegacy &&
                           std::find(figures.begin(), figures.end(), f) == figures.end();
                       if (dangling || old_copy) stale.push_back(e.path());
                     }
                     for (const fs::path& p : stale) ::unlink(p.c_str());
                   }});
  return steps;
}

std::vector<std::string> OutputFolder::Publish() const {
  // Concurrent runs publish one after the other; the last to finish is shown.
  const FolderLock lock(fs::path(root_) / kHistory / kLock);
  std::vector<std::string> kept;
  for (const PublishStep& step : PlanPublish(&kept)) step.run();
  return kept;
}

}  // namespace rtscalib::app

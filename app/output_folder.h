// The output folder (SPEC 5; docs/output.md): its top shows the latest run's
// model.yaml, report.json, report.txt, report.html and figures/; every run is
// kept whole under history/<NNN>-<YYYYmmdd-HHMMSS>/ so that a re-run never
// destroys an earlier run's results and the report can compare runs.
//
//   OUT/history/NNN-date-time/   one run: status, config.yaml, model.yaml,
//                                report.*, figures/*.png, ...
//   OUT/latest                   symlink -> history/NNN-date-time (the run
//                                published last)
//   OUT/model.yaml, report.*     symlinks -> latest/<name>
//   OUT/figures/<f>.png          symlinks -> ../latest/figures/<f>.png
//   OUT/.rtscalib-published      which run the top shows and what rtscalib put
//                                there (JSON, for people and tools)
//
// Every name at the top resolves through `latest`, so publishing a run is one
// rename of `latest`: at every instant the top shows one complete run, never a
// mix. rtscalib owns only the symlinks it made (recognised by their targets);
// any other file is the user's and is never replaced or removed.
#pragma once

#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace rtscalib::app {

// What a history entry's `status` file says, judged when the folder is opened.
enum class RunState {
  kComplete,    // all of the run's files were written
  kRunning,     // another process is still writing it (or on another host)
  kKilled,      // "running", but its process is gone: the entry is partial
  kFailed,      // the run stopped on an error (`reason`)
  kIncomplete,  // no status file and no report.json (not a finished run)
};
const char* RunStateName(RunState state);

struct HistoryEntry {
  std::string dir;   // absolute
  std::string name;  // NNN-YYYYmmdd-HHMMSS
  int number = 0;
  RunState state = RunState::kComplete;
  std::string reason;  // why failed / killed / running, for the reports
};

class OutputFolder {
 public:
  // The published names at the top besides figures/.
  static const std::vector<std::string>& TopFiles();

  // Checks that the top holds no file of the user's under a name rtscalib
  // publishes (throws InputError naming it, before anything is written),
  // then creates `root`, history/ and this run's entry with status
  // `running`. The entry's number is unique among concurrent processes (a
  // flock on history/.lock). Throws WriteError when a folder cannot be made.
  explicit OutputFolder(const std::string& root);

  const std::string& root() const { return root_; }
  const std::string& run_dir() const { return run_.dir; }
  const HistoryEntry& run() const { return run_; }
  // Earlier entries, oldest first (not including this one), with their state.
  const std::vector<HistoryEntry>& earlier() const { return earlier_; }

  // Path of a file in this run's entry.
  std::string RunFile(const std::string& name) const { return run_.dir + "/" + name; }
  // Writes `bytes` to RunFile(name) through WriteFileAtomic.
  void Write(const std::string& name, std::string_view bytes) const;

  // The entry's status: `complete` once every file is written, or
  // `failed: <reason>`. MarkFailed never throws (it runs while an error
  // propagates; if even the status cannot be written the entry stays
  // `running` and is listed as killed). After MarkComplete, MarkFailed
  // leaves the status alone: a run whose publishing fails is still whole.
  void MarkComplete();
  void MarkFailed(const std::string& reason) noexcept;

  // One step of publishing; Publish runs them in order. Exposed so that a
  // test can stop after any step, as a kill would.
  struct PublishStep {
    std::string what;
    std::function<void()> run;
  };
  // `kept` receives the figures/ names held by a user's file, which this
  // run therefore publishes only in its history entry.
  std::vector<PublishStep> PlanPublish(std::vector<std::string>* kept) const;

  // Shows this run at the top (see the header comment). Returns the figures
  // kept as the user's. Throws InputError when a user's file took a top
  // name during the run (the run stays complete in history), WriteError on
  // I/O errors.
  std::vector<std::string> Publish() const;

 private:
  std::string root_;
  HistoryEntry run_;
  std::vector<HistoryEntry> earlier_;
  bool complete_ = false;
};

}  // namespace rtscalib::app

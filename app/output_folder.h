// The output folder (SPEC 5): its top holds the latest run's model.yaml,
// report.json and report.html; every run is kept whole under
// history/<NNN>-<YYYYmmdd-HHMMSS>/ so that a re-run never destroys an earlier
// run's results and the report can compare runs.
#pragma once

#include <string>
#include <vector>

namespace rtscalib::app {

struct HistoryEntry {
  std::string dir;   // absolute
  std::string name;  // NNN-YYYYmmdd-HHMMSS
  int number = 0;
};

class OutputFolder {
 public:
  // Creates `root` and a new history entry. Throws std::runtime_error with the
  // path when the folder cannot be created or is a file.
  explicit OutputFolder(const std::string& root);

  const std::string& root() const { return root_; }
  const std::string& run_dir() const { return run_.dir; }
  const HistoryEntry& run() const { return run_; }
  // Earlier runs, oldest first (not including this one).
  const std::vector<HistoryEntry>& earlier() const { return earlier_; }

  // Path of a file in this run's folder.
  std::string RunFile(const std::string& name) const { return run_.dir + "/" + name; }
  // Copies this run's files (and folders) `names` to the top of the output
  // folder, replacing the previous latest copies (those stay in history).
  void Publish(const std::vector<std::string>& names) const;

 private:
  std::string root_;
  HistoryEntry run_;
  std::vector<HistoryEntry> earlier_;
};

}  // namespace rtscalib::app

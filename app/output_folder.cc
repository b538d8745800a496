#include "app/output_folder.h"

#include <algorithm>
#include <ctime>
#include <filesystem>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace fs = std::filesystem;

namespace rtscalib::app {

OutputFolder::OutputFolder(const std::string& root)
    : root_(fs::absolute(root).lexically_normal().string()) {
  std::error_code ec;
  if (fs::exists(root_) && !fs::is_directory(root_)) {
    throw std::runtime_error("output folder '" + root_ + "' exists and is not a folder");
  }
  fs::create_directories(fs::path(root_) / "history", ec);
  if (ec) throw std::runtime_error("cannot create output folder '" + root_ + "': " + ec.message());
  int last = 0;
  for (const auto& entry : fs::directory_iterator(fs::path(root_) / "history")) {
    if (!entry.is_directory()) continue;
    const std::string name = entry.path().filename().string();
    const int n = std::atoi(name.substr(0, name.find('-')).c_str());
    if (n <= 0) continue;
    earlier_.push_back({entry.path().string(), name, n});
    last = std::max(last, n);
  }
  std::sort(earlier_.begin(), earlier_.end(),
            [](const HistoryEntry& a, const HistoryEntry& b) { return a.number < b.number; });
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  localtime_r(&now, &tm);
  std::ostringstream name;
  name << std::setw(3) << std::setfill('0') << last + 1 << "-"
       << std::put_time(&tm, "%Y%m%d-%H%M%S");
  run_ = {(fs::path(root_) / "history" / name.str()).string(), name.str(), last + 1};
  fs::create_directories(run_.dir, ec);
  if (ec) throw std::runtime_error("cannot create run folder '" + run_.dir + "': " + ec.message());
}

void OutputFolder::Publish(const std::vector<std::string>& names) const {
  for (const std::string& n : names) {
    const fs::path from = fs::path(run_.dir) / n;
    const fs::path to = fs::path(root_) / n;
    if (!fs::exists(from)) continue;
    std::error_code ec;
    fs::remove_all(to, ec);  // the previous latest copy; its original stays in history
    fs::copy(from, to, fs::copy_options::recursive | fs::copy_options::overwrite_existing, ec);
    if (ec)
      throw std::runtime_error("cannot copy '" + from.string() + "' to '" + to.string() +
                               "': " + ec.message());
  }
}

}  // namespace rtscalib::app

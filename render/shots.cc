#include "render/shots.h"

#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

#include <opencv2/imgcodecs.hpp>

#include "detect/photos.h"
#include "detect/point_boards.h"
#include "libcalib/io/safe_write.h"
#include "libcalib/text/number_text.h"

namespace rtscalib::render {
namespace fs = std::filesystem;
namespace {

const char kShotsHeader[] = "index,shot,face,zoom,phi,theta,image";
// Optional columns after kShotsHeader's, in this order.
const char* const kShotsOptional[] = {"placement", "focus_distance"};
const char kExactHeader[] = "face,zoom,phi,theta,shot,target,corner,X,Y,Z,u,v,status";

bool ValidId(const std::string& id) {
  if (id.empty() || id[0] == '.') return false;
  for (char c : id) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.'))
      return false;
  }
  return true;
}

std::string ImageName(const Shot& s) { return s.id + ".png"; }

// Throttled progress lines on stderr: at most one per second, plus the last.
class Progress {
 public:
  Progress(std::string what, int total, bool enabled)
      : what_(std::move(what)),
        total_(total),
        enabled_(enabled),
        start_(std::chrono::steady_clock::now()),
        last_(start_) {}
  void Update(int done) {
    if (!enabled_) return;
    const auto now = std::chrono::steady_clock::now();
    if (done < total_ && now - last_ < std::chrono::seconds(1)) return;
    last_ = now;
    const double s = std::chrono::duration<double>(now - start_).count();
    std::fprintf(stderr, "%s: %d/%d shots, %.1f s, %.1f images/s\n", what_.c_str(), done, total_, s,
                 s > 0 ? done / s : 0.0);
    std::fflush(stderr);
  }

 private:
  std::string what_;
  int total_;
  bool enabled_;
  std::chrono::steady_clock::time_point start_, last_;
};

// Renders `indices` of `shots` into out_dir; calls done(index) after each
// image. One SceneRenderer holds the placements the indices need, each
// selected in turn.
void RenderIndices(const PlacedScenes& scenes, const std::vector<Shot>& shots,
                   const std::vector<int>& indices, const RenderShotsOptions& options,
                   const std::function<void(int)>& done) {
  HeadlessDisplay display(options.headless);
  std::map<std::string, int> scene_of;
  std::vector<TargetScene> needed;
  for (int i : indices) {
    if (scene_of.emplace(shots[i].placement, static_cast<int>(needed.size())).second) {
      needed.push_back(scenes.at(shots[i].placement));
    }
  }
  if (needed.empty()) return;
  SceneRenderer renderer(needed, options.render);
  for (int i : indices) {
    const Shot& s = shots[i];
    renderer.SelectScene(scene_of.at(s.placement));
    const cv::Mat img = renderer.Render(s.ref_from_cam, s.cam, static_cast<std::uint64_t>(i));
    const std::string path = (fs::path(options.out_dir) / ImageName(s)).string();
    // Encoded in memory and written through the checked writer: a full disk
    // is a WriteError naming the image, never a photo cut short.
    std::vector<unsigned char> png;
    if (!EncodePhotoPng(img, options.png_compression, &png)) {
      throw std::runtime_error("RenderShots: OpenCV could not encode " + path);
    }
    WriteFileAtomic(path, std::string_view(reinterpret_cast<const char*>(png.data()), png.size()));
    done(i);
  }
}

// Full write(2) of a string; false on error.
bool WriteAll(int fd, const std::string& s) {
  size_t off = 0;
  while (off < s.size()) {
    const ssize_t n = ::write(fd, s.data() + off, s.size() - off);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    off += static_cast<size_t>(n);
  }
  return true;
}

// Forks `jobs` workers over `indices`; worker k takes every jobs-th index
// starting at k. Each reports "ok <index>" or "error <message>" lines on its
// own pipe.
void RenderInWorkers(const PlacedScenes& scenes, const std::vector<Shot>& shots,
                     const std::vector<int>& indices, const RenderShotsOptions& options,
                     Progress* progress) {
  const int jobs = std::min<int>(options.jobs, static_cast<int>(indices.size()));
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  const std::string lp_threads = std::to_string(std::max(1u, cores / static_cast<unsigned>(jobs)));
  struct Worker {
    pid_t pid = -1;
    int fd = -1;
    std::string buffer;
  };
  std::vector<Worker> workers(jobs);
  // Stops the workers already started when starting the next one fails.
  auto abandon = [&](int started, const std::string& what) {
    for (int j = 0; j < started; ++j) {
      ::kill(workers[j].pid, SIGTERM);
      ::waitpid(workers[j].pid, nullptr, 0);
      ::close(workers[j].fd);
    }
    throw std::runtime_error("RenderShots: " + what + " failed: " + std::strerror(errno));
  };
  std::fflush(nullptr);  // or buffered output would be written once per process
  for (int k = 0; k < jobs; ++k) {
    int fds[2];
    if (::pipe(fds) != 0) abandon(k, "pipe()");
    const pid_t pid = ::fork();
    if (pid < 0) {
      ::close(fds[0]);
      ::close(fds[1]);
      abandon(k, "fork()");
    }
    if (pid == 0) {
      ::close(fds[0]);
      for (int j = 0; j < k; ++j) ::close(workers[j].fd);
      int code = 0;
      try {
        ::setenv("LP_NUM_THREADS", lp_threads.c_str(), 0);
        std::vector<int> mine;
        for (size_t j = k; j < indices.size(); j += jobs) mine.push_back(indices[j]);
        RenderIndices(scenes, shots, mine, options,
                      [&](int i) { WriteAll(fds[1], "ok " + std::to_string(i) + "\n"); });
      } catch (const WriteError& e) {
        // Passed on as what it is: the parent throws it again, naming the file.
        std::string reason = e.reason;
        std::replace(reason.begin(), reason.end(), '\n', ' ');
        WriteAll(fds[1], "write_error " + e.path + "\t" + reason + "\n");
        code = 1;
      } catch (const std::exception& e) {
        std::string msg = e.what();
        std::replace(msg.begin(), msg.end(), '\n', ' ');
        WriteAll(fds[1], "error worker " + std::to_string(k) + ": " + msg + "\n");
        code = 1;
      }
      ::close(fds[1]);
      // No exit handlers or static destructors of the parent's state.
      ::_exit(code);
    }
    ::close(fds[1]);
    workers[k].pid = pid;
    workers[k].fd = fds[0];
  }

  int done = 0, open = jobs;
  std::string error;
  std::optional<WriteError> write_error;
  while (open > 0) {
    std::vector<pollfd> pfds;
    std::vector<int> who;
    for (int k = 0; k < jobs; ++k) {
      if (workers[k].fd >= 0) {
        pfds.push_back({workers[k].fd, POLLIN, 0});
        who.push_back(k);
      }
    }
    if (::poll(pfds.data(), pfds.size(), -1) < 0) {
      if (errno == EINTR) continue;
      break;
    }
    for (size_t j = 0; j < pfds.size(); ++j) {
      if (pfds[j].revents == 0) continue;
      Worker& w = workers[who[j]];
      char buf[4096];
      const ssize_t n = ::read(w.fd, buf, sizeof(buf));
      if (n <= 0) {
        ::close(w.fd);
        w.fd = -1;
        --open;
        continue;
      }
      w.buffer.append(buf, static_cast<size_t>(n));
      size_t nl;
      while ((nl = w.buffer.find('\n')) != std::string::npos) {
        const std::string line = w.buffer.substr(0, nl);
        w.buffer.erase(0, nl + 1);
        if (line.rfind("ok ", 0) == 0) {
          progress->Update(++done);
        } else if (line.rfind("write_error ", 0) == 0) {
          const size_t tab = line.find('\t');
          if (!write_error && tab != std::string::npos) {
            write_error.emplace(line.substr(12, tab - 12), line.substr(tab + 1));
          }
        } else if (error.empty()) {
          error = line.rfind("error ", 0) == 0 ? line.substr(6) : line;
        }
      }
    }
  }
  bool crashed = false;
  for (Worker& w : workers) {
    int status = 0;
    ::waitpid(w.pid, &status, 0);
    crashed = crashed || !WIFEXITED(status) || WEXITSTATUS(status) != 0;
  }
  if (write_error) throw *write_error;
  if (!error.empty()) throw std::runtime_error("RenderShots: " + error);
  if (crashed || done != static_cast<int>(indices.size())) {
    throw std::runtime_error("RenderShots: a worker process died after " + std::to_string(done) +
                             " of " + std::to_string(indices.size()) + " images");
  }
}

std::vector<std::string> SplitCsvLine(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) out.push_back(cell);
  return out;
}

// The scene board holding target `id` (tag ids are unique within a scene:
// ExpectTags keys its tags by id).
int BoardIndexOf(const TargetScene& scene, int id) {
  for (size_t b = 0; b < scene.boards.size(); ++b) {
    if (scene.boards[b].HasId(id)) return static_cast<int>(b);
  }
  throw std::logic_error("DetectShots: matched target " + std::to_string(id) + " is on no board");
}

// K and N of a shard's table name "shots.shard-K-of-N.csv" (ShotsTableName);
// false for any other name.
bool ParseShardTableName(const std::string& name, int* shard, int* num_shards) {
  const std::string head = "shots.shard-", mid = "-of-", tail = ".csv";
  auto number = [&](size_t from, size_t to, int* out) {
    if (to <= from || to - from > 9) return false;
    for (size_t i = from; i < to; ++i) {
      if (!std::isdigit(static_cast<unsigned char>(name[i]))) return false;
    }
    *out = std::stoi(name.substr(from, to - from));
    return true;
  };
  if (name.size() <= head.size() + mid.size() + tail.size() || name.rfind(head, 0) != 0 ||
      name.compare(name.size() - tail.size(), tail.size(), tail) != 0) {
    return false;
  }
  const size_t m = name.find(mid, head.size());
  return m != std::string::npos && number(head.size(), m, shard) &&
         number(m + mid.size(), name.size() - tail.size(), num_shards);
}

}  // namespace

std::string CheckShots(const std::vector<Shot>& shots) {
  std::set<std::string> ids;
  for (size_t i = 0; i < shots.size(); ++i) {
    const Shot& s = shots[i];
    const std::string where = "shot " + std::to_string(i) + " ('" + s.id + "'): ";
    if (!ValidId(s.id))
      return where + "id: expected letters, digits, '_', '-', '.' (no leading '.')";
    if (!ids.insert(s.id).second) return where + "id: duplicated";
    if (!s.placement.empty() && !ValidId(s.placement))
      return where + "placement: expected letters, digits, '_', '-', '.' (no leading '.')";
    if (s.face != 1 && s.face != 2)
      return where + "face: expected 1 or 2, got " + std::to_string(s.face);
    if (s.zoom < 0) return where + "zoom: expected >= 0, got " + std::to_string(s.zoom);
    if (s.cam.width < 1 || s.cam.height < 1) return where + "cam: expected a positive image size";
    if (!(s.cam.intrinsics[0] > 0 && s.cam.intrinsics[1] > 0))
      return where + "cam: expected fx, fy > 0";
  }
  return "";
}

std::string RenderShotsOptions::Check() const {
  if (out_dir.empty()) return "out_dir: expected a folder";
  if (jobs < 1) return "jobs: expected >= 1, got " + std::to_string(jobs);
  if (num_shards < 1) return "num_shards: expected >= 1, got " + std::to_string(num_shards);
  if (shard < 0 || shard >= num_shards) {
    return "shard: expected 0.." + std::to_string(num_shards - 1) + ", got " +
           std::to_string(shard);
  }
  if (png_compression < -1 || png_compression > 9) {
    return "png_compression: expected -1..9, got " + std::to_string(png_compression);
  }
  if (const std::string m = render.Check(); !m.empty()) return "render." + m;
  if (const std::string m = visibility.Check(); !m.empty()) return "visibility." + m;
  if (const std::string m = headless.Check(); !m.empty()) return "headless." + m;
  return "";
}

std::string DetectShotsOptions::Check() const {
  if (jobs < 1) return "jobs: expected >= 1, got " + std::to_string(jobs);
  if (const std::string m = match.Check(); !m.empty()) return "match." + m;
  if (const std::string m = visibility.Check(); !m.empty()) return "visibility." + m;
  return "";
}

bool EncodePhotoPng(const cv::Mat& img, int png_compression, std::vector<unsigned char>* png) {
  // Without a level OpenCV takes its speed setting (SUB filter, level 1).
  const std::vector<int> params =
      png_compression < 0 ? std::vector<int>{}
                          : std::vector<int>{cv::IMWRITE_PNG_COMPRESSION, png_compression};
  return cv::imencode(".png", img, *png, params);
}

std::string ShotsTableName(int shard, int num_shards) {
  if (num_shards == 1) return "shots.csv";
  return "shots.shard-" + std::to_string(shard) + "-of-" + std::to_string(num_shards) + ".csv";
}

std::string ExactTableName(int shard, int num_shards) {
  if (num_shards == 1) return "exact.csv";
  return "exact.shard-" + std::to_string(shard) + "-of-" + std::to_string(num_shards) + ".csv";
}

RenderShotsResult RenderShots(const TargetScene& scene, const std::vector<Shot>& shots,
                              const RenderShotsOptions& options) {
  return RenderShots(PlacedScenes{{"", scene}}, shots, options);
}

RenderShotsResult RenderShots(const PlacedScenes& scenes, const std::vector<Shot>& shots,
                              const RenderShotsOptions& options) {
  if (const std::string m = options.Check(); !m.empty()) {
    throw std::invalid_argument("RenderShotsOptions: " + m);
  }
  if (const std::string m = CheckShots(shots); !m.empty())
    throw std::invalid_argument("shots: " + m);
  bool placements = false, focus = false;
  for (const Shot& s : shots) {
    if (!scenes.count(s.placement)) {
      throw std::invalid_argument("shots: shot " + s.id + " has placement '" + s.placement +
                                  "', which has no scene");
    }
    placements = placements || !s.placement.empty();
    focus = focus || s.focus_distance > 0;
  }
  fs::create_directories(options.out_dir);

  std::vector<int> indices;
  for (int i = 0; i < static_cast<int>(shots.size()); ++i) {
    if (i % options.num_shards == options.shard) indices.push_back(i);
  }

  // The tables need no rendering: written first, from the exact model.
  RenderShotsResult result;
  {
    std::ostringstream st, ex;
    st << kShotsHeader << (placements ? ",placement" : "") << (focus ? ",focus_distance" : "")
       << "\n";
    ex << kExactHeader << "\n";
    for (int i : indices) {
      const Shot& s = shots[i];
      st << i << "," << s.id << "," << s.face << "," << s.zoom << "," << FormatDouble(s.phi) << ","
         << FormatDouble(s.theta) << "," << ImageName(s);
      if (placements) st << "," << s.placement;
      if (focus) st << "," << (s.focus_distance > 0 ? FormatDouble(s.focus_distance) : "");
      st << "\n";
      const TargetScene& scene = scenes.at(s.placement);
      for (const ExpectedTag& t : ExpectTags(scene, s.ref_from_cam, s.cam, options.visibility)) {
        if (t.status == TagStatus::kBehind || t.status == TagStatus::kBackFacing ||
            t.status == TagStatus::kOutside || t.status == TagStatus::kOccluded) {
          continue;
        }
        for (int c = 0; c < t.corners; ++c) {
          if (!t.in_image[c]) continue;
          ex << s.face << "," << s.zoom << "," << FormatDouble(s.phi) << ","
             << FormatDouble(s.theta) << "," << s.id << "," << t.id << "," << c << ","
             << FormatDouble(t.X[c].x()) << "," << FormatDouble(t.X[c].y()) << ","
             << FormatDouble(t.X[c].z()) << "," << FormatDouble(t.uv[c].x()) << ","
             << FormatDouble(t.uv[c].y()) << "," << TagStatusName(t.status) << "\n";
          ++result.exact_corners;
        }
      }
    }
    // Through the checked writer: a full disk is a WriteError naming the table.
    WriteFileAtomic(
        (fs::path(options.out_dir) / ShotsTableName(options.shard, options.num_shards)).string(),
        st.str());
    WriteFileAtomic(
        (fs::path(options.out_dir) / ExactTableName(options.shard, options.num_shards)).string(),
        ex.str());
  }
  if (indices.empty()) return result;

  const auto start = std::chrono::steady_clock::now();
  std::string what = "render";
  if (options.num_shards > 1) {
    what += " shard " + std::to_string(options.shard) + "/" + std::to_string(options.num_shards);
  }
  Progress progress(what, static_cast<int>(indices.size()), options.progress);
  if (options.jobs == 1 || indices.size() == 1) {
    int done = 0;
    RenderIndices(scenes, shots, indices, options, [&](int) { progress.Update(++done); });
  } else {
    // One display for all workers; each worker's HeadlessDisplay adopts it.
    HeadlessDisplay display(options.headless);
    RenderInWorkers(scenes, shots, indices, options, &progress);
  }
  result.rendered = static_cast<int>(indices.size());
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

void MergeShards(const std::vector<std::string>& shard_dirs, const std::string& out_dir) {
  struct Table {
    std::string dir, shots, exact;
  };
  std::map<int, Table> found;  // shard -> tables
  int n = -1;
  for (const std::string& dir : shard_dirs) {
    if (!fs::is_directory(dir)) throw std::runtime_error("MergeShards: no folder " + dir);
    for (const auto& entry : fs::directory_iterator(dir)) {
      const std::string name = entry.path().filename().string();
      int k = 0, m = 0;
      if (!ParseShardTableName(name, &k, &m)) continue;
      if (n < 0) n = m;
      if (m != n) {
        throw std::runtime_error("MergeShards: " + entry.path().string() + " belongs to a " +
                                 std::to_string(m) + "-way split, expected " + std::to_string(n));
      }
      if (found.count(k) != 0) {
        throw std::runtime_error("MergeShards: shard " + std::to_string(k) + " found twice (" +
                                 found[k].dir + " and " + dir + ")");
      }
      const fs::path exact = fs::path(dir) / ExactTableName(k, m);
      if (!fs::exists(exact)) throw std::runtime_error("MergeShards: missing " + exact.string());
      found[k] = {dir, entry.path().string(), exact.string()};
    }
  }
  if (n < 0)
    throw std::runtime_error("MergeShards: no shard tables (shots.shard-K-of-N.csv) found");
  for (int k = 0; k < n; ++k) {
    if (found.count(k) == 0) {
      throw std::runtime_error("MergeShards: shard " + std::to_string(k) + " of " +
                               std::to_string(n) + " is missing");
    }
  }
  fs::create_directories(out_dir);

  // Rows keyed by shot index; exact rows follow their shot.
  std::map<int, std::string> shot_rows;
  std::map<int, std::vector<std::string>> exact_rows;
  std::string header;  // the shards' shots.csv header (with or without placement)
  for (const auto& [k, t] : found) {
    std::map<std::string, int> index_of_shot;
    std::ifstream in(t.shots);
    std::string line;
    std::getline(in, line);
    // kShotsHeader, then optional columns in their order.
    bool known = line.rfind(kShotsHeader, 0) == 0;
    if (known) {
      const std::vector<std::string> columns = SplitCsvLine(line);
      size_t next = 0;
      for (size_t c = 7; c < columns.size() && known; ++c) {
        while (next < std::size(kShotsOptional) && columns[c] != kShotsOptional[next]) ++next;
        known = next < std::size(kShotsOptional);
        ++next;
      }
    }
    if (!known || (!header.empty() && line != header)) {
      throw std::runtime_error("MergeShards: unexpected header in " + t.shots);
    }
    header = line;
    const size_t columns = SplitCsvLine(line).size();
    while (std::getline(in, line)) {
      if (line.empty()) continue;
      std::vector<std::string> cells = SplitCsvLine(line);
      // getline drops a last empty cell: "...,p3," has one cell fewer.
      if (cells.size() + 1 == columns && line.back() == ',') cells.emplace_back();
      if (cells.size() != columns) {
        throw std::runtime_error("MergeShards: bad row in " + t.shots + ": " + line);
      }
      const int index = std::stoi(cells[0]);
      if (shot_rows.count(index) != 0) {
        throw std::runtime_error("MergeShards: shot index " + cells[0] + " appears in two shards");
      }
      shot_rows[index] = line;
      index_of_shot[cells[1]] = index;
      if (!fs::equivalent(t.dir, out_dir)) {
        fs::copy_file(fs::path(t.dir) / cells[6], fs::path(out_dir) / cells[6],
                      fs::copy_options::overwrite_existing);
      }
    }
    std::ifstream ex(t.exact);
    std::getline(ex, line);
    if (line != kExactHeader)
      throw std::runtime_error("MergeShards: unexpected header in " + t.exact);
    while (std::getline(ex, line)) {
      if (line.empty()) continue;
      const std::vector<std::string> cells = SplitCsvLine(line);
      const auto it = cells.size() > 4 ? index_of_shot.find(cells[4]) : index_of_shot.end();
      if (it == index_of_shot.end()) {
        throw std::runtime_error("MergeShards: row of unknown shot in " + t.exact + ": " + line);
      }
      exact_rows[it->second].push_back(line);
    }
  }
  std::ostringstream st, ex;
  st << (header.empty() ? kShotsHeader : header.c_str()) << "\n";
  ex << kExactHeader << "\n";
  for (const auto& [index, row] : shot_rows) st << row << "\n";
  for (const auto& [index, rows] : exact_rows) {
    for (const std::string& row : rows) ex << row << "\n";
  }
  WriteFileAtomic((fs::path(out_dir) / "shots.csv").string(), st.str());
  WriteFileAtomic((fs::path(out_dir) / "exact.csv").string(), ex.str());
}

DetectShotsResult DetectShots(const TargetScene& scene, const std::vector<Shot>& shots,
                              const std::string& image_dir, const DetectShotsOptions& options) {
  if (const std::string m = options.Check(); !m.empty()) {
    throw std::invalid_argument("DetectShotsOptions: " + m);
  }
  if (const std::string m = CheckShots(shots); !m.empty())
    throw std::invalid_argument("shots: " + m);
  detect::DetectorOptions dopt = options.detector;
  dopt.families.clear();
  bool point_boards = false;
  for (const TagBoard& b : scene.boards) {
    point_boards = point_boards || b.IsPointBoard();
    if (b.IsPointBoard()) continue;  // OpenCV's detectors (detect/point_boards.h)
    const detect::PrintedFamily printed{b.family, b.border_bits};
    if (std::find(dopt.families.begin(), dopt.families.end(), printed) == dopt.families.end()) {
      dopt.families.push_back(printed);
    }
  }
  // A scene of point boards alone needs no AprilTag detector.
  const bool tags = !dopt.families.empty() || !point_boards;
  if (dopt.families.empty()) dopt.families = options.detector.families;

  const int n = static_cast<int>(shots.size());
  std::vector<std::vector<PixelObservation>> per_shot(n);
  DetectShotsResult result;
  result.stats.resize(n);
  std::atomic<int> next{0}, done{0};
  std::mutex mutex;
  std::string error;
  Progress progress("detect", n, options.progress);
  auto work = [&]() {
    try {
      std::unique_ptr<detect::TagDetector> detector;
      if (tags) detector = std::make_unique<detect::TagDetector>(dopt);
      for (int i = next++; i < n; i = next++) {
        {
          std::lock_guard<std::mutex> lock(mutex);
          if (!error.empty()) return;
        }
        const Shot& s = shots[i];
        const std::string path = (fs::path(image_dir) / ImageName(s)).string();
        const cv::Mat img = cv::imread(path, cv::IMREAD_GRAYSCALE);
        if (img.empty()) throw std::runtime_error("DetectShots: cannot read image " + path);
        if (img.cols != s.cam.width || img.rows != s.cam.height) {
          throw std::runtime_error("DetectShots: " + path + " is " + std::to_string(img.cols) +
                                   "x" + std::to_string(img.rows) + ", the shot's camera " +
                                   std::to_string(s.cam.width) + "x" +
                                   std::to_string(s.cam.height));
        }
        std::vector<detect::TagDetection> dets;
        if (detector) dets = detector->Detect(img);
        // Inner corners of ChArUco and chessboards as detections of their
        // board's family, all four corners the point (tag_matching.h).
        for (const TagBoard& b : scene.boards) {
          if (!b.IsPointBoard()) continue;
          for (const auto& [k, uv] : detect::DetectPointBoard(img, b, s.face).corners) {
            detect::TagDetection d;
            d.family = b.family;
            d.id = b.first_id + k;
            d.corners = {uv, uv, uv, uv};
            d.apriltag_corners = d.corners;
            d.refinement = detect::CornerRefinement::kSaddle;
            dets.push_back(d);
          }
        }
        const std::vector<ExpectedTag> expected =
            ExpectTags(scene, s.ref_from_cam, s.cam, options.visibility);
        ShotStats& stats = result.stats[i];
        stats.shot = s.id;
        std::vector<detect::DetectedTag> kept;
        for (const MatchedTag& m : MatchDetections(dets, expected, options.match, &stats)) {
          detect::DetectedTag tag;
          tag.board = BoardIndexOf(scene, m.id);
          tag.id = m.id;
          tag.uv = m.uv;
          kept.push_back(tag);
        }
        PhotoShot photo;
        photo.face = s.face;
        photo.zoom = s.zoom;
        photo.phi = s.phi;
        photo.theta = s.theta;
        photo.shot = s.id;
        photo.focus_distance = s.focus_distance;
        detect::AppendPixelObservations(photo, scene, kept, &per_shot[i]);
        const int d = ++done;
        std::lock_guard<std::mutex> lock(mutex);
        progress.Update(d);
      }
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> lock(mutex);
      if (error.empty()) error = e.what();
    }
  };
  const int threads = std::min(options.jobs, std::max(1, n));
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
  if (!error.empty()) throw std::runtime_error(error);
  for (int i = 0; i < n; ++i) {
    result.pixels.insert(result.pixels.end(), per_shot[i].begin(), per_shot[i].end());
    result.total.Add(result.stats[i]);
  }
  result.total.shot = "total";
  return result;
}

}  // namespace rtscalib::render

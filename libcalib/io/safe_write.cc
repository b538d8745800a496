#include "libcalib/io/safe_write.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace rtscalib {
namespace {

std::string TmpPath(const std::string& path) { return path + ".tmp"; }

// Closes a descriptor once; the destructor is only for paths that already
// throw (its result cannot matter then).
class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  int get() const { return fd_; }
  // Returns 0 or errno.
  int Close() {
    const int fd = fd_;
    fd_ = -1;
    return ::close(fd) == 0 ? 0 : errno;
  }

 private:
  int fd_;
};

[[noreturn]] void Fail(const std::string& path, const std::string& tmp, const std::string& reason) {
  if (!tmp.empty()) ::unlink(tmp.c_str());
  throw WriteError(path, reason);
}

// fsync and close of a file that `tmp` names; then its rename (or, for kKeep,
// its hard link) onto `path`. The tmp file is removed on every failure.
void SyncAndCommit(const std::string& path, const std::string& tmp, Existing existing) {
  Fd fd(::open(tmp.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW));
  if (fd.get() < 0) Fail(path, tmp, ErrnoText(errno) + " (opening " + tmp + ")");
  // A full disk or an I/O error may only show at fsync (delayed allocation).
  if (::fsync(fd.get()) != 0) Fail(path, tmp, ErrnoText(errno) + " (fsync)");
  if (const int err = fd.Close()) Fail(path, tmp, ErrnoText(err) + " (close)");
  if (existing == Existing::kKeep) {
    // link() fails with EEXIST instead of replacing, atomically.
    if (::link(tmp.c_str(), path.c_str()) != 0) {
      const int err = errno;
      Fail(path, tmp,
           err == EEXIST ? std::string("it exists and rtscalib does not replace files it did "
                                       "not write")
                         : ErrnoText(err));
    }
    ::unlink(tmp.c_str());
  } else if (::rename(tmp.c_str(), path.c_str()) != 0) {
    Fail(path, tmp, ErrnoText(errno) + " (rename from " + tmp + ")");
  }
}

}  // namespace

WriteError::WriteError(const std::string& path_in, const std::string& reason_in)
    : std::runtime_error("cannot write '" + path_in + "': " + reason_in),
      path(path_in),
      reason(reason_in) {}

std::string ErrnoText(int err) { return err ? std::strerror(err) : "no OS error reported"; }

void WriteFileAtomic(const std::string& path, std::string_view bytes, Existing existing) {
  const std::string tmp = TmpPath(path);
  // O_NOFOLLOW: a symlink at the tmp name is never followed out of the folder.
  Fd fd(::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC | O_NOFOLLOW, 0644));
  if (fd.get() < 0) Fail(path, "", ErrnoText(errno) + " (creating " + tmp + ")");
  const char* p = bytes.data();
  size_t left = bytes.size();
  while (left > 0) {
    const ssize_t n = ::write(fd.get(), p, left);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int err = errno;
      Fail(path, tmp,
           ErrnoText(err) + " (after " + std::to_string(bytes.size() - left) + " of " +
               std::to_string(bytes.size()) + " bytes)");
    }
    p += n;
    left -= static_cast<size_t>(n);
  }
  if (::fsync(fd.get()) != 0) Fail(path, tmp, ErrnoText(errno) + " (fsync)");
  if (const int err = fd.Close()) Fail(path, tmp, ErrnoText(err) + " (close)");
  // The data is on disk; SyncAndCommit's second fsync is cheap.
  SyncAndCommit(path, tmp, existing);
}

void WriteFileAtomicWith(const std::string& path,
                         const std::function<void(const std::string& tmp_path)>& write,
                         Existing existing) {
  const std::string tmp = TmpPath(path);
  errno = 0;
  try {
    write(tmp);
  } catch (const std::exception& e) {
    // The writer's message rarely carries the reason; errno still holds the
    // failed write's or close's error, read before anything else can set it.
    const int err = errno;
    Fail(path, tmp, std::string(e.what()) + (err ? std::string(": ") + ErrnoText(err) : ""));
  }
  SyncAndCommit(path, tmp, existing);
}

void SyncFolder(const std::string& folder) {
  Fd fd(::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (fd.get() < 0) throw WriteError(folder, ErrnoText(errno) + " (opening the folder)");
  if (::fsync(fd.get()) != 0) throw WriteError(folder, ErrnoText(errno) + " (fsync)");
  if (const int err = fd.Close()) throw WriteError(folder, ErrnoText(err) + " (close)");
}

}  // namespace rtscalib

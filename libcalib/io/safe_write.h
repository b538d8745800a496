// The one way rtscalib writes a file (app/, render/ and io's own writers): the bytes go to `<path>.tmp`, every step is
// checked (write, fsync, close), and only a complete file is renamed onto
// `path`. A reader therefore sees either the old file or the whole new one,
// never a file cut short by a full disk or a kill; a failure throws WriteError
// naming the file and the operating system's reason, and removes the partial
// `<path>.tmp`.
#pragma once

#include <functional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace rtscalib {

// A file could not be written: `path` is the file the caller asked for,
// `reason` the OS's text (strerror) or the writer's own message.
struct WriteError : std::runtime_error {
  WriteError(const std::string& path, const std::string& reason);
  std::string path;
  std::string reason;
};

// What to do when `path` already exists.
enum class Existing {
  kReplace,  // rename over it (the caller knows the file is its own)
  kKeep,     // never replace it: throw WriteError (the file belongs to the user)
};

// Writes `bytes` to `path` through `<path>.tmp`. Throws WriteError.
void WriteFileAtomic(const std::string& path, std::string_view bytes,
                     Existing existing = Existing::kReplace);

// For writers that only take a path (libcalib's WriteModelYaml, WriteRecords):
// `write(tmp_path)` writes the whole file to `tmp_path`; this then checks it
// (fsync, close) and renames it onto `path`. An exception from `write` becomes
// a WriteError naming `path` with the writer's message and errno's text.
void WriteFileAtomicWith(const std::string& path,
                         const std::function<void(const std::string& tmp_path)>& write,
                         Existing existing = Existing::kReplace);

// fsync of a folder, so that a rename inside it survives a crash. Throws
// WriteError.
void SyncFolder(const std::string& folder);

// "<what>: <strerror(err)>" for messages.
std::string ErrnoText(int err);

}  // namespace rtscalib

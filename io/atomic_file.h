// AtomicFile: all-or-nothing file output. Bytes go to a temporary file next
// to the destination (same directory, so the final rename stays on one file
// system and is atomic); commit() flushes, fsyncs and renames it into place.
// If the object dies uncommitted (an exception midway, an early return) the
// temporary is removed and any previous file at the destination is untouched.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>

namespace atelier {

class AtomicFile {
 public:
  /// Creates `path.tmp.<pid>.<n>` (first free n). Throws Error(kIo) when the
  /// directory does not exist or is not writable.
  explicit AtomicFile(std::filesystem::path path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  /// Buffered writes; throw Error(kIo) on a failed system call.
  void write(std::string_view bytes);
  void write(const void* data, std::size_t n) { write(std::string_view(static_cast<const char*>(data), n)); }

  /// Flushes, fsyncs, closes and renames onto the destination, then fsyncs
  /// the directory so the rename itself is durable. Throws Error(kIo).
  void commit();

  [[nodiscard]] const std::filesystem::path& path() const noexcept { return path_; }
  [[nodiscard]] const std::filesystem::path& temp_path() const noexcept { return temp_; }
  [[nodiscard]] bool committed() const noexcept { return committed_; }

 private:
  void flush();
  [[noreturn]] void fail(const std::string& what, int err) const;

  std::filesystem::path path_;
  std::filesystem::path temp_;
  std::string buffer_;
  int fd_ = -1;
  bool committed_ = false;
};

/// Runs `produce` on an AtomicFile for `path` and commits it; if `produce`
/// throws, the exception propagates and nothing is left at `path` but what
/// was there before.
void write_atomically(const std::filesystem::path& path, const std::function<void(AtomicFile&)>& produce);

/// Removes the temporaries `<name>.tmp.<pid>.<n>` in `dir` (not recursive)
/// that a writer killed before commit() left behind: those whose <pid> is no
/// running process (kill(pid, 0) fails with ESRCH). A temporary of a live
/// process (this one, or another run writing into the same folder) is kept;
/// a pid reused by an unrelated process keeps its file until a later call.
/// Reads and writes: the directory's entries. Returns the number removed;
/// entries that cannot be read or removed are skipped (never throws).
std::size_t remove_stale_temporaries(const std::filesystem::path& dir) noexcept;

}  // namespace atelier

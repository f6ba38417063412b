#include <atelier/io/atomic_file.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstring>
#include <limits>
#include <system_error>

#include <atelier/engine/status.h>

namespace atelier {

namespace {
constexpr std::size_t kBufferSize = std::size_t{1} << 16;
}

AtomicFile::AtomicFile(std::filesystem::path path) : path_(std::move(path)) {
  const std::string base = path_.string() + ".tmp." + std::to_string(::getpid()) + ".";
  // O_EXCL picks the first free name: no shared counter, and two writers in
  // one process never share a temporary.
  for (unsigned n = 0;; ++n) {
    temp_ = base + std::to_string(n);
    fd_ = ::open(temp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd_ >= 0) break;
    if (errno != EEXIST || n > 1000) {
      const int err = errno;
      temp_.clear();
      fail("cannot create a temporary file", err);
    }
  }
  buffer_.reserve(kBufferSize);
}

AtomicFile::~AtomicFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!committed_ && !temp_.empty()) ::unlink(temp_.c_str());
}

void AtomicFile::fail(const std::string& what, int err) const {
  throw Error(Status(ErrorCode::kIo, path_.string() + ": " + what + ": " + std::strerror(err)));
}

void AtomicFile::write(std::string_view bytes) {
  if (fd_ < 0) throw Error(Status(ErrorCode::kIo, path_.string() + ": write after commit"));
  if (buffer_.size() + bytes.size() > kBufferSize) flush();
  if (bytes.size() >= kBufferSize) {
    buffer_.assign(bytes);
    flush();
  } else {
    buffer_.append(bytes);
  }
}

void AtomicFile::flush() {
  const char* p = buffer_.data();
  std::size_t left = buffer_.size();
  while (left > 0) {
    const ssize_t w = ::write(fd_, p, left);
    if (w < 0) {
      if (errno == EINTR) continue;
      fail("write failed", errno);
    }
    p += w;
    left -= static_cast<std::size_t>(w);
  }
  buffer_.clear();
}

void AtomicFile::commit() {
  if (committed_) return;
  flush();
  if (::fsync(fd_) != 0) fail("fsync failed", errno);
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0) fail("close failed", errno);
  if (::rename(temp_.c_str(), path_.c_str()) != 0) fail("cannot rename the temporary file into place", errno);
  committed_ = true;
  // Durability of the rename: fsync the directory (best effort; some file
  // systems refuse O_RDONLY fsync on directories).
  std::filesystem::path dir = path_.parent_path();
  if (dir.empty()) dir = ".";
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    (void)::fsync(dfd);
    ::close(dfd);
  }
}

void write_atomically(const std::filesystem::path& path, const std::function<void(AtomicFile&)>& produce) {
  AtomicFile f(path);
  produce(f);
  f.commit();
}

namespace {

/// The writer's pid of a name `<dest>.tmp.<pid>.<n>`, or 0 when the name is
/// not one of AtomicFile's temporaries.
pid_t temporary_writer(const std::string& name) {
  const std::size_t dot_n = name.rfind('.');
  if (dot_n == std::string::npos || dot_n + 1 == name.size()) return 0;
  const std::size_t dot_pid = name.rfind('.', dot_n - 1);
  if (dot_pid == std::string::npos || dot_pid < 4 || name.compare(dot_pid - 4, 4, ".tmp") != 0) return 0;
  auto all_digits = [&](std::size_t b, std::size_t e) {
    if (b >= e) return false;
    for (std::size_t i = b; i < e; ++i)
      if (name[i] < '0' || name[i] > '9') return false;
    return true;
  };
  if (!all_digits(dot_n + 1, name.size()) || !all_digits(dot_pid + 1, dot_n)) return 0;
  long pid = 0;
  const auto [p, ec] = std::from_chars(name.data() + dot_pid + 1, name.data() + dot_n, pid);
  if (ec != std::errc() || pid <= 0 || pid > std::numeric_limits<pid_t>::max()) return 0;
  return static_cast<pid_t>(pid);
}

}  // namespace

std::size_t remove_stale_temporaries(const std::filesystem::path& dir) noexcept {
  std::size_t removed = 0;
  std::error_code ec;
  std::filesystem::directory_iterator it(dir, ec), end;
  for (; !ec && it != end; it.increment(ec)) {
    std::error_code e2;
    if (!it->is_regular_file(e2)) continue;
    const pid_t pid = temporary_writer(it->path().filename().string());
    if (pid == 0 || pid == ::getpid()) continue;
    // ESRCH: no such process, so nobody will commit or remove this file.
    // EPERM means a live process of another user: keep it.
    if (::kill(pid, 0) == 0 || errno != ESRCH) continue;
    removed += std::filesystem::remove(it->path(), e2) ? 1 : 0;
  }
  return removed;
}

}  // namespace atelier

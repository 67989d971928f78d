#include "state_dir.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <utility>

#include "outfile.hpp"

namespace dpc31::serve {

namespace {

constexpr std::size_t kMaxComponent = 255;  // NAME_MAX

bool is_blank(char c) { return c == ' ' || c == '\t'; }

std::string errno_text(int e) { return std::strerror(e); }

StateDir::Error denied(std::string message) {
  return {StateDir::Error::Kind::denied, std::move(message)};
}
StateDir::Error failed(std::string message) {
  return {StateDir::Error::Kind::failed, std::move(message)};
}

// What is at `comp` in `dirfd`, for a message: never follows it.
StateDir::Error classify(int dirfd, const std::string& comp, std::string_view name, int open_errno,
                         bool want_dir) {
  struct stat st {};
  if (::fstatat(dirfd, comp.c_str(), &st, AT_SYMLINK_NOFOLLOW) != 0) {
    if (errno == ENOENT)
      return failed(fmt::format("{}: no such file in the state directory", name));
    return failed(fmt::format("{}: cannot open: {}", name, errno_text(errno)));
  }
  if (S_ISLNK(st.st_mode)) {
    return denied(fmt::format("{}: {} is a symbolic link (links are not followed)", name, comp));
  }
  if (want_dir && !S_ISDIR(st.st_mode)) {
    return failed(fmt::format("{}: {} is not a directory", name, comp));
  }
  if (!want_dir && !S_ISREG(st.st_mode)) {
    return denied(fmt::format("{}: not a regular file", name));
  }
  return failed(fmt::format("{}: cannot open: {}", name, errno_text(open_errno)));
}

}  // namespace

StateDir::StateDir(const std::string& dir) {
  fd_ = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd_ < 0) {
    throw std::runtime_error(fmt::format("--state-dir {}: {}", dir, errno_text(errno)));
  }
}

StateDir::~StateDir() {
  if (fd_ >= 0) ::close(fd_);
}

StateDir::StateDir(StateDir&& o) noexcept : fd_(std::exchange(o.fd_, -1)) {}

StateDir& StateDir::operator=(StateDir&& o) noexcept {
  if (this != &o) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(o.fd_, -1);
  }
  return *this;
}

std::string StateDir::check_name(std::string_view name) {
  if (name.empty()) return "empty name";
  if (name.front() == '/') {
    return fmt::format(
        "{}: absolute names are not allowed (names are relative to the state "
        "directory)",
        name);
  }
  std::size_t b = 0;
  for (;;) {
    const std::size_t e = name.find('/', b);
    const std::string_view comp = name.substr(b, e == std::string_view::npos ? e : e - b);
    if (comp.empty()) return fmt::format("{}: empty path component", name);
    if (comp == "." || comp == "..") {
      return fmt::format("{}: '{}' is not allowed (names stay inside the state directory)", name,
                         comp);
    }
    if (comp.starts_with(outfile::kTempPrefix)) {
      // The server's own temporaries: a client that took all their names would stop every save.
      return fmt::format("{}: a name starting with '{}' is the server's temporary", name,
                         outfile::kTempPrefix);
    }
    if (is_blank(comp.front()) || is_blank(comp.back())) {
      // Invisible in a listing: `save a ` would be a second `a` (or, trimmed, overwrite it).
      return fmt::format("{}: a component may not begin or end with a blank", name);
    }
    if (comp.size() > kMaxComponent) {
      return fmt::format("{}: a component longer than {} bytes", name, kMaxComponent);
    }
    if (e == std::string_view::npos) return {};
    b = e + 1;
  }
}

int StateDir::parent_of(std::string_view name, std::string& leaf, bool& owned, Error& error) const {
  owned = false;
  if (fd_ < 0) {
    error = denied("file commands are disabled: the server was started without --state-dir");
    return -1;
  }
  if (std::string why = check_name(name); !why.empty()) {
    error = denied(std::move(why));
    return -1;
  }
  int dir = fd_;
  std::size_t b = 0;
  for (;;) {
    const std::size_t e = name.find('/', b);
    if (e == std::string_view::npos) {
      leaf = std::string(name.substr(b));
      return dir;
    }
    const std::string comp(name.substr(b, e - b));
    const int next = ::openat(dir, comp.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
    const int open_errno = errno;
    if (next < 0) error = classify(dir, comp, name, open_errno, true);
    if (owned) ::close(dir);
    if (next < 0) return -1;
    dir = next;
    owned = true;
    b = e + 1;
  }
}

bool StateDir::read(std::string_view name, std::size_t max, std::vector<std::uint8_t>& bytes,
                    Error& error) const {
  std::string leaf;
  bool owned = false;
  const int dir = parent_of(name, leaf, owned, error);
  if (dir < 0) return false;
  struct Closer {
    int fd;
    bool owned;
    ~Closer() {
      if (owned) ::close(fd);
    }
  } closer{dir, owned};
  // Looked at before it is opened: opening a device can have effects of its own.
  struct stat st {};
  if (::fstatat(dir, leaf.c_str(), &st, AT_SYMLINK_NOFOLLOW) != 0 || !S_ISREG(st.st_mode)) {
    error = classify(dir, leaf, name, errno, false);
    return false;
  }
  // O_NONBLOCK: should it have become a FIFO since, opening it does not wait for a writer.
  const int fd =
      ::openat(dir, leaf.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
  if (fd < 0) {
    error = classify(dir, leaf, name, errno, false);
    return false;
  }
  struct FdCloser {
    int fd;
    ~FdCloser() { ::close(fd); }
  } fd_closer{fd};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    error = denied(fmt::format("{}: not a regular file", name));
    return false;
  }
  if (static_cast<std::uint64_t>(st.st_size) > max) {
    error = failed(fmt::format("{}: larger than {} bytes", name, max));
    return false;
  }
  bytes.assign(static_cast<std::size_t>(st.st_size), 0);
  std::size_t got = 0;
  for (;;) {
    if (got == bytes.size()) {
      if (bytes.size() > max) {
        error = failed(fmt::format("{}: larger than {} bytes", name, max));
        return false;
      }
      bytes.resize(std::min(max + 1, bytes.size() + 4096));  // it grew since the fstat
    }
    const ssize_t n = ::read(fd, bytes.data() + got, bytes.size() - got);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      error = failed(fmt::format("{}: cannot read: {}", name, errno_text(errno)));
      return false;
    }
    if (n == 0) break;
    got += static_cast<std::size_t>(n);
  }
  bytes.resize(got);
  return true;
}

void StateDir::usage(int dir, int depth, std::size_t& files, std::uint64_t& bytes) const {
  const int fd = ::openat(dir, ".", O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  DIR* d = ::fdopendir(fd);
  if (d == nullptr) {
    ::close(fd);
    return;
  }
  while (const dirent* e = ::readdir(d)) {
    if (files > quota_.files + 1) break;  // refused even if one of them is replaced
    const std::string_view n = e->d_name;
    if (n == "." || n == "..") continue;
    struct stat st {};
    if (::fstatat(fd, e->d_name, &st, AT_SYMLINK_NOFOLLOW) != 0) continue;
    if (S_ISREG(st.st_mode)) {
      ++files;
      bytes += static_cast<std::uint64_t>(st.st_size);
    } else if (S_ISDIR(st.st_mode) && depth < kMaxDepth) {
      const int sub = ::openat(fd, e->d_name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
      if (sub >= 0) {
        usage(sub, depth + 1, files, bytes);
        ::close(sub);
      }
    }
  }
  ::closedir(d);
}

bool StateDir::write(std::string_view name, std::span<const std::uint8_t> bytes,
                     Error& error) const {
  std::string leaf;
  bool owned = false;
  const int dir = parent_of(name, leaf, owned, error);
  if (dir < 0) return false;
  struct stat st {};
  const bool exists = ::fstatat(dir, leaf.c_str(), &st, AT_SYMLINK_NOFOLLOW) == 0;
  if (exists && !S_ISREG(st.st_mode)) {
    error = classify(dir, leaf, name, 0, false);  // a link, a FIFO, a device: left alone
    if (owned) ::close(dir);
    return false;
  }
  std::size_t files = 0;
  std::uint64_t used = 0;
  usage(fd_, 0, files, used);
  if (exists) {
    --files;
    used -= std::min<std::uint64_t>(used, static_cast<std::uint64_t>(st.st_size));
  }
  if (files + 1 > quota_.files || used + bytes.size() > quota_.bytes) {
    error = failed(fmt::format(
        "{}: the state directory is full (at most {} files and {} MiB; it holds {} files, {} "
        "bytes): delete snapshots or save over an old one",
        name, quota_.files, quota_.bytes >> 20, files, used));
    if (owned) ::close(dir);
    return false;
  }
  std::string why;
  const bool ok =
      outfile::write_file_at(dir, leaf, {reinterpret_cast<const char*>(bytes.data()), bytes.size()},
                             std::string(name), why);
  if (owned) ::close(dir);
  if (!ok) error = failed(std::move(why));
  return ok;
}

}  // namespace dpc31::serve

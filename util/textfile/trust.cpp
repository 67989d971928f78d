#include "trust.hpp"

#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdint>
#include <system_error>

namespace dpc31 {

namespace {

bool ours(uid_t uid) { return uid == 0 || uid == ::geteuid(); }

constexpr mode_t kOthersWrite = S_IWGRP | S_IWOTH;

// The real path of what `fd` holds, or "".
std::string real_path(int fd) {
  std::array<char, 4096> buf{};
  const ssize_t n =
      ::readlink(fmt::format("/proc/self/fd/{}", fd).c_str(), buf.data(), buf.size() - 1);
  if (n <= 0 || buf[0] != '/') return {};
  return std::string(buf.data(), static_cast<std::size_t>(n));
}

std::string owner_problem(const std::string& what, const struct stat& st) {
  if (!ours(st.st_uid)) {
    return fmt::format("{} is owned by uid {}, not by you (uid {}) or root", what, st.st_uid,
                       ::geteuid());
  }
  return {};
}

// Who may write besides the owner, as the mode says: others (whatever the group may), or its
// group alone.
const char* writers(mode_t mode) { return (mode & S_IWOTH) != 0 ? "others" : "its group"; }

// Every directory above `real` (an absolute path without links), the closest first: owned by us
// or root, and writable by others only when sticky and the name below it is ours. `below` is the
// status of what `real` names.
std::string chain_problem(const std::string& real, struct stat below) {
  std::string path = real;
  while (path.size() > 1) {
    const std::size_t slash = path.find_last_of('/');
    path = slash == 0 ? std::string("/") : path.substr(0, slash);
    struct stat st {};
    if (::lstat(path.c_str(), &st) != 0) {
      return fmt::format("cannot check the directory {}: {}", path,
                         std::error_code(errno, std::generic_category()).message());
    }
    if (std::string p = owner_problem("the directory " + path, st); !p.empty()) return p;
    if ((st.st_mode & kOthersWrite) != 0 && !((st.st_mode & S_ISVTX) != 0 && ours(below.st_uid))) {
      return fmt::format("the directory {} is writable by {} (mode {:04o})", path,
                         writers(st.st_mode), st.st_mode & 07777);
    }
    below = st;
  }
  return {};
}

enum class Kind : std::uint8_t { file, directory, input };

std::string checked(int fd, const std::string& shown, Kind kind) {
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    return fmt::format("{}: cannot check it: {}", shown,
                       std::error_code(errno, std::generic_category()).message());
  }
  if (kind == Kind::input) {
    if (real_path(fd).empty()) return {};  // an anonymous pipe: "pipe:[N]", the piper's own
  } else if (kind == Kind::directory ? !S_ISDIR(st.st_mode) : !S_ISREG(st.st_mode)) {
    return fmt::format("{} is not a {}", shown,
                       kind == Kind::directory ? "directory" : "regular file");
  }
  if (std::string p = owner_problem(shown, st); !p.empty()) return p;
  if ((st.st_mode & kOthersWrite) != 0) {
    return fmt::format("{} is writable by {} (mode {:04o})", shown, writers(st.st_mode),
                       st.st_mode & 07777);
  }
  const std::string real = real_path(fd);
  if (real.empty()) return fmt::format("{}: cannot find its real path in /proc/self/fd", shown);
  std::string p = chain_problem(real, st);
  return p.empty() ? p : fmt::format("{}: {}", shown, p);
}

}  // namespace

std::string untrusted_code(int fd, const std::string& shown) {
  return checked(fd, shown, Kind::file);
}

std::string untrusted_directory(int fd, const std::string& shown) {
  return checked(fd, shown, Kind::directory);
}

std::string untrusted_input(int fd, const std::string& shown) {
  return checked(fd, shown, Kind::input);
}

}  // namespace dpc31

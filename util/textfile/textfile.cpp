#include "textfile.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>

namespace dpc31 {

namespace {

// "an Intel HEX", "a trace": by the first letter.
std::string_view article(std::string_view what) {
  return !what.empty() && std::string_view("AEIOUaeiou").find(what[0]) != std::string_view::npos
             ? "an"
             : "a";
}

// A pipe (bash's <(...), `| ... /dev/stdin`) lives on the kernel's pipe file system, a named FIFO
// in a directory: only the FIFO's open() waits for a writer.
bool anonymous_pipe(const struct stat& st) {
  if (!S_ISFIFO(st.st_mode)) return false;
  int ends[2];
  if (::pipe2(ends, O_CLOEXEC) != 0) return false;
  struct stat ours {};
  const bool same = ::fstat(ends[0], &ours) == 0 && ours.st_dev == st.st_dev;
  ::close(ends[0]);
  ::close(ends[1]);
  return same;
}

}  // namespace

bool read_text_file(const std::string& path, std::size_t max_bytes, std::string_view what,
                    std::string& text, std::string& error) {
  // Opened once (a pipe can be read only once), without waiting: a named FIFO's open() would
  // wait for a writer (the run hung). What was opened is judged by its descriptor, so nothing
  // renamed in at the path meanwhile gets past: a FIFO or a device (/dev/zero fills the cap) is
  // refused, a pipe is read as a file is, then in blocking reads.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) {
    error = errno == ENOENT ? "no such file" : "cannot open the file";
    return false;
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0 || ::fcntl(fd, F_SETFL, O_RDONLY) != 0) {
    ::close(fd);
    error = "cannot open the file";
    return false;
  }
  if (!S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode) && !anonymous_pipe(st)) {
    ::close(fd);
    error = fmt::format("not a regular file, not {} {} file", article(what), what);
    return false;
  }
  // Read in pieces: memory follows what the file holds, not the cap (a cap of 256 MiB is not
  // allocated for /dev/null).
  const bool read = read_text_fd(fd, max_bytes, what, text, error);
  ::close(fd);
  return read;
}

bool read_text_fd(int fd, std::size_t max_bytes, std::string_view what, std::string& text,
                  std::string& error) {
  struct stat st {};
  if (::fstat(fd, &st) == 0 && S_ISDIR(st.st_mode)) {
    error = fmt::format("is a directory, not {} {} file", article(what), what);
    return false;
  }
  constexpr std::size_t kPiece = 64 * 1024;
  text.clear();
  for (;;) {
    const std::size_t have = text.size();
    const std::size_t want = std::min(kPiece, max_bytes + 1 - have);
    text.resize(have + want);
    const ssize_t n = ::read(fd, text.data() + have, want);
    if (n < 0 && errno == EINTR) {
      text.resize(have);
      continue;
    }
    text.resize(have + static_cast<std::size_t>(std::max<ssize_t>(n, 0)));
    if (n < 0) {
      error = "cannot read the file";
      return false;
    }
    if (n == 0 || text.size() > max_bytes) break;
  }
  if (text.size() > max_bytes) {
    error = fmt::format("too large for {} {} (more than {} bytes)", article(what), what, max_bytes);
    return false;
  }
  text.shrink_to_fit();
  return true;
}

int cut_off_line(std::string_view text, std::string& error) {
  if (text.empty() || text.back() == '\n') return 0;
  error = "truncated: the last line has no end of line";
  return static_cast<int>(std::count(text.begin(), text.end(), '\n')) + 1;
}

std::string not_text(unsigned char c) {
  return c == 0 ? "a NUL byte: not a text file"
                : fmt::format("a control byte \\x{:02X}: not a text file", c);
}

namespace {

// `s` with each byte below 0x20, DEL and (unless `keep_high`) each byte from 0x80 as \xHH.
std::string escaped(std::string_view s, std::size_t max_chars, bool keep_high) {
  std::string out;
  for (std::size_t i = 0; i < s.size() && i < max_chars; ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    if ((c >= 0x20 && c < 0x7F) || (keep_high && c >= 0x80)) {
      out += static_cast<char>(c);
    } else {
      out += fmt::format("\\x{:02X}", c);
    }
  }
  if (s.size() > max_chars) out += "...";
  return out;
}

}  // namespace

std::string shown(std::string_view s, std::size_t max_chars) {
  return escaped(s, max_chars, false);
}

std::string shown_line(std::string_view line) { return escaped(line, kWhole, true); }

}  // namespace dpc31

#include "textfile.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

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

// True with `error` set if `fd` is a directory.
bool directory(int fd, std::string_view what, std::string& error) {
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISDIR(st.st_mode)) return false;
  error = fmt::format("is a directory, not {} {} file", article(what), what);
  return true;
}

constexpr std::size_t kPiece = 64 * 1024;

}  // namespace

int open_text_file(const std::string& path, std::string_view what, std::string& error, bool& pipe) {
  // Opened once (a pipe can be read only once), without waiting: a named FIFO's open() would
  // wait for a writer (the run hung). What was opened is judged by its descriptor, so nothing
  // renamed in at the path meanwhile gets past: a FIFO or a device (/dev/zero fills the cap) is
  // refused, a pipe is read as a file is, then in blocking reads.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) {
    error = errno == ENOENT ? "no such file" : "cannot open the file";
    return -1;
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0 || ::fcntl(fd, F_SETFL, O_RDONLY) != 0) {
    ::close(fd);
    error = "cannot open the file";
    return -1;
  }
  pipe = anonymous_pipe(st);
  if (!S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode) && !pipe) {
    ::close(fd);
    error = fmt::format("not a regular file, not {} {} file", article(what), what);
    return -1;
  }
  if (directory(fd, what, error)) {
    ::close(fd);
    return -1;
  }
  return fd;
}

bool read_text_file(const std::string& path, std::size_t max_bytes, std::string_view what,
                    std::string& text, std::string& error) {
  bool pipe = false;
  const int fd = open_text_file(path, what, error, pipe);
  if (fd < 0) return false;
  // Read in pieces: memory follows what the file holds, not the cap (a cap of 256 MiB is not
  // allocated for /dev/null).
  const bool read = read_text_fd(fd, max_bytes, what, text, error);
  ::close(fd);
  return read;
}

bool read_text_fd(int fd, std::size_t max_bytes, std::string_view what, std::string& text,
                  std::string& error) {
  if (directory(fd, what, error)) return false;
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

TextLines::TextLines(int fd, std::uint64_t offset, std::size_t max_text, std::uint64_t max_line,
                     char comment, bool inspect)
    : fd_(fd),
      at_(offset),
      max_text_(max_text),
      max_line_(max_line),
      comment_(comment),
      inspect_(inspect),
      piece_(kPiece) {}

bool TextLines::fill() {
  for (;;) {
    const ssize_t n = ::pread(fd_, piece_.data(), piece_.size(), static_cast<off_t>(at_));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) failed_ = true;
    pos_ = 0;
    end_ = static_cast<std::size_t>(std::max<ssize_t>(n, 0));
    at_ += end_;
    return end_ > 0;
  }
}

bool TextLines::next(Line& line) {
  line = Line{};
  line.offset = at_ - (end_ - pos_);
  text_.clear();
  std::uint64_t length = 0;
  bool comment = false;
  bool copied = false;  // the text is in text_ (it spans pieces)
  for (;;) {
    if (pos_ == end_ && !fill()) {
      // The end of the file (or a failed read): a last line without its newline, if any.
      if (failed_ || length == 0) return false;
      break;
    }
    const char* begin = piece_.data() + pos_;
    const auto* nl = static_cast<const char*>(std::memchr(begin, '\n', end_ - pos_));
    const std::size_t n = nl != nullptr ? static_cast<std::size_t>(nl - begin) : end_ - pos_;
    if (inspect_) {
      for (std::size_t i = 0; i < n; ++i) {
        const auto u = static_cast<unsigned char>(begin[i]);
        line.nul |= u == 0;
        line.control |= (u < 0x20 && u != '\t' && u != '\r') || u == 0x7F;
      }
    }
    length += n;
    line.too_long |= length > max_line_;
    if (!comment && !line.too_long && !line.long_text) {
      const auto* hash = static_cast<const char*>(std::memchr(begin, comment_, n));
      const std::size_t take = hash != nullptr ? static_cast<std::size_t>(hash - begin) : n;
      comment = hash != nullptr;
      line.long_text = text_.size() + take > max_text_;
      if (!line.long_text) {
        if (nl != nullptr && !copied) {
          line.text = std::string_view(begin, take);  // the whole line in this piece
        } else {
          text_.append(begin, take);
          copied = true;
        }
      }
    }
    pos_ += n;
    if (nl != nullptr) {
      ++pos_;
      line.ended = true;
      break;
    }
  }
  if (line.too_long || line.long_text) {
    line.text = {};
  } else if (copied) {
    line.text = text_;
  }
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

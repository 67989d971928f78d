// Common parts of the readers: errors, timescales, reference names, format detection.
#include <fcntl.h>
#include <fmt/format.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <utility>
#include <vector>

#include "wave_reader_impl.hpp"

namespace dpc31::wavediff {

void fail(const std::string& file, std::uint64_t line, const std::string& what) {
  // Garbage quoted from a file must not bring control characters (a CR, escapes) into the line.
  std::string shown;
  for (const char c : what) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7F) {
      shown += fmt::format("\\x{:02X}", u);
    } else {
      shown += c;
    }
  }
  throw InputError(fmt::format("{}:{}: {}", file, line, shown));
}

void Declarations::open_scope(std::string_view name, std::uint64_t line) {
  if (ends_.size() >= kMaxDepth) {
    fail(path_, line, fmt::format("scopes nested deeper than {}", kMaxDepth));
  }
  if (prefix_.size() + name.size() + 1 > kMaxName) {
    fail(path_, line, fmt::format("a scope path longer than {} bytes", kMaxName));
  }
  ends_.push_back(prefix_.size());
  prefix_.append(name);
  prefix_.push_back('.');
}

bool Declarations::close_scope() {
  if (ends_.empty()) return false;
  prefix_.resize(ends_.back());
  ends_.pop_back();
  return true;
}

std::string Declarations::name(std::string_view ref, std::uint64_t line) {
  const std::size_t n = prefix_.size() + ref.size();
  if (n > kMaxName)
    fail(path_, line, fmt::format("a variable's full name longer than {} bytes", kMaxName));
  names_ += n;
  if (names_ > kMaxNames) {
    fail(path_, line,
         fmt::format("the variables' full names exceed {} MiB in all", kMaxNames >> 20));
  }
  std::string full;
  full.reserve(n);
  full.append(prefix_);
  full.append(ref);
  return full;
}

void Declarations::slot(std::uint64_t bits, std::uint64_t line) {
  bits_ += bits;
  if (bits_ > kMaxBits) {
    fail(path_, line, fmt::format("the variables exceed {} Mi bits in all", kMaxBits >> 20));
  }
}

namespace {

struct Unit {
  const char* name;
  int pow;  // of ten femtoseconds
};
constexpr Unit kUnits[] = {{"s", 15}, {"ms", 12}, {"us", 9}, {"ns", 6}, {"ps", 3}, {"fs", 0}};

std::string_view trim(std::string_view s) {
  while (!s.empty() && static_cast<unsigned char>(s.front()) <= ' ') s.remove_prefix(1);
  while (!s.empty() && static_cast<unsigned char>(s.back()) <= ' ') s.remove_suffix(1);
  return s;
}

bool parse_int(std::string_view s, int& v) {
  s = trim(s);
  if (s.empty()) return false;
  auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

}  // namespace

bool parse_timescale(std::string_view text, int& pow) {
  std::string t;
  for (char c : text) {
    if (static_cast<unsigned char>(c) > ' ') t += c;
  }
  std::size_t i = 0;
  while (i < t.size() && t[i] >= '0' && t[i] <= '9') ++i;
  const std::string num = t.substr(0, i);
  const std::string unit = t.substr(i);
  int mult = 0;
  if (num == "1") {
    mult = 0;
  } else if (num == "10") {
    mult = 1;
  } else if (num == "100") {
    mult = 2;
  } else {
    return false;
  }
  for (const Unit& u : kUnits) {
    if (unit == u.name) {
      pow = u.pow + mult;
      return true;
    }
  }
  return false;
}

std::string timescale_text(int pow) {
  for (const Unit& u : kUnits) {
    if (pow >= u.pow && pow <= u.pow + 2) {
      return fmt::format("{}{}", pow == u.pow ? "1" : pow == u.pow + 1 ? "10" : "100", u.name);
    }
  }
  return fmt::format("1e{}fs", pow);
}

void split_reference(std::string_view ref, std::string& name, int& msb, int& lsb) {
  msb = -1;
  lsb = -1;
  std::string_view s = trim(ref);
  if (!s.empty() && s.back() == ']') {
    const std::size_t lb = s.rfind('[');
    if (lb != std::string_view::npos) {
      const std::string_view inner = s.substr(lb + 1, s.size() - lb - 2);
      const std::string_view base = trim(s.substr(0, lb));
      const std::size_t colon = inner.find(':');
      int a = 0;
      int b = 0;
      if (colon != std::string_view::npos && parse_int(inner.substr(0, colon), a) &&
          parse_int(inner.substr(colon + 1), b) && !base.empty()) {
        msb = a;
        lsb = b;
        // A range after a single index ("mem[3] [7:0]"): keep the index, without blanks.
        split_reference(base, name, a, b);
        return;
      }
      if (parse_int(inner, a) && !base.empty()) {
        name = fmt::format("{}[{}]", base, a);
        return;
      }
    }
  } else if (!s.empty() && s.back() == ')') {
    const std::size_t lp = s.rfind('(');
    int a = 0;
    if (lp != std::string_view::npos && lp > 0 &&
        parse_int(s.substr(lp + 1, s.size() - lp - 2), a)) {
      name = fmt::format("{}({})", trim(s.substr(0, lp)), a);
      return;
    }
  }
  name = std::string(s);
}

namespace {

// Closes the descriptor unless released (an error on the way).
struct FdGuard {
  int fd;
  ~FdGuard() {
    if (fd >= 0) ::close(fd);
  }
  int release() { return std::exchange(fd, -1); }
};

}  // namespace

std::unique_ptr<WaveReader> open_wave(const std::string& path) {
  FdGuard in{::open(path.c_str(), O_RDONLY | O_CLOEXEC)};
  if (in.fd < 0) fail(path, 0, fmt::format("cannot open: {}", std::strerror(errno)));
  struct stat st {};
  if (::fstat(in.fd, &st) != 0) fail(path, 0, fmt::format("cannot open: {}", std::strerror(errno)));
  if (S_ISDIR(st.st_mode)) fail(path, 0, "cannot open: is a directory");
  // The first byte tells the format: FST starts with a header block (type 0) or a gzip
  // wrapper block (type 254). A regular file is peeked at; a pipe gives it only once.
  const bool seekable = S_ISREG(st.st_mode);
  unsigned char first = '\n';
  ssize_t n = 0;
  do {
    n = seekable ? ::pread(in.fd, &first, 1, 0) : ::read(in.fd, &first, 1);
  } while (n < 0 && errno == EINTR);
  if (n < 0) fail(path, 0, fmt::format("read error: {}", std::strerror(errno)));
  const bool fst = n == 1 && (first == 0 || first == 254);
  if (!fst) {
    const std::string_view prefix(reinterpret_cast<const char*>(&first),
                                  seekable ? 0 : static_cast<std::size_t>(n));
    return open_vcd(path, in.release(), prefix);
  }
  if (seekable) {
    const int fd = in.release();
    return open_fst(path, fd, fmt::format("/proc/self/fd/{}", fd));
  }
  // fstapi seeks: what the pipe gives goes into an anonymous memory file first, up to a bound
  // (it is memory; /dev/zero would fill it without end). A file is read in place, unbounded.
  constexpr std::uint64_t kMaxPipedFst = std::uint64_t{1} << 30;
  FdGuard mem{::memfd_create("dpc31-wavediff", MFD_CLOEXEC)};
  if (mem.fd < 0) fail(path, 0, fmt::format("cannot buffer the pipe: {}", std::strerror(errno)));
  std::vector<char> buf(1 << 16);
  buf[0] = static_cast<char>(first);
  std::size_t have = 1;
  std::uint64_t total = 0;
  for (;;) {
    total += have;
    if (total > kMaxPipedFst) {
      fail(path, 0,
           fmt::format("an FST from a pipe is held in memory, at most {} GiB: give a larger one "
                       "as a file",
                       kMaxPipedFst >> 30));
    }
    if (::write(mem.fd, buf.data(), have) != static_cast<ssize_t>(have)) {
      fail(path, 0, fmt::format("cannot buffer the pipe: {}", std::strerror(errno)));
    }
    do {
      n = ::read(in.fd, buf.data(), buf.size());
    } while (n < 0 && errno == EINTR);
    if (n < 0) fail(path, 0, fmt::format("read error: {}", std::strerror(errno)));
    if (n == 0) break;
    have = static_cast<std::size_t>(n);
  }
  const int fd = mem.release();
  return open_fst(path, fd, fmt::format("/proc/self/fd/{}", fd));
}

}  // namespace dpc31::wavediff

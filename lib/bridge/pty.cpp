#include "pty.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <stdlib.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <vector>

#include "outfile.hpp"

namespace dpc31::bridge {

namespace {

std::string errno_text(const char* what) { return std::string(what) + ": " + std::strerror(errno); }

bool same_termios(const termios& a, const termios& b) {
  return a.c_iflag == b.c_iflag && a.c_oflag == b.c_oflag && a.c_cflag == b.c_cflag &&
         a.c_lflag == b.c_lflag && cfgetispeed(&a) == cfgetispeed(&b) &&
         cfgetospeed(&a) == cfgetospeed(&b) && std::memcmp(a.c_cc, b.c_cc, sizeof a.c_cc) == 0;
}

}  // namespace

unsigned speed_baud(speed_t s) {
  struct Entry {
    speed_t code;
    unsigned baud;
  };
  static constexpr Entry kSpeeds[] = {
      {B0, 0},
      {B50, 50},
      {B75, 75},
      {B110, 110},
      {B134, 134},
      {B150, 150},
      {B200, 200},
      {B300, 300},
      {B600, 600},
      {B1200, 1200},
      {B1800, 1800},
      {B2400, 2400},
      {B4800, 4800},
      {B9600, 9600},
      {B19200, 19200},
      {B38400, 38400},
      {B57600, 57600},
      {B115200, 115200},
      {B230400, 230400},
      {B460800, 460800},
      {B500000, 500000},
      {B576000, 576000},
      {B921600, 921600},
      {B1000000, 1000000},
      {B1152000, 1152000},
      {B1500000, 1500000},
      {B2000000, 2000000},
      {B2500000, 2500000},
      {B3000000, 3000000},
      {B3500000, 3500000},
      {B4000000, 4000000},
  };
  for (const Entry& e : kSpeeds) {
    if (e.code == s) return e.baud;
  }
  return 0;
}

Pty::Pty() {
  master_ = posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (master_ < 0) throw PtyError(errno_text("posix_openpt"));
  const auto fail = [this](const char* what) {
    const std::string msg = errno_text(what);
    ::close(master_);
    master_ = -1;
    throw PtyError(msg);
  };
  if (grantpt(master_) != 0) fail("grantpt");
  if (unlockpt(master_) != 0) fail("unlockpt");
  std::vector<char> name(256);
  if (ptsname_r(master_, name.data(), name.size()) != 0) fail("ptsname");
  slave_ = name.data();
  const int flags = fcntl(master_, F_GETFL);
  if (flags < 0 || fcntl(master_, F_SETFL, flags | O_NONBLOCK) != 0) fail("fcntl O_NONBLOCK");
  termios t{};
  if (tcgetattr(master_, &t) != 0) fail("tcgetattr");
  cfmakeraw(&t);
  t.c_cflag &= ~static_cast<tcflag_t>(CSIZE | PARENB | CSTOPB | CRTSCTS | HUPCL);
  t.c_cflag |= CS8 | CREAD | CLOCAL;
  t.c_cc[VMIN] = 1;
  t.c_cc[VTIME] = 0;
  if (cfsetspeed(&t, B38400) != 0) fail("cfsetspeed");
  // On the master, termios ioctls act on the slave side.
  if (tcsetattr(master_, TCSANOW, &t) != 0) fail("tcsetattr");
  if (tcgetattr(master_, &ref_) != 0) fail("tcgetattr");
  try {
    reset();
  } catch (const PtyError&) {
    ::close(master_);
    master_ = -1;
    throw;
  }
}

Pty::~Pty() {
  if (master_ >= 0) ::close(master_);
}

bool Pty::client_open() const {
  pollfd p{master_, POLLIN, 0};
  if (::poll(&p, 1, 0) < 0) return false;
  return (p.revents & POLLHUP) == 0;
}

void Pty::reset() {
  termios t = ref_;
  if (tcsetattr(master_, TCSANOW, &t) != 0) throw PtyError(errno_text("tcsetattr (reset)"));
  // What the chip sent that the last client did not read stays in the slave's input queue,
  // whatever the master flushes: empty it through a slave fd of our own, closed at once.
  const int s = ::open(slave_.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (s < 0) throw PtyError(errno_text(("open " + slave_).c_str()));
  tcflush(s, TCIOFLUSH);
  ::close(s);
  tcflush(master_, TCIOFLUSH);
  // Anything the client wrote before it went is discarded with it.
  unsigned char buf[4096];
  while (::read(master_, buf, sizeof buf) > 0) {
  }
}

bool Pty::changed() const {
  termios t{};
  if (tcgetattr(master_, &t) != 0) return false;
  return !same_termios(t, ref_);
}

// Linux's struct termios2 (asm-generic/termbits.h; glibc's termios.h cannot be included with
// it): the rate in baud, also one set as BOTHER with TCSETS2 (45450, 93750, 187500, 6 M, 12 M have
// no B constant), which cfgetospeed() reports only as BOTHER.
struct KernelTermios2 {
  tcflag_t c_iflag, c_oflag, c_cflag, c_lflag;
  cc_t c_line;
  cc_t c_cc[19];
  speed_t c_ispeed, c_ospeed;
};

unsigned Pty::speed() const {
  KernelTermios2 t{};
  if (::ioctl(master_, _IOR('T', 0x2A, KernelTermios2), &t) == 0) return t.c_ospeed;  // TCGETS2
  termios old{};
  if (tcgetattr(master_, &old) != 0) return 0;
  return speed_baud(cfgetospeed(&old));
}

long Pty::read(unsigned char* buf, unsigned long size) const {
  for (;;) {
    const ssize_t n = ::read(master_, buf, size);
    if (n > 0) return n;
    if (n == 0) return -1;
    if (errno == EINTR) continue;
    if (errno == EAGAIN || errno == EWOULDBLOCK) return 0;
    return -1;  // EIO: no slave fd open any more
  }
}

unsigned long Pty::write(const unsigned char* buf, unsigned long size) const {
  unsigned long done = 0;
  while (done < size) {
    const ssize_t n = ::write(master_, buf + done, size - done);
    if (n > 0) {
      done += static_cast<unsigned long>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    break;  // EAGAIN: the client does not read; the rest is dropped
  }
  return done;
}

std::string PtyPort::describe() const {
  return fmt::format("pty {} -> {}", link_, pty_.slave_name());
}

std::vector<pollfd> PtyPort::poll_fds() const {
  if (!present_) return {};
  return {{pty_.master_fd(), POLLIN, 0}};
}

void PtyPort::service(std::span<const pollfd> fds, const PortEvents& ev) {
  if (present_) {
    if (!fds.empty() && (fds[0].revents & (POLLIN | POLLHUP | POLLERR)) != 0) read_client(ev);
  } else if (pty_.client_open()) {
    present_ = true;
    speed_checked_ = false;
    ev.note("client opened the pty");
  } else if (pty_.changed()) {
    // A client opened, configured and closed the pty between two looks.
    pty_.reset();
    ev.note("a client changed the pty's settings and left: slave side reset");
  }
}

void PtyPort::read_client(const PortEvents& ev) {
  const auto read = [this, &ev](std::uint8_t* buf, std::size_t size) {
    const long n = pty_.read(buf, size);
    if (n > 0 && !speed_checked_) {
      speed_checked_ = true;
      const unsigned s = pty_.speed();
      if (s != baud_) {
        ev.note(fmt::format(
            "the client set {} on the pty; the bridge carries its bytes at {} baud",
            s == 0 ? std::string("a non-standard speed") : fmt::format("{} baud", s), baud_));
      }
    }
    return n;
  };
  if (read_bounded(read, ev)) return;
  // Hang-up: no slave fd open any more.
  present_ = false;
  // What it queued and the bus has not carried yet goes with it (a flood of its bytes must not
  // keep the next client waiting).
  ev.gone();
  pty_.reset();
  ev.note("client closed the pty: slave side reset (raw, 38400 baud), queues flushed");
}

std::size_t PtyPort::write(std::span<const std::uint8_t> bytes) {
  return pty_.write(bytes.data(), bytes.size());
}

std::string make_link(const std::string& path, const std::string& target) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) == 0) {
    if (!S_ISLNK(st.st_mode)) {
      return path + " exists and is not a symlink: refusing to replace it";
    }
    // Only a pty's link (a bridge's: stale, or live and the newest bridge wins) is replaced: a
    // user's own link (a dotfile, /dev/stdout, /dev/fd) is theirs, and would be gone at exit.
    std::vector<char> buf(4096);
    const ssize_t n = ::readlink(path.c_str(), buf.data(), buf.size() - 1);
    if (n < 0) return errno_text(path.c_str());
    const std::string old(buf.data(), static_cast<std::size_t>(n));
    if (!old.starts_with(kPtsDir)) {
      return fmt::format("{} is a symlink to {}, not to a pty in {}: refusing to replace it", path,
                         old, kPtsDir);
    }
    // Replace atomically: a client never finds the path missing.
    std::string error;
    const std::string tmp = outfile::create_temp(
        path,
        [&target](const std::string& name) {
          return ::symlink(target.c_str(), name.c_str()) == 0 ? 0 : errno;
        },
        error);
    if (tmp.empty() || !outfile::replace(tmp, path, error)) return error;
    return {};
  }
  if (errno != ENOENT) return errno_text(path.c_str());
  if (::symlink(target.c_str(), path.c_str()) != 0) return errno_text(("symlink " + path).c_str());
  return {};
}

void remove_link(const std::string& path, const std::string& target) {
  std::vector<char> buf(4096);
  const ssize_t n = ::readlink(path.c_str(), buf.data(), buf.size() - 1);
  if (n < 0) return;
  if (std::string(buf.data(), static_cast<std::size_t>(n)) == target) ::unlink(path.c_str());
}

}  // namespace dpc31::bridge

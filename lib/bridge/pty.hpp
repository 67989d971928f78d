// The pseudo-terminal of `dpc31 bridge` (docs/bridge.md, "The pty"): the bridge holds the master
// side; a DP master program opens the slave side (through a symlink) as its serial device.
//
// Linux specifics handled here:
// - the pty driver keeps no parity (PARENB is cleared on every tcsetattr), and Debian's glibc
//   reads the attributes back and fails a tcsetattr with EINVAL when nothing else of the request
//   took effect. So a client asking for 8E1 at the speed the pty already has fails. reset() puts
//   the slave side back to a fixed state whose speed (38400) is no PROFIBUS rate, so the next
//   client's request always changes the speed and succeeds.
// - termios ioctls on the master act on the slave side, so the reset needs no client.
// - with no slave fd open the master reports POLLHUP (and read() fails with EIO) continuously;
//   the bridge holds no slave fd, looks for a client with client_open() on a timer while none
//   is there, and polls the master for input only while one is.
#pragma once

#include <termios.h>

#include <stdexcept>
#include <string>
#include <string_view>

#include "port.hpp"

namespace dpc31::bridge {

struct PtyError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class Pty {
 public:
  // Opens a new pty pair: the master non-blocking and close-on-exec, the slave side reset().
  // The slave is opened and closed once, so the master reports hang-up until a client opens it.
  // Throws PtyError.
  Pty();
  ~Pty();
  Pty(const Pty&) = delete;
  Pty& operator=(const Pty&) = delete;

  [[nodiscard]] int master_fd() const { return master_; }
  [[nodiscard]] const std::string& slave_name() const { return slave_; }  // "/dev/pts/4"

  // Some process has the slave side open (the master does not report hang-up).
  [[nodiscard]] bool client_open() const;
  // The slave side back to the reset state: raw (cfmakeraw), 8 data bits, receiver on, modem
  // lines ignored, 38400 baud; both queues flushed (through a short-lived slave fd: flushing
  // from the master does not empty the slave's input queue). Throws PtyError.
  void reset();
  // The slave side's attributes differ from the reset state (a client changed them).
  [[nodiscard]] bool changed() const;
  // The output speed the slave side has now, in baud (also a non-standard one, set with
  // TCSETS2 and BOTHER); 0 if unknown.
  [[nodiscard]] unsigned speed() const;

  // Reads what the client wrote: bytes read (> 0), 0 when nothing is there, -1 on hang-up (EIO).
  long read(unsigned char* buf, unsigned long size) const;
  // Writes to the client; returns the bytes written (fewer when the client does not read).
  unsigned long write(const unsigned char* buf, unsigned long size) const;

 private:
  int master_ = -1;
  std::string slave_;
  termios ref_{};  // the reset state as the kernel keeps it
};

// The pty as the bridge's client port: polled only while a client has the slave side open (with
// none, the master reports hang-up continuously); otherwise each look checks whether one came.
class PtyPort final : public ClientPort {
 public:
  // `link` is the symlink the client opens (for the log); `baud` the bridge's rate, against
  // which the client's termios speed is compared once per connection.
  PtyPort(Pty& pty, std::string link, unsigned baud)
      : pty_(pty), link_(std::move(link)), baud_(baud) {}
  [[nodiscard]] std::string describe() const override;
  [[nodiscard]] std::vector<pollfd> poll_fds() const override;
  void service(std::span<const pollfd> fds, const PortEvents& ev) override;
  [[nodiscard]] bool present() const override { return present_; }
  std::size_t write(std::span<const std::uint8_t> bytes) override;

 private:
  void read_client(const PortEvents& ev);
  Pty& pty_;
  std::string link_;
  unsigned baud_;
  bool present_ = false;
  bool speed_checked_ = false;
};

// Where the slave sides of pseudo-terminals are: an existing symlink into it is a bridge's.
inline constexpr std::string_view kPtsDir = "/dev/pts/";

// Makes `path` a symlink to `target`. An existing symlink into kPtsDir is replaced (atomically);
// any other existing file or symlink is left alone. Returns an empty string, or a one-line reason
// it failed.
std::string make_link(const std::string& path, const std::string& target);
// Removes `path` if it is still a symlink to `target` (not one another bridge made since).
void remove_link(const std::string& path, const std::string& target);

// Baud rate of a termios speed constant (B19200 -> 19200), 0 if unknown.
unsigned speed_baud(speed_t s);

}  // namespace dpc31::bridge

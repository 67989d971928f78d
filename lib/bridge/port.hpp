// Where a DP master program meets `dpc31 bridge` (docs/bridge.md): a pseudo-terminal or a TCP
// port. The bridge's loop polls the port's descriptors, lets the port look at what happened, and
// writes the chip's answers back; one client at a time on either.
#pragma once

#include <poll.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

namespace dpc31::bridge {

// What a port tells the bridge while it looks (service()).
struct PortEvents {
  std::function<void(std::span<const std::uint8_t>)> bytes;  // the client wrote these
  std::function<void()> gone;  // the client went away (before the port's note about it)
  std::function<void(const std::string&)> note;  // a NOTE line: opened, closed, refused, ...
};

// The client's bytes one look takes at most: the rest waits in the kernel (the pty's buffer, the
// socket's and TCP's flow control) for the next turn of the bridge's loop, so a client that
// writes without pause cannot keep the chip and the signals from their turn. Far more than the
// fastest line carries in a loop period (12 Mbaud: 1.1 KB a millisecond).
inline constexpr std::size_t kMaxReadPerLook = 16 * 1024;

// Hands the client's bytes to ev.bytes, up to kMaxReadPerLook; false when the client went.
// `read(buf, size)` returns the bytes it read (> 0), 0 when none are waiting, < 0 when the client
// went.
template <class Read>
bool read_bounded(Read&& read, const PortEvents& ev) {
  std::uint8_t buf[4096];
  for (std::size_t taken = 0; taken < kMaxReadPerLook;) {
    const long n = read(buf, sizeof buf);
    if (n == 0) return true;
    if (n < 0) return false;
    ev.bytes({buf, static_cast<std::size_t>(n)});
    taken += static_cast<std::size_t>(n);
  }
  return true;
}

class ClientPort {
 public:
  virtual ~ClientPort() = default;
  // "pty /tmp/dp0 -> /dev/pts/3", "tcp 127.0.0.1:5000": the log's first line names it.
  [[nodiscard]] virtual std::string describe() const = 0;
  // The descriptors to poll for input now (none: the bridge looks again after its idle tick).
  [[nodiscard]] virtual std::vector<pollfd> poll_fds() const = 0;
  // After every poll, with the descriptors' revents (in poll_fds()'s order): takes a client,
  // reads its bytes, notices that it left. Throws PtyError when the port itself fails.
  virtual void service(std::span<const pollfd> fds, const PortEvents& ev) = 0;
  [[nodiscard]] virtual bool present() const = 0;  // a client is connected
  // Writes to the client; returns the bytes written (fewer when the client does not read).
  virtual std::size_t write(std::span<const std::uint8_t> bytes) = 0;
  // The client closed its sending side but may still read (a TCP half-close: `nc -N`): what it
  // sent is answered, then the bridge calls hang_up(), once nothing of it is queued, on the line
  // or unanswered.
  [[nodiscard]] virtual bool sent_all() const { return false; }
  virtual void hang_up(const PortEvents& /*ev*/) {}
};

}  // namespace dpc31::bridge

// Where a DP master program meets `dpc31 bridge` (docs/bridge.md): a pseudo-terminal or a TCP
// port. The bridge's loop polls the port's descriptors, lets the port look at what happened, and
// writes the chip's answers back; one client at a time on either.
#pragma once

#include <poll.h>

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
};

}  // namespace dpc31::bridge

// `dpc31 serve`: one emulated chip behind a line-based socket protocol (docs/protocol.md), on a
// loopback TCP port and/or a Unix socket. Single-threaded: one poll() loop accepts clients,
// reads their lines, executes them one at a time on the shared chip, and writes the replies and
// the async lines without ever blocking on a client.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "auth.hpp"
#include "dpc31/chip.hpp"
#include "serve_cpu.hpp"

namespace dpc31::serve {

// Bad endpoint, bind or listen failure (the CLI exits 2 with the message).
class ServerError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The shortest idle and first-line timeout, in seconds (0 turns the idle timeout off): shorter
// ones would close every client before its first line could arrive.
inline constexpr double kMinTimeout = 0.1;

// Limits and defaults: docs/protocol.md ("Limits") and docs/security.md.
struct ServerOptions {
  ChipOptions chip;
  // --cpu: an 80C32 beside the chip or its C31, the bus master (docs/protocol.md, "A CPU on the
  // bus").
  std::optional<CpuSetup> cpu;
  // "PORT" (binds 127.0.0.1) or "ADDR:PORT" ("[::1]:PORT" for IPv6); port 0 picks a free one.
  std::optional<std::string> tcp;
  std::optional<std::string> unix_path;  // the socket is created mode 0600
  // The only directory `save` and `load` may use; none = both are refused.
  std::optional<std::string> state_dir;
  // If set, a TCP client's first line must be `auth SECRET` (read_secret_file).
  std::optional<std::string> secret;
  std::size_t max_clients = 16;  // connections, also those that have not sent their first line
  double idle_timeout = 300;     // seconds without input before a client is closed; 0 = never
  // One line per wrong secret (who, how many in a row, the delay), and a warning at start for a
  // TCP port on another interface than the loopback without a secret; nullptr: none.
  std::FILE* log = nullptr;
  // Seconds a new connection has for its first line (and auth); the idle timeout if shorter.
  double hello_timeout = 10;
  // Bytes per line, without the newline: a whole *block of kMaxBlock bytes fits, its hex with a
  // blank between the bytes (3 x 4096 and the command).
  std::size_t max_line = 16 * 1024;
  std::size_t max_output = 1u << 20;     // queued output bytes before a client is dropped
  std::size_t output_pause = 64u << 10;  // stop executing a client's lines above this much output
  std::size_t max_input = 64u << 10;     // unexecuted input bytes before reading pauses
};

class Server {
 public:
  // Binds and listens at once; throws ServerError.
  explicit Server(ServerOptions opt);
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  // One line per endpoint: "listening tcp 127.0.0.1:PORT", "listening unix PATH".
  [[nodiscard]] const std::vector<std::string>& listening() const;
  [[nodiscard]] std::uint16_t tcp_port() const;

  // Serves until a client sends `shutdown` or stop() is called; returns 0.
  int run();
  // Makes run() return soon. Async-signal-safe and thread-safe.
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dpc31::serve

// `dpc31 serve`: one emulated chip behind a line-based socket protocol (docs/protocol.md), on a
// loopback TCP port and/or a Unix socket. Single-threaded: one poll() loop accepts clients,
// reads their lines, executes them one at a time on the shared chip, and writes the replies and
// the async lines without ever blocking on a client.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "dpc31/chip.hpp"

namespace dpc31::serve {

// Bad endpoint, bind or listen failure (the CLI exits 2 with the message).
class ServerError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Limits and defaults: docs/protocol.md ("Limits") and docs/security.md.
struct ServerOptions {
  ChipOptions chip;
  // "PORT" (binds 127.0.0.1) or "ADDR:PORT" ("[::1]:PORT" for IPv6); port 0 picks a free one.
  std::optional<std::string> tcp;
  std::optional<std::string> unix_path;  // the socket is created mode 0600
  // The only directory `save` and `load` may use; none = both are refused.
  std::optional<std::string> state_dir;
  // If set, a TCP client's first line must be `auth SECRET` (read_secret_file).
  std::optional<std::string> secret;
  std::size_t max_clients = 16;  // connections, also those that have not sent their first line
  double idle_timeout = 300;     // seconds without input before a client is closed; 0 = never
  // Seconds a new connection has for its first line (and auth); the idle timeout if shorter.
  double hello_timeout = 10;
  std::size_t max_line = 4096;           // bytes per line, without the newline
  std::size_t max_output = 1u << 20;     // queued output bytes before a client is dropped
  std::size_t output_pause = 64u << 10;  // stop executing a client's lines above this much output
  std::size_t max_input = 64u << 10;     // unexecuted input bytes before reading pauses
};

// The secret of --secret-file: the file's first line (a trailing CR is dropped), 16..1024
// printable ASCII characters without blanks; the file must be a regular file that neither group
// nor others may access (chmod 600). Throws ServerError with one line.
std::string read_secret_file(const std::string& path);

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

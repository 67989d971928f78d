// The listening sockets of `dpc31 serve` (docs/protocol.md): a loopback TCP port by default and
// a Unix socket of mode 0600.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <string>

namespace dpc31::serve {

struct Endpoint {
  int fd = -1;             // listening, non-blocking, close-on-exec
  std::uint16_t port = 0;  // TCP: the port bound
  bool loopback = true;    // TCP: bound to 127.0.0.0/8 or ::1, where only this host reaches it
  std::string line;        // "listening tcp 127.0.0.1:PORT", "listening unix PATH"
  std::string unix_path;   // Unix: the socket file made (unlinked at the end if still ours)
  dev_t dev = 0;
  ino_t ino = 0;
};

// "PORT" (127.0.0.1) or "ADDR:PORT": ADDR a dotted-quad IPv4 address, "[v6]" or a host name
// (inet_aton's legacy forms such as "0" or "127.1" are refused). Throws ServerError with one line.
Endpoint open_tcp(const std::string& spec);
// A socket file at `path`, mode 0600; a stale socket left by a dead server is replaced, one a
// live server listens on (even with a full backlog) is refused. Throws ServerError.
Endpoint open_unix(const std::string& path);

void set_cloexec_nonblock(int fd);

}  // namespace dpc31::serve

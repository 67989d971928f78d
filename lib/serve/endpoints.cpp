#include "endpoints.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <netdb.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <string_view>

#include "serve_server.hpp"

namespace dpc31::serve {

namespace {

std::string errno_text(int e) { return std::strerror(e); }

bool all_digits(std::string_view s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// Why `host` is none of the forms docs/protocol.md names for ADDR (a dotted-quad IPv4 address,
// `[v6]`, a host name), "" if it is one. The resolver also reads inet_aton's legacy forms (`0`,
// `127.1`, `0x7f000001`, `010.0.0.1` in octal) as addresses: `0:5555`, meant as "port 5555",
// would listen on every interface. A name whose last label is all digits is no host name
// (RFC 3696, 2) and would only go to DNS.
std::string check_host(const std::string& host, bool bracketed) {
  in6_addr v6{};
  if (bracketed) {
    // A link-local address names its interface after '%' (fe80::1%eth0, RFC 4007): the
    // resolver takes the zone, inet_pton the address before it.
    const std::string addr = host.substr(0, host.find('%'));
    const bool zone_ok = addr.size() == host.size() || addr.size() + 1 < host.size();
    return zone_ok && ::inet_pton(AF_INET6, addr.c_str(), &v6) == 1
               ? std::string()
               : fmt::format("'[{}]' is no IPv6 address", host);
  }
  if (host.find(':') != std::string::npos) {
    return fmt::format("an IPv6 address goes in brackets: [{}]:PORT", host);
  }
  in_addr v4{};
  if (::inet_pton(AF_INET, host.c_str(), &v4) == 1) return {};
  const std::string_view last = std::string_view(host).substr(host.rfind('.') + 1);
  if (::inet_aton(host.c_str(), &v4) != 0 || all_digits(last)) {
    return fmt::format(
        "'{}' is neither a dotted-quad IPv4 address (four decimal parts: 127.0.0.1, 0.0.0.0) nor a "
        "host name",
        host);
  }
  return {};
}

}  // namespace

void set_cloexec_nonblock(int fd) {
  ::fcntl(fd, F_SETFD, FD_CLOEXEC);
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK);
}

Endpoint open_tcp(const std::string& spec) {
  Endpoint ep;
  int& tcp_fd = ep.fd;
  std::string host = "127.0.0.1";
  std::string port_text = spec;
  bool bracketed = false;
  if (!all_digits(spec)) {
    const std::size_t colon = spec.rfind(':');
    if (colon == std::string::npos) {
      throw ServerError(fmt::format("--tcp '{}': expected PORT or ADDR:PORT", spec));
    }
    host = spec.substr(0, colon);
    port_text = spec.substr(colon + 1);
    bracketed = host.size() >= 2 && host.front() == '[' && host.back() == ']';
    if (bracketed) host = host.substr(1, host.size() - 2);
  }
  if (host.empty() || !all_digits(port_text) || port_text.size() > 5 ||
      std::stoul(port_text) > 65535) {
    throw ServerError(fmt::format("--tcp '{}': expected PORT or ADDR:PORT, port 0..65535", spec));
  }
  if (const std::string why = check_host(host, bracketed); !why.empty()) {
    throw ServerError(fmt::format("--tcp '{}': {}", spec, why));
  }
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  addrinfo* res = nullptr;
  if (const int rc = ::getaddrinfo(host.c_str(), port_text.c_str(), &hints, &res); rc != 0) {
    throw ServerError(fmt::format("--tcp '{}': {}", spec, ::gai_strerror(rc)));
  }
  std::string why = "no address";
  for (addrinfo* a = res; a != nullptr; a = a->ai_next) {
    const int fd = ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol);
    if (fd < 0) {
      why = errno_text(errno);
      continue;
    }
    const int one = 1;
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    if (::bind(fd, a->ai_addr, a->ai_addrlen) != 0 || ::listen(fd, 64) != 0) {
      why = errno_text(errno);
      ::close(fd);
      continue;
    }
    tcp_fd = fd;
    break;
  }
  ::freeaddrinfo(res);
  if (tcp_fd < 0) throw ServerError(fmt::format("cannot listen on tcp {}: {}", spec, why));
  set_cloexec_nonblock(tcp_fd);
  sockaddr_storage ss{};
  socklen_t len = sizeof ss;
  ::getsockname(tcp_fd, reinterpret_cast<sockaddr*>(&ss), &len);
  char h[NI_MAXHOST];
  char s[NI_MAXSERV];
  ::getnameinfo(reinterpret_cast<sockaddr*>(&ss), len, h, sizeof h, s, sizeof s,
                NI_NUMERICHOST | NI_NUMERICSERV);
  ep.port = static_cast<std::uint16_t>(std::stoul(s));
  // ::1, 127/8, and 127/8 mapped into IPv6 (::ffff:127.0.0.1).
  const auto v4_loopback = [](std::uint32_t host_order) { return (host_order >> 24) == 127; };
  if (ss.ss_family == AF_INET6) {
    const in6_addr& a = reinterpret_cast<const sockaddr_in6&>(ss).sin6_addr;
    std::uint32_t mapped = 0;
    std::memcpy(&mapped, a.s6_addr + 12, 4);
    ep.loopback =
        IN6_IS_ADDR_LOOPBACK(&a) || (IN6_IS_ADDR_V4MAPPED(&a) && v4_loopback(ntohl(mapped)));
  } else {
    ep.loopback = v4_loopback(ntohl(reinterpret_cast<const sockaddr_in&>(ss).sin_addr.s_addr));
  }
  ep.line = ss.ss_family == AF_INET6 ? fmt::format("listening tcp [{}]:{}", h, s)
                                     : fmt::format("listening tcp {}:{}", h, s);
  return ep;
}

Endpoint open_unix(const std::string& path) {
  Endpoint ep;
  sockaddr_un sa{};
  sa.sun_family = AF_UNIX;
  if (path.empty() || path.size() >= sizeof sa.sun_path) {
    throw ServerError(
        fmt::format("--unix '{}': the path must have 1..{} bytes", path, sizeof sa.sun_path - 1));
  }
  std::memcpy(sa.sun_path, path.c_str(), path.size() + 1);
  const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw ServerError("socket: " + errno_text(errno));
  struct stat st {};
  if (::lstat(path.c_str(), &st) == 0) {
    if (!S_ISSOCK(st.st_mode)) {
      ::close(fd);
      throw ServerError(fmt::format("--unix {}: exists and is not a socket", path));
    }
    // A socket nobody accepts on is left over from a server that died: replace it.
    // Non-blocking: a live server whose backlog is full answers EAGAIN at once instead of
    // holding the connect() until it accepts.
    const int probe = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    const bool stale = probe >= 0 &&
                       ::connect(probe, reinterpret_cast<sockaddr*>(&sa), sizeof sa) != 0 &&
                       errno == ECONNREFUSED;
    if (probe >= 0) ::close(probe);
    if (!stale) {
      ::close(fd);
      throw ServerError(fmt::format("--unix {}: in use by a running server", path));
    }
    ::unlink(path.c_str());
  }
  // Only our user may connect: the socket file is created 0600 (connect() needs write permission
  // on it). The umask makes it so from the start; the chmod is for file systems that ignore it.
  const mode_t old_mask = ::umask(0177);
  const int bound = ::bind(fd, reinterpret_cast<sockaddr*>(&sa), sizeof sa);
  const int bind_errno = errno;
  ::umask(old_mask);
  if (bound != 0 || ::chmod(path.c_str(), 0600) != 0 || ::listen(fd, 64) != 0) {
    const int e = bound != 0 ? bind_errno : errno;
    if (bound == 0) ::unlink(path.c_str());
    ::close(fd);
    throw ServerError(fmt::format("cannot listen on unix {}: {}", path, errno_text(e)));
  }
  ep.fd = fd;
  set_cloexec_nonblock(fd);
  if (::lstat(path.c_str(), &st) == 0) {
    ep.unix_path = path;
    ep.dev = st.st_dev;
    ep.ino = st.st_ino;
  }
  ep.line = "listening unix " + path;
  return ep;
}

}  // namespace dpc31::serve

#include "tcp.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstring>

namespace dpc31::bridge {

namespace {

std::string errno_text(const std::string& what) { return what + ": " + std::strerror(errno); }

std::string address_text(const sockaddr_storage& ss) {
  char host[INET6_ADDRSTRLEN] = "?";
  unsigned port = 0;
  if (ss.ss_family == AF_INET) {
    const auto& a = reinterpret_cast<const sockaddr_in&>(ss);
    ::inet_ntop(AF_INET, &a.sin_addr, host, sizeof host);
    port = ntohs(a.sin_port);
    return fmt::format("{}:{}", host, port);
  }
  const auto& a = reinterpret_cast<const sockaddr_in6&>(ss);
  ::inet_ntop(AF_INET6, &a.sin6_addr, host, sizeof host);
  port = ntohs(a.sin6_port);
  return fmt::format("[{}]:{}", host, port);
}

}  // namespace

std::string parse_listen(const std::string& text, ListenAddress& a) {
  std::string host = "127.0.0.1";
  std::string port = text;
  if (!text.empty() && text.front() == '[') {
    const std::size_t close = text.find("]:");
    if (close == std::string::npos) return fmt::format("'{}' is no [HOST]:PORT", text);
    host = text.substr(1, close - 1);
    port = text.substr(close + 2);
  } else if (const std::size_t colon = text.rfind(':'); colon != std::string::npos) {
    host = text.substr(0, colon);
    port = text.substr(colon + 1);
  }
  unsigned v = 0;
  const auto [p, ec] = std::from_chars(port.data(), port.data() + port.size(), v, 10);
  if (port.empty() || ec != std::errc() || p != port.data() + port.size() || v > 65535) {
    return fmt::format("'{}' has no port 0..65535", text);
  }
  in6_addr buf{};
  if (::inet_pton(AF_INET, host.c_str(), &buf) != 1 &&
      ::inet_pton(AF_INET6, host.c_str(), &buf) != 1) {
    return fmt::format("'{}' is no numeric IPv4 or IPv6 address", host);
  }
  a.host = host;
  a.port = v;
  return {};
}

bool is_loopback(const std::string& host) {
  in_addr v4{};
  if (::inet_pton(AF_INET, host.c_str(), &v4) == 1) return (ntohl(v4.s_addr) >> 24) == 127;
  in6_addr v6{};
  return ::inet_pton(AF_INET6, host.c_str(), &v6) == 1 && IN6_IS_ADDR_LOOPBACK(&v6);
}

TcpPort::TcpPort(const ListenAddress& a) : host_(a.host) {
  addrinfo hints{};
  hints.ai_flags = AI_NUMERICHOST | AI_NUMERICSERV | AI_PASSIVE;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* res = nullptr;
  if (const int rc = ::getaddrinfo(a.host.c_str(), std::to_string(a.port).c_str(), &hints, &res);
      rc != 0) {
    throw PtyError(fmt::format("{}: {}", a.host, ::gai_strerror(rc)));
  }
  const int fd = ::socket(res->ai_family, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    ::freeaddrinfo(res);
    throw PtyError(errno_text("socket"));
  }
  const int one = 1;
  ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  const std::string where = a.host.find(':') != std::string::npos
                                ? fmt::format("[{}]:{}", a.host, a.port)
                                : fmt::format("{}:{}", a.host, a.port);
  if (::bind(fd, res->ai_addr, res->ai_addrlen) != 0 || ::listen(fd, 4) != 0) {
    const std::string msg = errno_text("cannot listen on " + where);
    ::freeaddrinfo(res);
    ::close(fd);
    throw PtyError(msg);
  }
  ::freeaddrinfo(res);
  sockaddr_storage ss{};
  socklen_t len = sizeof ss;
  if (::getsockname(fd, reinterpret_cast<sockaddr*>(&ss), &len) != 0) {
    const std::string msg = errno_text("getsockname");
    ::close(fd);
    throw PtyError(msg);
  }
  port_ = ntohs(ss.ss_family == AF_INET ? reinterpret_cast<const sockaddr_in&>(ss).sin_port
                                        : reinterpret_cast<const sockaddr_in6&>(ss).sin6_port);
  listen_ = fd;
}

TcpPort::~TcpPort() {
  if (client_ >= 0) ::close(client_);
  if (listen_ >= 0) ::close(listen_);
}

std::string TcpPort::describe() const {
  return host_.find(':') != std::string::npos ? fmt::format("tcp [{}]:{}", host_, port_)
                                              : fmt::format("tcp {}:{}", host_, port_);
}

// The listening socket is always polled: a second client is refused at once, not left waiting
// in the backlog believing it is connected.
std::vector<pollfd> TcpPort::poll_fds() const {
  std::vector<pollfd> fds{{listen_, POLLIN, 0}};
  // After a half-close only a reset is looked for: POLLIN would report the end of input forever.
  if (client_ >= 0) fds.push_back({client_, static_cast<short>(sent_all_ ? 0 : POLLIN), 0});
  return fds;
}

void TcpPort::service(std::span<const pollfd> fds, const PortEvents& ev) {
  // The client's bytes first: a client that sent its last request and closed is read to the end
  // before a new one is taken.
  if (client_ >= 0 && fds.size() > 1 && (fds[1].revents & (POLLIN | POLLHUP | POLLERR)) != 0) {
    read_client(ev);
  }
  if (!fds.empty() && (fds[0].revents & POLLIN) != 0) accept_one(ev);
}

void TcpPort::accept_one(const PortEvents& ev) {
  for (;;) {
    sockaddr_storage ss{};
    socklen_t len = sizeof ss;
    const int fd =
        ::accept4(listen_, reinterpret_cast<sockaddr*>(&ss), &len, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) {
      if (errno == EINTR || errno == ECONNABORTED) continue;
      return;  // EAGAIN: no more waiting; anything else is the next client's problem
    }
    const std::string peer = address_text(ss);
    // A client that half-closed waits for its answers only while nobody else wants the port.
    if (sent_all()) drop_client(ev, "closed the connection");
    if (client_ >= 0) {
      ::close(fd);
      ev.note(fmt::format("refused a second client from {}: one client at a time ({} is connected)",
                          peer, peer_));
      continue;
    }
    // A master writes one telegram and waits for the answer: no Nagle delay on the answers.
    const int one = 1;
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    client_ = fd;
    peer_ = peer;
    ev.note(fmt::format("client connected from {}", peer_));
  }
}

// A client with Nagle on (pyserial's socket://) holds the rest of a telegram it wrote in two
// writes until its first part is ACKed; Linux delays the ACK up to 40 ms once it sees a dialogue,
// beyond the 20 ms after which an incomplete telegram goes out as it is. The kernel clears
// TCP_QUICKACK by itself, so it is set again after every read.
void TcpPort::quick_ack() const {
#ifdef TCP_QUICKACK
  const int one = 1;
  ::setsockopt(client_, IPPROTO_TCP, TCP_QUICKACK, &one, sizeof one);
#endif
}

void TcpPort::read_client(const PortEvents& ev) {
  int error = 0;  // 0: the end of its input
  const auto read = [this, &error](std::uint8_t* buf, std::size_t size) -> long {
    for (;;) {
      const ssize_t n = ::recv(client_, buf, size, MSG_DONTWAIT);
      if (n > 0) {
        quick_ack();
        return n;
      }
      if (n < 0 && errno == EINTR) continue;
      if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return 0;
      error = n < 0 ? errno : 0;
      return -1;
    }
  };
  if (read_bounded(read, ev)) return;
  if (error == 0 && !sent_all_) {
    // The end of its input, which may be a half-close: the client may still read its answers.
    sent_all_ = true;
    ev.note(fmt::format("client {} closed its sending side: answering what it sent", peer_));
    return;
  }
  errno = error;
  drop_client(ev, error == 0 ? std::string("closed the connection") : errno_text("connection"));
}

void TcpPort::drop_client(const PortEvents& ev, const std::string& why) {
  ::close(client_);
  client_ = -1;
  sent_all_ = false;
  // What it queued and the bus has not carried yet goes with it, as on the pty.
  ev.gone();
  ev.note(fmt::format("client {} {}: queues flushed", peer_, why));
}

std::size_t TcpPort::write(std::span<const std::uint8_t> bytes) {
  std::size_t done = 0;
  while (client_ >= 0 && done < bytes.size()) {
    const ssize_t n =
        ::send(client_, bytes.data() + done, bytes.size() - done, MSG_DONTWAIT | MSG_NOSIGNAL);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    break;  // EAGAIN: the client does not read (the rest is dropped); EPIPE: read_client sees it
  }
  return done;
}

}  // namespace dpc31::bridge

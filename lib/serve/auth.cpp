#include "auth.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <netinet/in.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "serve_server.hpp"

namespace dpc31::serve {

bool same_secret(std::string_view given, std::string_view secret) {
  unsigned diff = given.size() == secret.size() ? 0 : 1;
  for (std::size_t i = 0; i < secret.size(); ++i) {
    const auto g = static_cast<unsigned char>(i < given.size() ? given[i] : 0);
    diff |= g ^ static_cast<unsigned char>(secret[i]);
  }
  return diff == 0;
}

std::string read_secret_file(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
  if (fd < 0) throw ServerError(fmt::format("--secret-file {}: {}", path, std::strerror(errno)));
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    throw ServerError(fmt::format("--secret-file {}: not a regular file", path));
  }
  // Its owner could have read it, or may change it (and its mode) at any time.
  if (st.st_uid != ::geteuid()) {
    throw ServerError(fmt::format(
        "--secret-file {}: owned by user {}, not by this user ({}): the secret must be yours alone",
        path, st.st_uid, ::geteuid()));
  }
  if ((st.st_mode & 077) != 0) {
    throw ServerError(
        fmt::format("--secret-file {}: group or others may access it (mode {:04o}): chmod 600 it",
                    path, st.st_mode & 07777));
  }
  char buf[4096];
  std::string text;
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw ServerError(fmt::format("--secret-file {}: {}", path, std::strerror(errno)));
    if (n == 0 || text.size() > 4096) break;
    text.append(buf, static_cast<std::size_t>(n));
  }
  std::string secret = text.substr(0, text.find('\n'));
  if (!secret.empty() && secret.back() == '\r') secret.pop_back();
  const bool printable = std::all_of(secret.begin(), secret.end(), [](char ch) {
    return static_cast<unsigned char>(ch) > 0x20 && static_cast<unsigned char>(ch) < 0x7F;
  });
  if (secret.size() < 16 || secret.size() > 1024 || !printable) {
    throw ServerError(fmt::format(
        "--secret-file {}: the first line must be 16 to 1024 printable ASCII characters without "
        "blanks",
        path));
  }
  return secret;
}

std::string peer_of(const sockaddr_storage& addr) {
  char text[INET6_ADDRSTRLEN] = {};
  if (addr.ss_family == AF_INET) {
    in_addr a = reinterpret_cast<const sockaddr_in&>(addr).sin_addr;
    if ((ntohl(a.s_addr) >> 24) == 127) return "127.0.0.0/8";
    ::inet_ntop(AF_INET, &a, text, sizeof text);
    return text;
  }
  if (addr.ss_family == AF_INET6) {
    in6_addr a = reinterpret_cast<const sockaddr_in6&>(addr).sin6_addr;
    if (IN6_IS_ADDR_V4MAPPED(&a) && a.s6_addr[12] == 127) return "127.0.0.0/8";
    if (IN6_IS_ADDR_LOOPBACK(&a) || IN6_IS_ADDR_V4MAPPED(&a)) {
      ::inet_ntop(AF_INET6, &a, text, sizeof text);
      return text;
    }
    std::fill(a.s6_addr + 8, a.s6_addr + 16, 0);
    ::inet_ntop(AF_INET6, &a, text, sizeof text);
    return std::string(text) + "/64";
  }
  return "unknown";
}

AuthThrottle::Clock::time_point AuthThrottle::ready_at(const std::string& peer,
                                                       Clock::time_point now) {
  const auto it = peers_.find(peer);
  if (it == peers_.end()) return now;
  if (now - it->second.last >= kForget) {
    peers_.erase(it);
    return now;
  }
  return it->second.ready;
}

std::uint64_t AuthThrottle::failed(const std::string& peer, Clock::time_point now,
                                   Clock::duration& delay) {
  if (peers_.size() >= kMaxPeers && peers_.find(peer) == peers_.end()) {
    peers_.erase(std::min_element(peers_.begin(), peers_.end(), [](const auto& a, const auto& b) {
      return a.second.last < b.second.last;
    }));
  }
  Record& r = peers_[peer];
  if (r.failures > 0 && now - r.last >= kForget) r = Record{};
  ++r.failures;
  r.last = now;
  const std::uint64_t doublings = std::min<std::uint64_t>(r.failures - 1, 16);
  delay = std::min<Clock::duration>(kFirstDelay * (std::uint64_t{1} << doublings), kMaxDelay);
  r.ready = now + delay;
  return r.failures;
}

}  // namespace dpc31::serve

// The shared secret of `dpc31 serve --secret-file` (docs/security.md): reading the file, the
// constant-time comparison, and the delay that grows with each wrong secret from one peer.
#pragma once

#include <sys/socket.h>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <unordered_map>

namespace dpc31::serve {

// The secret of --secret-file: the file's first line (a trailing CR is dropped), 16..1024
// printable ASCII characters without blanks; the file must be a regular file owned by the
// server's user that neither group nor others may access (chmod 600). Throws ServerError.
std::string read_secret_file(const std::string& path);

// Equal in time independent of where they differ: every byte of the secret is looked at,
// whatever was given.
bool same_secret(std::string_view given, std::string_view secret);

// Who a TCP client is, for the delay: its address, all of 127.0.0.0/8 as one (a local process
// may bind any of them) and an IPv6 address by its /64 (one host's share).
std::string peer_of(const sockaddr_storage& addr);

// Wrong secrets from one peer: the next `auth` line of that peer is judged no sooner than
// kFirstDelay x 2^(failures - 1) after the last wrong one, at most kMaxDelay; the record is
// forgotten kForget after its last failure, or at a right secret. At most kMaxPeers records (the
// oldest failure gives way).
class AuthThrottle {
 public:
  using Clock = std::chrono::steady_clock;
  static constexpr auto kFirstDelay = std::chrono::milliseconds(50);
  static constexpr auto kMaxDelay = std::chrono::seconds(5);
  static constexpr auto kForget = std::chrono::seconds(600);
  static constexpr std::size_t kMaxPeers = 4096;

  // When the peer's next `auth` line may be judged (in the past when at once).
  [[nodiscard]] Clock::time_point ready_at(const std::string& peer, Clock::time_point now);
  // A wrong secret: the peer's failures so far, and the delay before its next judgement.
  std::uint64_t failed(const std::string& peer, Clock::time_point now, Clock::duration& delay);
  void succeeded(const std::string& peer) { peers_.erase(peer); }

 private:
  struct Record {
    std::uint64_t failures = 0;
    Clock::time_point last;
    Clock::time_point ready;
  };
  std::unordered_map<std::string, Record> peers_;
};

}  // namespace dpc31::serve

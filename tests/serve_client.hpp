// Test helpers for `dpc31 serve` (docs/protocol.md): the real binary as a child process, and a
// line client over TCP or a Unix socket. Every wait has a deadline: a server that hangs fails
// the test (std::runtime_error) instead of hanging it.
#pragma once

#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

extern char** environ;

namespace testutil {

inline std::vector<std::string> words(const std::string& s) {
  std::istringstream in(s);
  std::vector<std::string> w;
  for (std::string x; in >> x;) w.push_back(x);
  return w;
}

inline bool starts_with(const std::string& s, std::string_view p) { return s.rfind(p, 0) == 0; }

inline constexpr int kDefaultTimeoutMs = 10'000;

// Wall-clock limits are multiplied by DPC31_TIMEOUT_SCALE; only the sanitizer build
// (CMakePresets.json, asan) sets it above 1 (docs/sanitizers.md).
inline int scaled_ms(int ms) {
  const char* s = std::getenv("DPC31_TIMEOUT_SCALE");
  const double f = s != nullptr ? std::atof(s) : 1.0;
  return f > 1.0 ? static_cast<int>(ms * f) : ms;
}

// `dpc31 serve ARGS...` with its stdout on a pipe; the constructor waits for the "listening"
// lines (one per endpoint asked for). `launcher` (a shell that sets a limit, then `exec "$@"`)
// runs it, if given.
class ServerProcess {
 public:
  ServerProcess(const std::string& binary, const std::vector<std::string>& args,
                const std::vector<std::string>& launcher = {}) {
    int p[2];
    if (::pipe2(p, O_CLOEXEC) != 0) throw std::runtime_error("pipe2");
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_adddup2(&fa, p[1], STDOUT_FILENO);
    std::vector<std::string> argv_s = launcher;
    argv_s.insert(argv_s.end(), {binary, "serve"});
    argv_s.insert(argv_s.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& a : argv_s) argv.push_back(a.data());
    argv.push_back(nullptr);
    const int rc = posix_spawn(&pid_, argv_s.front().c_str(), &fa, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    ::close(p[1]);
    out_fd_ = p[0];
    if (rc != 0) throw std::runtime_error("posix_spawn " + binary + ": " + std::strerror(rc));
    std::size_t expected = 0;
    for (const auto& a : args) expected += (a == "--tcp" || a == "--unix") ? 1 : 0;
    while (listening_.size() < expected) {
      const std::optional<std::string> l = read_stdout_line(kDefaultTimeoutMs);
      if (!l) break;  // exited
      listening_.push_back(*l);
      if (l->rfind("listening tcp ", 0) == 0) {
        port_ = static_cast<std::uint16_t>(std::stoul(l->substr(l->rfind(':') + 1)));
      }
    }
  }
  ~ServerProcess() {
    if (pid_ > 0 && wait_exit(0) == kRunning) {
      ::kill(pid_, SIGTERM);
      if (wait_exit(5000) == kRunning) {
        ::kill(pid_, SIGKILL);
        wait_exit(5000);
      }
    }
    if (out_fd_ >= 0) ::close(out_fd_);
  }
  ServerProcess(const ServerProcess&) = delete;
  ServerProcess& operator=(const ServerProcess&) = delete;

  static constexpr int kRunning = -1000;
  // The exit code (-signal if killed), or kRunning if it has not exited within `timeout_ms`.
  int wait_exit(int timeout_ms) {
    if (exited_) return status_;
    const auto until =
        std::chrono::steady_clock::now() + std::chrono::milliseconds(scaled_ms(timeout_ms));
    for (;;) {
      int st = 0;
      const pid_t r = ::waitpid(pid_, &st, WNOHANG);
      if (r == pid_) {
        exited_ = true;
        status_ = WIFEXITED(st) ? WEXITSTATUS(st) : -WTERMSIG(st);
        return status_;
      }
      if (std::chrono::steady_clock::now() >= until) return kRunning;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
  void signal(int sig) const { ::kill(pid_, sig); }
  [[nodiscard]] pid_t pid() const { return pid_; }

  [[nodiscard]] const std::vector<std::string>& listening() const { return listening_; }
  [[nodiscard]] std::uint16_t port() const { return port_; }

 private:
  std::optional<std::string> read_stdout_line(int timeout_ms) {
    std::string line;
    for (;;) {
      pollfd pfd{out_fd_, POLLIN, 0};
      if (::poll(&pfd, 1, scaled_ms(timeout_ms)) <= 0)
        throw std::runtime_error("server printed nothing");
      char ch = 0;
      const ssize_t n = ::read(out_fd_, &ch, 1);
      if (n <= 0) return std::nullopt;
      if (ch == '\n') return line;
      line.push_back(ch);
    }
  }

  pid_t pid_ = -1;
  int out_fd_ = -1;
  bool exited_ = false;
  int status_ = 0;
  std::vector<std::string> listening_;
  std::uint16_t port_ = 0;
};

// One connection speaking the line protocol. Replies are returned by command(); async lines
// ("! ...") that arrive before a reply are appended to `async` in order.
class LineClient {
 public:
  static LineClient tcp(std::uint16_t port) {
    const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in sa{};
    sa.sin_family = AF_INET;
    sa.sin_port = htons(port);
    sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&sa), sizeof sa) != 0) {
      ::close(fd);
      throw std::runtime_error("connect tcp: " + std::string(std::strerror(errno)));
    }
    const int one = 1;
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    return LineClient(fd);
  }
  static LineClient unix_socket(const std::string& path) {
    const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_un sa{};
    sa.sun_family = AF_UNIX;
    std::strncpy(sa.sun_path, path.c_str(), sizeof sa.sun_path - 1);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&sa), sizeof sa) != 0) {
      ::close(fd);
      throw std::runtime_error("connect unix: " + std::string(std::strerror(errno)));
    }
    return LineClient(fd);
  }

  explicit LineClient(int fd) : fd_(fd) {}
  LineClient(LineClient&& o) noexcept
      : async(std::move(o.async)), fd_(std::exchange(o.fd_, -1)), buf_(std::move(o.buf_)) {}
  LineClient& operator=(LineClient&&) = delete;
  LineClient(const LineClient&) = delete;
  ~LineClient() { close(); }

  void close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }
  [[nodiscard]] int fd() const { return fd_; }

  void send(std::string_view bytes, int timeout_ms = kDefaultTimeoutMs) {
    const auto until = deadline(timeout_ms);
    while (!bytes.empty()) {
      const ssize_t n = ::send(fd_, bytes.data(), bytes.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
      if (n > 0) {
        bytes.remove_prefix(static_cast<std::size_t>(n));
        continue;
      }
      if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
        throw std::runtime_error("send: " + std::string(std::strerror(errno)));
      }
      wait_for(POLLOUT, until, "send");
    }
  }

  // The next line (without its newline); nullopt at end of stream (or reset).
  std::optional<std::string> read_line(int timeout_ms = kDefaultTimeoutMs) {
    const auto until = deadline(timeout_ms);
    for (;;) {
      const std::size_t nl = buf_.find('\n');
      if (nl != std::string::npos) {
        std::string l = buf_.substr(0, nl);
        buf_.erase(0, nl + 1);
        return l;
      }
      if (eof_) return std::nullopt;
      wait_for(POLLIN, until, "read");
      fill();
    }
  }

  // Sends `line` and returns its reply; async lines before it go to `async`.
  std::string command(std::string_view line, int timeout_ms = kDefaultTimeoutMs) {
    send(std::string(line) + "\n", timeout_ms);
    return reply(timeout_ms);
  }
  // The next reply line, collecting async lines.
  std::string reply(int timeout_ms = kDefaultTimeoutMs) {
    for (;;) {
      const std::optional<std::string> l = read_line(timeout_ms);
      if (!l) throw std::runtime_error("connection closed while waiting for a reply");
      if (!l->empty() && (*l)[0] == '!') {
        async.push_back(*l);
        continue;
      }
      return *l;
    }
  }
  // Reads (collecting async lines, dropping nothing else) until the server closes; returns the
  // non-async lines seen. Throws if it stays open for `timeout_ms`.
  std::vector<std::string> read_until_closed(int timeout_ms = kDefaultTimeoutMs) {
    std::vector<std::string> lines;
    for (;;) {
      const std::optional<std::string> l = read_line(timeout_ms);
      if (!l) return lines;
      if (!l->empty() && (*l)[0] == '!') {
        async.push_back(*l);
      } else {
        lines.push_back(*l);
      }
    }
  }

  std::vector<std::string> async;

 private:
  static std::chrono::steady_clock::time_point deadline(int ms) {
    return std::chrono::steady_clock::now() + std::chrono::milliseconds(scaled_ms(ms));
  }
  void wait_for(short ev, std::chrono::steady_clock::time_point until, const char* what) const {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
                          until - std::chrono::steady_clock::now())
                          .count();
    pollfd pfd{fd_, ev, 0};
    if (left <= 0 || ::poll(&pfd, 1, static_cast<int>(left)) <= 0) {
      throw std::runtime_error(std::string("timeout in ") + what);
    }
  }
  void fill() {
    char b[65536];
    const ssize_t n = ::recv(fd_, b, sizeof b, MSG_DONTWAIT);
    if (n > 0) {
      buf_.append(b, static_cast<std::size_t>(n));
    } else if (n == 0 || (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
      eof_ = true;
    }
  }

  int fd_ = -1;
  std::string buf_;
  bool eof_ = false;
};

}  // namespace testutil

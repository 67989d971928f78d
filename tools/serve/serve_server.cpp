#include "serve_server.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <string_view>

#include "serve_session.hpp"

namespace dpc31::serve {

namespace {

using Clock = std::chrono::steady_clock;

constexpr std::size_t kReadChunk = 16u << 10;
constexpr int kMaxPasses = 64;                         // lines per client per poll() round
constexpr auto kCloseGrace = std::chrono::seconds(2);  // to flush the last lines of a client
constexpr auto kShutdownGrace = std::chrono::seconds(1);
constexpr auto kAcceptPause = std::chrono::milliseconds(100);  // after EMFILE and friends

std::string errno_text(int e) { return std::strerror(e); }

void set_cloexec_nonblock(int fd) {
  ::fcntl(fd, F_SETFD, FD_CLOEXEC);
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK);
}

bool all_digits(std::string_view s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

struct Client {
  int fd = -1;
  std::string in;
  std::size_t in_off = 0;
  std::string out;
  std::size_t out_off = 0;
  bool discarding = false;  // inside an over-long line: drop bytes up to the next newline
  bool eof = false;         // the peer sends no more: execute what is left, then close
  bool closing = false;     // no more input; close once the output is sent or at close_by
  bool dead = false;        // close now, unsent output is lost
  Clock::time_point last_input;
  Clock::time_point close_by;
  ClientState state;

  [[nodiscard]] std::size_t pending_in() const { return in.size() - in_off; }
  [[nodiscard]] std::size_t pending_out() const { return out.size() - out_off; }
  [[nodiscard]] std::string_view input() const { return {in.data() + in_off, pending_in()}; }
};

enum class Got : std::uint8_t { none, line, too_long };

}  // namespace

struct Server::Impl {
  explicit Impl(ServerOptions o)
      : opt(std::move(o)), session(opt.chip, [this](const AsyncLine& l) { broadcast(l); }) {}
  ~Impl();

  void open_wake_pipe();
  void listen_tcp(const std::string& spec);
  void listen_unix(const std::string& path);
  void poll_once();
  void accept_all(int lfd, bool tcp);
  void read_client(Client& c);
  void flush(Client& c);
  void queue(Client& c, std::string_view text);
  void broadcast(const AsyncLine& l);
  Got next_line(Client& c, std::string_view& line) const;
  [[nodiscard]] bool has_work(const Client& c) const;
  void execute_round();
  void handle(Client& c, Got got, std::string_view line);
  void begin_close(Client& c, Clock::duration grace);
  void close_client(Client& c);
  void final_flush();
  [[nodiscard]] std::size_t active_clients() const;

  ServerOptions opt;
  Session session;
  int tcp_fd = -1;
  int unix_fd = -1;
  int wake_r = -1;
  int wake_w = -1;
  std::uint16_t port = 0;
  std::string unix_bound;  // unlinked at the end if it is still our socket
  dev_t unix_dev = 0;
  ino_t unix_ino = 0;
  std::vector<std::string> listening;
  std::vector<std::unique_ptr<Client>> clients;
  std::atomic<bool> stop_requested{false};
  bool shutting_down = false;
  Clock::time_point accept_paused_until{};
  Clock::time_point now = Clock::now();
};

Server::Impl::~Impl() {
  for (auto& c : clients) {
    if (c->fd >= 0) ::close(c->fd);
  }
  for (const int fd : {tcp_fd, unix_fd, wake_r, wake_w}) {
    if (fd >= 0) ::close(fd);
  }
  struct stat st {};
  if (!unix_bound.empty() && ::lstat(unix_bound.c_str(), &st) == 0 && st.st_dev == unix_dev &&
      st.st_ino == unix_ino) {
    ::unlink(unix_bound.c_str());
  }
}

void Server::Impl::open_wake_pipe() {
  int p[2];
  if (::pipe(p) != 0) throw ServerError("pipe: " + errno_text(errno));
  wake_r = p[0];
  wake_w = p[1];
  set_cloexec_nonblock(wake_r);
  set_cloexec_nonblock(wake_w);
}

void Server::Impl::listen_tcp(const std::string& spec) {
  std::string host = "127.0.0.1";
  std::string port_text = spec;
  if (!all_digits(spec)) {
    const std::size_t colon = spec.rfind(':');
    if (colon == std::string::npos) {
      throw ServerError(fmt::format("--tcp '{}': expected PORT or ADDR:PORT", spec));
    }
    host = spec.substr(0, colon);
    port_text = spec.substr(colon + 1);
    if (host.size() >= 2 && host.front() == '[' && host.back() == ']') {
      host = host.substr(1, host.size() - 2);
    }
  }
  if (host.empty() || !all_digits(port_text) || port_text.size() > 5 ||
      std::stoul(port_text) > 65535) {
    throw ServerError(fmt::format("--tcp '{}': expected PORT or ADDR:PORT, port 0..65535", spec));
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
  port = static_cast<std::uint16_t>(std::stoul(s));
  listening.push_back(ss.ss_family == AF_INET6 ? fmt::format("listening tcp [{}]:{}", h, s)
                                               : fmt::format("listening tcp {}:{}", h, s));
}

void Server::Impl::listen_unix(const std::string& path) {
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
    const int probe = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
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
  if (::bind(fd, reinterpret_cast<sockaddr*>(&sa), sizeof sa) != 0 || ::listen(fd, 64) != 0) {
    const int e = errno;
    ::close(fd);
    throw ServerError(fmt::format("cannot listen on unix {}: {}", path, errno_text(e)));
  }
  unix_fd = fd;
  set_cloexec_nonblock(unix_fd);
  if (::lstat(path.c_str(), &st) == 0) {
    unix_bound = path;
    unix_dev = st.st_dev;
    unix_ino = st.st_ino;
  }
  listening.push_back("listening unix " + path);
}

std::size_t Server::Impl::active_clients() const {
  return static_cast<std::size_t>(std::count_if(
      clients.begin(), clients.end(), [](const auto& c) { return !c->dead && !c->closing; }));
}

void Server::Impl::accept_all(int lfd, bool tcp) {
  for (;;) {
    const int fd = ::accept4(lfd, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) {
      if (errno == EINTR || errno == ECONNABORTED) continue;
      if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM) {
        accept_paused_until = now + kAcceptPause;
      }
      return;
    }
    if (shutting_down || active_clients() >= opt.max_clients) {
      const std::string msg =
          shutting_down ? "ERR busy the server is shutting down\n"
                        : fmt::format("ERR busy too many clients (at most {})\n", opt.max_clients);
      ::send(fd, msg.data(), msg.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
      auto c = std::make_unique<Client>();
      c->fd = fd;
      close_client(*c);
      continue;
    }
    if (tcp) {
      const int one = 1;
      ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    }
    auto c = std::make_unique<Client>();
    c->fd = fd;
    c->last_input = now;
    clients.push_back(std::move(c));
  }
}

void Server::Impl::read_client(Client& c) {
  if (c.in_off == c.in.size()) {
    c.in.clear();
    c.in_off = 0;
  } else if (c.in_off > kReadChunk) {
    c.in.erase(0, c.in_off);
    c.in_off = 0;
  }
  char buf[kReadChunk];
  while (c.pending_in() < opt.max_input) {
    const ssize_t n = ::recv(c.fd, buf, sizeof buf, 0);
    if (n > 0) {
      c.in.append(buf, static_cast<std::size_t>(n));
      c.last_input = now;
      continue;
    }
    if (n == 0) {
      c.eof = true;
    } else if (errno == EINTR) {
      continue;
    } else if (errno != EAGAIN && errno != EWOULDBLOCK) {
      c.dead = true;
    }
    return;
  }
}

void Server::Impl::flush(Client& c) {
  while (!c.dead && c.pending_out() > 0) {
    const ssize_t n =
        ::send(c.fd, c.out.data() + c.out_off, c.pending_out(), MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n > 0) {
      c.out_off += static_cast<std::size_t>(n);
    } else if (n < 0 && errno == EINTR) {
      continue;
    } else if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      break;
    } else {
      c.dead = true;
    }
  }
  if (c.out_off == c.out.size()) {
    c.out.clear();
    c.out_off = 0;
  } else if (c.out_off > kReadChunk) {
    c.out.erase(0, c.out_off);
    c.out_off = 0;
  }
}

void Server::Impl::queue(Client& c, std::string_view text) {
  if (c.dead) return;
  c.out.append(text);
  c.out.push_back('\n');
  // A client that does not read its replies and async lines is dropped, never waited for.
  if (c.pending_out() > opt.max_output) c.dead = true;
}

void Server::Impl::broadcast(const AsyncLine& l) {
  for (auto& c : clients) {
    if (c->dead || c->closing) continue;
    if (l.kind == AsyncLine::Kind::log && (!c->state.log_level || l.level < *c->state.log_level)) {
      continue;
    }
    queue(*c, l.text);
  }
}

Got Server::Impl::next_line(Client& c, std::string_view& line) const {
  for (;;) {
    const std::string_view in = c.input();
    if (c.discarding) {
      const std::size_t nl = in.find('\n');
      if (nl == std::string_view::npos) {
        c.in_off = c.in.size();
        return Got::none;
      }
      c.in_off += nl + 1;
      c.discarding = false;
      continue;
    }
    // A line may carry a CR before its newline on top of max_line bytes.
    const std::size_t nl = in.substr(0, opt.max_line + 2).find('\n');
    if (nl == std::string_view::npos) {
      if (in.size() > opt.max_line + 1 || (in.size() == opt.max_line + 1 && in.back() != '\r')) {
        c.discarding = true;
        c.in_off += std::min(in.size(), opt.max_line + 2);  // no newline in there
        return Got::too_long;
      }
      if (c.eof && !in.empty()) {  // an unterminated last line
        line = in;
        c.in_off = c.in.size();
        return Got::line;
      }
      return Got::none;
    }
    line = in.substr(0, nl);
    c.in_off += nl + 1;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    return line.size() > opt.max_line ? Got::too_long : Got::line;
  }
}

bool Server::Impl::has_work(const Client& c) const {
  if (c.dead || c.closing || c.pending_out() > opt.output_pause) return false;
  const std::string_view in = c.input();
  if (in.empty()) return c.eof;  // an eof to act on
  if (c.discarding || c.eof) return true;
  return in.size() > opt.max_line + 1 || in.substr(0, opt.max_line + 2).find('\n') != in.npos;
}

void Server::Impl::begin_close(Client& c, Clock::duration grace) {
  if (c.closing) return;
  c.closing = true;
  c.close_by = now + grace;
}

void Server::Impl::handle(Client& c, Got got, std::string_view line) {
  if (got == Got::too_long) {
    queue(c, fmt::format("ERR line_too_long a line has at most {} bytes; the rest up to the next "
                         "newline is discarded",
                         opt.max_line));
    return;
  }
  if (line.find_first_not_of(" \t\r") == std::string_view::npos) return;  // blank: no reply
  const Session::Result r = session.execute(line, c.state);
  queue(c, r.reply);
  if (r.action == Session::Action::quit) begin_close(c, kCloseGrace);
  if (r.action == Session::Action::shutdown) {
    shutting_down = true;
    for (auto& o : clients) {
      if (o.get() != &c && !o->closing) queue(*o, "! bye shutdown");
    }
  }
}

void Server::Impl::execute_round() {
  // Round-robin, one line per client and pass: a client flooding the server delays the others
  // by one command each round, never more.
  for (int pass = 0; pass < kMaxPasses && !shutting_down; ++pass) {
    bool any = false;
    for (std::size_t i = 0; i < clients.size() && !shutting_down; ++i) {
      Client& c = *clients[i];
      if (!has_work(c)) continue;
      std::string_view line;
      const Got got = next_line(c, line);
      if (got == Got::none) {
        if (c.eof && c.input().empty()) begin_close(c, kCloseGrace);
        continue;
      }
      any = true;
      handle(c, got, line);
    }
    if (!any) break;
  }
}

void Server::Impl::close_client(Client& c) {
  if (c.fd < 0) return;
  // Tell the peer we are done before closing, and take what it already sent, so that close()
  // does not turn into a reset that could destroy our last lines in flight.
  ::shutdown(c.fd, SHUT_WR);
  char buf[4096];
  for (int i = 0; i < 16 && ::recv(c.fd, buf, sizeof buf, MSG_DONTWAIT) > 0; ++i) {
  }
  ::close(c.fd);
  c.fd = -1;
}

void Server::Impl::poll_once() {
  now = Clock::now();
  std::vector<pollfd> fds;
  fds.push_back({wake_r, POLLIN, 0});
  const bool accepting = now >= accept_paused_until;
  const std::size_t first_listener = fds.size();
  if (accepting) {
    if (tcp_fd >= 0) fds.push_back({tcp_fd, POLLIN, 0});
    if (unix_fd >= 0) fds.push_back({unix_fd, POLLIN, 0});
  }
  const std::size_t first_client = fds.size();
  for (const auto& c : clients) {
    short ev = 0;
    if (!c->closing && !c->eof && c->pending_in() < opt.max_input) ev |= POLLIN;
    if (c->pending_out() > 0) ev |= POLLOUT;
    fds.push_back({c->fd, ev, 0});
  }

  // Sleep until input, room for output, or the next deadline.
  Clock::time_point wake = Clock::time_point::max();
  for (const auto& c : clients) {
    if (has_work(*c)) wake = now;
    if (c->closing) {
      wake = std::min(wake, c->close_by);
    } else if (opt.idle_timeout > 0) {
      wake = std::min(wake, c->last_input + std::chrono::duration_cast<Clock::duration>(
                                                std::chrono::duration<double>(opt.idle_timeout)));
    }
  }
  if (!accepting) wake = std::min(wake, accept_paused_until);
  int timeout_ms = -1;
  if (wake != Clock::time_point::max()) {
    const auto ms = std::chrono::ceil<std::chrono::milliseconds>(wake - now).count();
    timeout_ms = static_cast<int>(std::clamp<std::int64_t>(ms, 0, 60'000));
  }
  const int n = ::poll(fds.data(), fds.size(), timeout_ms);
  now = Clock::now();
  if (n < 0 && errno != EINTR) throw ServerError("poll: " + errno_text(errno));
  if (n > 0) {
    if ((fds[0].revents & POLLIN) != 0) {
      char buf[64];
      while (::read(wake_r, buf, sizeof buf) > 0) {
      }
    }
    for (std::size_t i = first_listener; i < first_client; ++i) {
      if ((fds[i].revents & POLLIN) != 0) accept_all(fds[i].fd, fds[i].fd == tcp_fd);
    }
    // Clients accepted just now are not in fds; they are polled next time.
    for (std::size_t i = first_client; i < fds.size(); ++i) {
      Client& c = *clients[i - first_client];
      const short re = fds[i].revents;
      if ((re & POLLNVAL) != 0 || (re & POLLERR) != 0) {
        c.dead = true;
        continue;
      }
      if ((re & (POLLIN | POLLHUP)) != 0) {
        if ((fds[i].events & POLLIN) != 0) {
          read_client(c);
        } else if ((re & POLLHUP) != 0) {
          c.eof = true;  // hung up while we did not read: nothing more will come
        }
      }
      if ((re & POLLOUT) != 0) flush(c);
    }
  }
  if (stop_requested.load()) {
    shutting_down = true;
    for (auto& c : clients) {
      if (!c->closing) queue(*c, "! bye shutdown");
    }
  }
  if (!shutting_down) execute_round();

  for (auto& c : clients) {
    flush(*c);
    if (!c->closing && !c->dead && opt.idle_timeout > 0 &&
        std::chrono::duration<double>(now - c->last_input).count() >= opt.idle_timeout) {
      queue(*c, "! bye idle_timeout");
      flush(*c);
      begin_close(*c, kCloseGrace);
    }
    if (c->dead || (c->closing && (c->pending_out() == 0 || now >= c->close_by))) {
      close_client(*c);
    }
  }
  std::erase_if(clients, [](const auto& c) { return c->fd < 0; });
}

void Server::Impl::final_flush() {
  const Clock::time_point until = Clock::now() + kShutdownGrace;
  for (;;) {
    std::vector<pollfd> fds;
    std::vector<Client*> who;
    for (auto& c : clients) {
      flush(*c);
      if (!c->dead && c->pending_out() > 0) {
        fds.push_back({c->fd, POLLOUT, 0});
        who.push_back(c.get());
      }
    }
    now = Clock::now();
    if (fds.empty() || now >= until) break;
    const auto ms = std::chrono::ceil<std::chrono::milliseconds>(until - now).count();
    if (::poll(fds.data(), fds.size(), static_cast<int>(ms)) < 0 && errno != EINTR) break;
  }
  for (auto& c : clients) close_client(*c);
  clients.clear();
}

Server::Server(ServerOptions opt) : impl_(std::make_unique<Impl>(std::move(opt))) {
  if (!impl_->opt.tcp && !impl_->opt.unix_path) {
    throw ServerError("nothing to listen on: give --tcp and/or --unix");
  }
  if (impl_->opt.max_clients == 0) throw ServerError("--max-clients must be at least 1");
  impl_->open_wake_pipe();
  if (impl_->opt.tcp) impl_->listen_tcp(*impl_->opt.tcp);
  if (impl_->opt.unix_path) impl_->listen_unix(*impl_->opt.unix_path);
}

Server::~Server() = default;

const std::vector<std::string>& Server::listening() const { return impl_->listening; }
std::uint16_t Server::tcp_port() const { return impl_->port; }

int Server::run() {
  while (!impl_->shutting_down) impl_->poll_once();
  impl_->final_flush();
  return 0;
}

void Server::stop() {
  impl_->stop_requested.store(true);
  const char b = 1;
  [[maybe_unused]] const ssize_t n = ::write(impl_->wake_w, &b, 1);
}

}  // namespace dpc31::serve

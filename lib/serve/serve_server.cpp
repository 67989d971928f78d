#include "serve_server.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <string_view>
#include <vector>

#include "auth.hpp"
#include "endpoints.hpp"
#include "serve_session.hpp"

namespace dpc31::serve {

namespace {

using Clock = std::chrono::steady_clock;

constexpr std::size_t kReadChunk = 16u << 10;
constexpr int kAcceptBatch = 4;                 // connections per listener per round
constexpr std::size_t kKeepBuffer = 64u << 10;  // a drained buffer keeps this capacity
constexpr std::size_t kLoneRound = 64;          // lines of a round when only one client has work
constexpr auto kCloseGrace = std::chrono::seconds(2);  // to flush the last lines of a client
constexpr auto kShutdownGrace = std::chrono::seconds(1);
constexpr auto kAcceptPause = std::chrono::milliseconds(100);  // after ENOBUFS and ENOMEM
// Descriptors kept free beyond the clients': the spare that refuses a newcomer when none is left
// (accept_some), and those `save`/`load` open for a while (directories on the way, the file).
constexpr rlim_t kReservedDescriptors = 8;
// A lone client's next line is waited for in recv() itself for up to this long, and only this
// long after poll() last looked at every socket (docs/protocol.md, "Several clients").
constexpr auto kLoneWait = std::chrono::milliseconds(1);

std::string errno_text(int e) { return std::strerror(e); }

Clock::duration seconds(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

// The first line of a connection (docs/protocol.md, "The first line"): it must start with a
// command word (`auth` only, where a secret is required), in printable ASCII. Judged on what has
// arrived so far, so that an HTTP request line, a TLS ClientHello or binary junk is refused at its
// first bytes, before any newline.
enum class Hello : std::uint8_t { more, accept, reject };

bool is_word_prefix(std::string_view partial, bool auth_only) {
  if (auth_only) return std::string_view("auth").starts_with(partial);
  for (std::size_t b = 0; b < kCommandNames.size();) {
    std::size_t e = kCommandNames.find(' ', b);
    if (e == std::string_view::npos) e = kCommandNames.size();
    if (kCommandNames.substr(b, e - b).starts_with(partial)) return true;
    b = e + 1;
  }
  return false;
}

Hello judge_hello(std::string_view line, bool complete, bool auth_only, std::size_t max_line) {
  // A CR is allowed at the end only (CR LF, or CR as the last byte so far).
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  if (line.size() > max_line) return Hello::reject;
  if (line.empty()) return complete ? Hello::reject : Hello::more;
  if (line[0] < 'a' || line[0] > 'z') return Hello::reject;
  for (const char ch : line) {
    const auto c = static_cast<unsigned char>(ch);
    if ((c < 0x20 && c != '\t') || c >= 0x7F) return Hello::reject;
  }
  const std::size_t blank = line.find_first_of(" \t");
  const std::string_view word = line.substr(0, blank);
  if (blank == std::string_view::npos && !complete) {
    return is_word_prefix(word, auth_only) ? Hello::more : Hello::reject;
  }
  if (auth_only ? word != "auth" : !is_command(word)) return Hello::reject;
  return complete ? Hello::accept : Hello::more;
}

struct Client {
  int fd = -1;
  bool tcp = false;
  bool established = false;  // its first line was accepted (and auth, where required)
  std::string in;
  std::size_t in_off = 0;
  std::string out;
  std::size_t out_off = 0;
  bool discarding = false;  // inside an over-long line: drop bytes up to the next newline
  bool eof = false;         // the peer sends no more: execute what is left, then close
  bool closing = false;     // no more input; close once the output is sent or at close_by
  bool dead = false;        // close now, unsent output is lost
  Clock::time_point accepted;
  Clock::time_point last_input;
  Clock::time_point close_by;
  Clock::time_point held_until{};  // its `auth` line waits for the peer's delay (AuthThrottle)
  std::string peer;                // who it is for AuthThrottle
  ClientState state;

  [[nodiscard]] std::size_t pending_in() const { return in.size() - in_off; }
  [[nodiscard]] std::size_t pending_out() const { return out.size() - out_off; }
  [[nodiscard]] std::string_view input() const { return {in.data() + in_off, pending_in()}; }
};

enum class Got : std::uint8_t { none, line, too_long, cut };

// A buffer read from the front up to `off`: emptied (its storage freed when it grew large), or
// its consumed front dropped once that is more than a chunk.
void compact(std::string& buf, std::size_t& off) {
  if (off == buf.size()) {
    buf.clear();
    if (buf.capacity() > kKeepBuffer) std::string().swap(buf);
    off = 0;
  } else if (off > kReadChunk) {
    buf.erase(0, off);
    off = 0;
  }
}

}  // namespace

struct Server::Impl {
  explicit Impl(ServerOptions o)
      : opt(std::move(o)), session(opt.chip, [this](const AsyncLine& l) { broadcast(l); }) {
    if (opt.cpu) session.attach_cpu(std::move(*opt.cpu));
  }
  ~Impl();

  void open_wake_pipe();
  // Makes room for --max-clients descriptors: raises the soft RLIMIT_NOFILE as far as needed and
  // the hard limit allows, else lowers max_clients to what fits, with one line on the log.
  void fit_descriptors();
  // A newcomer when no descriptor is left: the spare is given up to accept it, to tell it
  // `ERR busy` instead of leaving it unanswered in the backlog, and taken again. False if there
  // is no spare (accepting pauses then).
  bool refuse_without_descriptor(int lfd);
  void listen_tcp(const std::string& spec);
  void listen_unix(const std::string& path);
  void poll_once();
  void poll_all();
  void accept_some(int lfd, bool tcp);
  // One recv() into c.in: whether it filled the buffer, emptied the socket, found nothing, or
  // found the end (eof, or an error: dead).
  enum class Recv : std::uint8_t { full, drained, none, end };
  Recv take(Client& c, int flags);
  void read_client(Client& c);
  // A lone client, its replies sent: waits for its next bytes in recv() instead of poll() (one
  // system call less per command); whether any came. Not more than kLoneWait after a poll().
  bool read_lone();
  void check_hello(Client& c);
  void reject(Client& c, std::string_view why);
  void flush(Client& c);
  void queue(Client& c, std::string_view text);
  void broadcast(const AsyncLine& l);
  Got next_line(Client& c, std::string_view& line) const;
  [[nodiscard]] bool has_work(const Client& c) const;
  // Whether a client other than `c` has bytes waiting in its socket (a poll() that does not wait).
  bool others_readable(const Client& c);
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
  int spare_fd = -1;  // /dev/null, held for refuse_without_descriptor
  std::uint16_t port = 0;
  std::string unix_bound;  // unlinked at the end if it is still our socket
  dev_t unix_dev = 0;
  ino_t unix_ino = 0;
  std::vector<std::string> listening;
  std::vector<std::unique_ptr<Client>> clients;
  std::atomic<bool> stop_requested{false};
  bool shutting_down = false;
  Clock::time_point accept_paused_until{};
  bool unix_first = false;      // which listener is served first: alternates every round
  std::size_t round_start = 0;  // where the next round of execute_round begins
  Clock::time_point now = Clock::now();
  std::vector<pollfd> fds;            // poll_all's, kept from round to round
  std::vector<pollfd> others;         // others_readable's, kept likewise
  Clock::time_point last_poll = now;  // when poll() last looked at every socket
  AuthThrottle throttle;
};

Server::Impl::~Impl() {
  for (auto& c : clients) {
    if (c->fd >= 0) ::close(c->fd);
  }
  for (const int fd : {tcp_fd, unix_fd, wake_r, wake_w, spare_fd}) {
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

void Server::Impl::fit_descriptors() {
  spare_fd = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
  rlim_t open_now = 0;  // this process's descriptors now, counted in /proc/self/fd
  if (DIR* d = ::opendir("/proc/self/fd")) {
    while (const dirent* e = ::readdir(d)) open_now += e->d_name[0] != '.' ? 1 : 0;
    ::closedir(d);
    --open_now;  // the directory's own
  }
  rlimit lim{};
  if (::getrlimit(RLIMIT_NOFILE, &lim) != 0) return;
  const rlim_t needed = open_now + opt.max_clients + kReservedDescriptors;
  if (lim.rlim_cur != RLIM_INFINITY && lim.rlim_cur < needed) {
    rlimit raised = lim;
    raised.rlim_cur = lim.rlim_max == RLIM_INFINITY ? needed : std::min(needed, lim.rlim_max);
    if (::setrlimit(RLIMIT_NOFILE, &raised) == 0) lim = raised;
  }
  if (lim.rlim_cur == RLIM_INFINITY || lim.rlim_cur >= needed) return;
  const rlim_t room = lim.rlim_cur > open_now + kReservedDescriptors
                          ? lim.rlim_cur - open_now - kReservedDescriptors
                          : 0;
  if (room == 0) {
    throw ServerError(
        fmt::format("no descriptor left for a client: {} open, the limit is {} "
                    "(ulimit -n), {} are kept for refusing clients and snapshots",
                    open_now, lim.rlim_cur, kReservedDescriptors));
  }
  if (opt.log != nullptr) {
    fmt::print(opt.log,
               "dpc31 serve: --max-clients {}: the descriptor limit is {} (ulimit -n, hard limit "
               "{}) and {} are in use or kept: at most {} clients\n",
               opt.max_clients, lim.rlim_cur, lim.rlim_max, open_now + kReservedDescriptors, room);
    std::fflush(opt.log);
  }
  opt.max_clients = static_cast<std::size_t>(room);
}

bool Server::Impl::refuse_without_descriptor(int lfd) {
  if (spare_fd < 0) return false;
  ::close(spare_fd);
  const int fd = ::accept4(lfd, nullptr, nullptr, SOCK_CLOEXEC);
  if (fd >= 0) {
    constexpr std::string_view kMsg = "ERR busy the server has no descriptor left for a client\n";
    ::send(fd, kMsg.data(), kMsg.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
    Client c;
    c.fd = fd;
    close_client(c);
  }
  spare_fd = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
  return true;
}

void Server::Impl::listen_tcp(const std::string& spec) {
  Endpoint e = open_tcp(spec);
  tcp_fd = e.fd;
  port = e.port;
  // Other hosts reach it, and nothing asks them who they are (docs/protocol.md, "Threat model").
  if (!e.loopback && !opt.secret && opt.log != nullptr) {
    fmt::print(opt.log,
               "dpc31 serve: warning: {} is not a loopback address and there is no "
               "--secret-file: every host that reaches it is a full client\n",
               e.line.substr(e.line.find("tcp ")));
    std::fflush(opt.log);
  }
  listening.push_back(std::move(e.line));
}

void Server::Impl::listen_unix(const std::string& path) {
  Endpoint e = open_unix(path);
  unix_fd = e.fd;
  unix_bound = std::move(e.unix_path);
  unix_dev = e.dev;
  unix_ino = e.ino;
  listening.push_back(std::move(e.line));
}

std::size_t Server::Impl::active_clients() const {
  return static_cast<std::size_t>(std::count_if(
      clients.begin(), clients.end(), [](const auto& c) { return !c->dead && !c->closing; }));
}

void Server::Impl::accept_some(int lfd, bool tcp) {
  // A few per round and listener: a connection flood on one listener neither starves the other
  // nor the clients.
  for (int i = 0; i < kAcceptBatch; ++i) {
    // Blocking, but every recv() and send() says MSG_DONTWAIT, except read_lone's, which
    // SO_RCVTIMEO bounds.
    sockaddr_storage from{};
    socklen_t from_len = sizeof from;
    const int fd = ::accept4(lfd, reinterpret_cast<sockaddr*>(&from), &from_len, SOCK_CLOEXEC);
    if (fd < 0) {
      if (errno == EINTR || errno == ECONNABORTED) continue;
      if ((errno == EMFILE || errno == ENFILE) && refuse_without_descriptor(lfd)) continue;
      if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM) {
        accept_paused_until = now + kAcceptPause;
      }
      return;
    }
    bool refuse = shutting_down;
    if (!refuse && active_clients() >= opt.max_clients) {
      // Full. A connection that has not sent its first line yet gives way to the newcomer (the
      // oldest one): silent or unauthenticated connections cannot lock the others out. It is
      // told why, as a first line too late is (docs/protocol.md).
      Client* oldest = nullptr;
      for (auto& o : clients) {
        if (!o->established && !o->dead && !o->closing &&
            (oldest == nullptr || o->accepted < oldest->accepted)) {
          oldest = o.get();
        }
      }
      if (oldest != nullptr) {
        reject(*oldest, "! bye max_clients");
      } else {
        refuse = true;
      }
    }
    if (refuse) {
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
    const timeval wait{0, std::chrono::microseconds(kLoneWait).count()};
    ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &wait, sizeof wait);
    auto c = std::make_unique<Client>();
    c->fd = fd;
    c->tcp = tcp;
    c->peer = tcp ? peer_of(from) : "the unix socket";
    c->accepted = now;
    c->last_input = now;
    clients.push_back(std::move(c));
  }
}

void Server::Impl::reject(Client& c, std::string_view why) {
  // Nothing it sent is executed; what it sends from now on is not read.
  c.in.clear();
  c.in_off = 0;
  c.discarding = false;
  queue(c, why);
  begin_close(c, kCloseGrace);
}

void Server::Impl::check_hello(Client& c) {
  const std::string_view in = c.input();
  const std::size_t nl = in.find('\n');
  const bool complete = nl != std::string_view::npos || (c.eof && !in.empty());
  const std::string_view line = in.substr(0, nl);
  const bool auth_required = opt.secret.has_value() && c.tcp;
  if (in.empty()) {
    if (c.eof) begin_close(c, kCloseGrace);
    return;
  }
  switch (judge_hello(line, complete, auth_required, opt.max_line)) {
    case Hello::more:
      return;
    case Hello::reject:
      reject(c,
             auth_required
                 ? "ERR protocol the first line must be 'auth SECRET' (docs/protocol.md); closing"
                 : "ERR protocol the first line must be a dpc31 serve command "
                   "(docs/protocol.md); closing");
      return;
    case Hello::accept:
      break;
  }
  std::string_view l = line;
  if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
  const std::size_t blank = l.find_first_of(" \t");
  if (l.substr(0, blank) != "auth") {
    c.established = true;  // the line stays: it is executed in its turn
    return;
  }
  // `auth SECRET`: taken here, never by the interpreter.
  std::vector<std::string_view> words;
  for (std::size_t i = 0; i < l.size();) {
    while (i < l.size() && (l[i] == ' ' || l[i] == '\t')) ++i;
    const std::size_t b = i;
    while (i < l.size() && l[i] != ' ' && l[i] != '\t') ++i;
    if (i > b) words.push_back(l.substr(b, i - b));
  }
  if (opt.secret) {
    // A peer that sent wrong secrets waits before its next one is looked at, on every
    // connection it has: guessing is slowed to one guess per delay (docs/security.md).
    const Clock::time_point ready = throttle.ready_at(c.peer, now);
    if (ready > now) {
      c.held_until = ready;
      // A guess nobody waits for the answer to is dropped unjudged.
      if (c.eof) begin_close(c, kCloseGrace);
      return;
    }
  }
  c.held_until = {};
  c.in_off += nl == std::string_view::npos ? in.size() : nl + 1;
  if (!opt.secret) {
    c.established = true;
    queue(c, "OK auth not required");
    return;
  }
  if (words.size() != 2 || !same_secret(words[1], *opt.secret)) {
    Clock::duration delay{};
    const std::uint64_t n = throttle.failed(c.peer, now, delay);
    if (opt.log != nullptr) {
      fmt::print(opt.log,
                 "dpc31 serve: a wrong secret from {} ({} in a row); its next 'auth' is looked "
                 "at in {} ms\n",
                 c.peer, n, std::chrono::duration_cast<std::chrono::milliseconds>(delay).count());
      std::fflush(opt.log);
    }
    reject(c, "ERR auth wrong secret; closing");
    return;
  }
  throttle.succeeded(c.peer);
  c.established = true;
  queue(c, "OK auth");
}

Server::Impl::Recv Server::Impl::take(Client& c, int flags) {
  char buf[kReadChunk];
  const ssize_t n = ::recv(c.fd, buf, sizeof buf, flags);
  if (n > 0) {
    c.in.append(buf, static_cast<std::size_t>(n));
    c.last_input = now;
    return static_cast<std::size_t>(n) < sizeof buf ? Recv::drained : Recv::full;
  }
  if (n == 0) {
    c.eof = true;
  } else if (errno == EINTR || errno == EAGAIN || errno == EWOULDBLOCK) {
    return Recv::none;
  } else {
    c.dead = true;
  }
  return Recv::end;
}

void Server::Impl::read_client(Client& c) {
  compact(c.in, c.in_off);
  // A short read emptied the socket; what arrives later, the next poll() reports. Not reading
  // again until EAGAIN saves a system call per round (docs/protocol.md, "Several clients").
  while (c.pending_in() < opt.max_input && take(c, MSG_DONTWAIT) == Recv::full) {
  }
  if (!c.established && !c.dead && !c.closing) check_hello(c);
}

bool Server::Impl::read_lone() {
  if (clients.size() != 1 || shutting_down || now - last_poll >= kLoneWait) return false;
  Client& c = *clients.front();
  if (!c.established || c.dead || c.closing || c.eof || c.pending_out() > 0 ||
      c.pending_in() >= opt.max_input || has_work(c)) {
    return false;
  }
  compact(c.in, c.in_off);
  const Recv r = take(c, 0);  // blocks for up to kLoneWait (SO_RCVTIMEO)
  now = Clock::now();
  return r != Recv::none;
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
  compact(c.out, c.out_off);
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
    if (c->dead || c->closing || !c->established) continue;  // nothing for strangers
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
      if (c.eof && !in.empty()) {  // a last line without its newline: cut off, not run
        c.in_off = c.in.size();
        return Got::cut;
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
  if (!c.established || c.dead || c.closing || c.pending_out() > opt.output_pause) return false;
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
  if (got == Got::cut) {
    // "step 1000" cut to "step 10" would run (docs/protocol.md, "Lines").
    queue(c, "ERR syntax the last line has no newline: cut off, not executed");
    return;
  }
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
      if (o.get() != &c && !o->closing && o->established) queue(*o, "! bye shutdown");
    }
  }
}

void Server::Impl::execute_round() {
  // One line per client and round, round robin, then back to poll() for what arrived meanwhile:
  // a command that has arrived waits for the rest of the round in progress and at most one line
  // of every other client in the next (2 x (clients - 1) lines; docs/protocol.md, "Several
  // clients"). The round starts one client further each time.
  const std::size_t n = clients.size();
  Client* only = nullptr;  // the one client that executed a line, if it was one
  std::size_t busy = 0;
  for (std::size_t k = 0; k < n && !shutting_down; ++k) {
    Client& c = *clients[(round_start + k) % n];
    if (!has_work(c)) continue;
    std::string_view line;
    const Got got = next_line(c, line);
    if (got == Got::none) {
      if (c.eof && c.input().empty()) begin_close(c, kCloseGrace);
      continue;
    }
    handle(c, got, line);
    only = &c;
    ++busy;
  }
  round_start = n == 0 ? 0 : (round_start + 1) % n;
  // A lone pipelining client: nobody else had a line this round, so it runs on, up to kLoneRound
  // lines in all, before its replies go out and poll() looks again (a poll() and a send() per
  // line were most of the cost of a pipelined `peek`). A command of another client that arrives
  // meanwhile waits for at most these lines (docs/protocol.md, "Several clients").
  // Not while another client has bytes waiting (its line might not be complete in our buffer
  // yet, a flood's read ended short): a flood stays one line per client and round.
  if (busy != 1 || (n > 1 && others_readable(*only))) return;
  for (std::size_t k = 1; k < kLoneRound && !shutting_down && has_work(*only); ++k) {
    std::string_view line;
    const Got got = next_line(*only, line);
    if (got == Got::none) break;
    handle(*only, got, line);
  }
}

bool Server::Impl::others_readable(const Client& c) {
  others.clear();
  for (const auto& o : clients) {
    if (o.get() != &c && o->fd >= 0 && !o->dead && !o->eof) others.push_back({o->fd, POLLIN, 0});
  }
  if (others.empty()) return false;
  int r = 0;
  do {
    r = ::poll(others.data(), others.size(), 0);
  } while (r < 0 && errno == EINTR);
  return r != 0;  // an error: as if readable, the fair way
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

void Server::Impl::poll_all() {
  fds.clear();
  fds.push_back({wake_r, POLLIN, 0});
  const bool accepting = now >= accept_paused_until;
  const std::size_t first_listener = fds.size();
  if (accepting) {
    unix_first = !unix_first;
    for (const int lfd : unix_first ? std::array{unix_fd, tcp_fd} : std::array{tcp_fd, unix_fd}) {
      if (lfd >= 0) fds.push_back({lfd, POLLIN, 0});
    }
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
    } else if (!c->established) {
      wake = std::min(wake, c->accepted + seconds(opt.hello_timeout));
      if (c->held_until != Clock::time_point{}) wake = std::min(wake, c->held_until);
    } else if (opt.idle_timeout > 0) {
      wake = std::min(wake, c->last_input + seconds(opt.idle_timeout));
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
  last_poll = now;
  if (n < 0 && errno != EINTR) throw ServerError("poll: " + errno_text(errno));
  if (n > 0) {
    if ((fds[0].revents & POLLIN) != 0) {
      char buf[64];
      while (::read(wake_r, buf, sizeof buf) > 0) {
      }
    }
    // Clients first, then the listeners: a newcomer whose first line has arrived is established
    // before another connection could take its place (accept_some).
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
    // Clients accepted now are not in fds; they are polled next time.
    for (std::size_t i = first_listener; i < first_client; ++i) {
      if ((fds[i].revents & POLLIN) != 0) accept_some(fds[i].fd, fds[i].fd == tcp_fd);
    }
  }
}

void Server::Impl::poll_once() {
  now = Clock::now();
  if (!read_lone()) poll_all();
  if (stop_requested.load()) {
    shutting_down = true;
    for (auto& c : clients) {
      if (!c->closing && c->established) queue(*c, "! bye shutdown");
    }
  }
  if (!shutting_down) execute_round();

  for (auto& c : clients) {
    if (!c->closing && !c->dead && !c->established && c->held_until != Clock::time_point{} &&
        now >= c->held_until) {
      check_hello(*c);
    }
    flush(*c);
    if (!c->closing && !c->dead && !c->established &&
        std::chrono::duration<double>(now - c->accepted).count() >= opt.hello_timeout) {
      reject(*c, "! bye hello_timeout");  // no first line in time
      flush(*c);
    } else if (!c->closing && !c->dead && c->established && opt.idle_timeout > 0 &&
               std::chrono::duration<double>(now - c->last_input).count() >= opt.idle_timeout) {
      queue(*c, "! bye idle_timeout");
      flush(*c);
      begin_close(*c, kCloseGrace);
    }
    if (c->dead || (c->closing && (c->pending_out() == 0 || now >= c->close_by))) {
      close_client(*c);
    }
  }
  std::erase_if(clients, [this](const auto& c) {
    if (c->fd >= 0) return false;
    session.leave(c->state);
    return true;
  });
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
  if (!(impl_->opt.hello_timeout >= kMinTimeout)) {
    throw ServerError(fmt::format("the first-line timeout must be at least {} s", kMinTimeout));
  }
  if (impl_->opt.idle_timeout != 0 && !(impl_->opt.idle_timeout >= kMinTimeout)) {
    throw ServerError(fmt::format("--idle-timeout {}: 0 (never) or at least {} s",
                                  impl_->opt.idle_timeout, kMinTimeout));
  }
  if (impl_->opt.idle_timeout > 0) {
    impl_->opt.hello_timeout = std::min(impl_->opt.hello_timeout, impl_->opt.idle_timeout);
  }
  if (impl_->opt.secret && impl_->opt.secret->empty()) throw ServerError("an empty secret");
  if (impl_->opt.state_dir) {
    try {
      impl_->session.set_state_dir(StateDir(*impl_->opt.state_dir));
    } catch (const std::runtime_error& e) {
      throw ServerError(e.what());
    }
  }
  impl_->open_wake_pipe();
  if (impl_->opt.tcp) impl_->listen_tcp(*impl_->opt.tcp);
  if (impl_->opt.unix_path) impl_->listen_unix(*impl_->opt.unix_path);
  impl_->fit_descriptors();
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

// `dpc31 serve` round trips (docs/protocol.md): a client sends `peek 0` and waits for its reply,
// over loopback TCP and a Unix socket, against the server running on a thread of this process.
// Items per second = commands per second; Arg 1: one command in flight, Arg 64: 64 pipelined on
// the connection. server_ns_per_cmd is the server thread's own CPU time per command (its thread
// CPU clock), host_ns_per_cmd the rest of the wall time per command: the client, the kernel's
// socket path and the wake-ups of both threads. The in-process interpreter alone gives the floor.
// BM_SocketFlood: the same round trips while 13 other clients pipeline as fast as they can; its
// p99 is the scheduler's bound in wall time (docs/protocol.md, "Several clients").
#include <benchmark/benchmark.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <pthread.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "bench_options.hpp"
#include "cleanup.hpp"
#include "serve_server.hpp"
#include "serve_session.hpp"

namespace {

// The server on its own thread for the lifetime of one benchmark.
class ServerThread {
 public:
  explicit ServerThread(dpc31::serve::ServerOptions opt)
      : server_(std::move(opt)), thread_([this] { server_.run(); }) {}
  ~ServerThread() {
    server_.stop();
    thread_.join();
  }
  ServerThread(const ServerThread&) = delete;
  ServerThread& operator=(const ServerThread&) = delete;
  [[nodiscard]] std::uint16_t port() const { return server_.tcp_port(); }
  // The server thread's CPU time so far.
  [[nodiscard]] double cpu_ns() {
    clockid_t id{};
    timespec ts{};
    if (::pthread_getcpuclockid(thread_.native_handle(), &id) != 0 ||
        ::clock_gettime(id, &ts) != 0) {
      std::abort();
    }
    return static_cast<double>(ts.tv_sec) * 1e9 + static_cast<double>(ts.tv_nsec);
  }

 private:
  dpc31::serve::Server server_;
  std::thread thread_;
};

int connect_tcp(std::uint16_t port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in sa{};
  sa.sin_family = AF_INET;
  sa.sin_port = htons(port);
  sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&sa), sizeof sa) != 0) std::abort();
  const int one = 1;
  ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  return fd;
}

int connect_unix(const std::string& path) {
  const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
  sockaddr_un sa{};
  sa.sun_family = AF_UNIX;
  std::strncpy(sa.sun_path, path.c_str(), sizeof sa.sun_path - 1);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&sa), sizeof sa) != 0) std::abort();
  return fd;
}

// Sends `batch` `peek 0` lines at once and reads as many replies.
void round_trips(benchmark::State& st, ServerThread& server, int fd, int batch) {
  std::string req;
  for (int i = 0; i < batch; ++i) req += "peek 0\n";
  char buf[65536];
  const double cpu_before = server.cpu_ns();
  const auto t_begin = std::chrono::steady_clock::now();
  for (auto _ : st) {
    if (::send(fd, req.data(), req.size(), 0) != static_cast<ssize_t>(req.size())) std::abort();
    int replies = 0;
    while (replies < batch) {
      const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
      if (n <= 0) std::abort();
      for (ssize_t i = 0; i < n; ++i) replies += buf[i] == '\n' ? 1 : 0;
    }
  }
  const double wall_ns =
      std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t_begin).count();
  const double commands = static_cast<double>(st.iterations()) * batch;
  const double server_ns = (server.cpu_ns() - cpu_before) / commands;
  st.SetItemsProcessed(st.iterations() * batch);
  st.counters["server_ns_per_cmd"] = server_ns;
  st.counters["host_ns_per_cmd"] = wall_ns / commands - server_ns;
  ::close(fd);
}

void BM_SocketPeekTcp(benchmark::State& st) {
  dpc31::serve::ServerOptions opt;
  opt.tcp = "0";
  ServerThread s(opt);
  round_trips(st, s, connect_tcp(s.port()), static_cast<int>(st.range(0)));
}
BENCHMARK(BM_SocketPeekTcp)->Arg(1)->Arg(64)->UseRealTime();

// The socket in TMPDIR (under `dpc31 bench` its private directory) if its path fits a socket
// address, else in /tmp; removed if a signal ends the run.
std::string unix_socket_path() {
  const std::string name = "dpc31-bench-" + std::to_string(::getpid()) + ".sock";
  const std::string in_tmpdir = (std::filesystem::temp_directory_path() / name).string();
  return in_tmpdir.size() < sizeof(sockaddr_un::sun_path) ? in_tmpdir : "/tmp/" + name;
}

void BM_SocketPeekUnix(benchmark::State& st) {
  const std::string path = unix_socket_path();
  const dpc31::cleanup::Entry gone = dpc31::cleanup::Entry::path(path);
  dpc31::serve::ServerOptions opt;
  opt.unix_path = path;
  ServerThread s(opt);
  dpc31::bench::files_made();
  round_trips(st, s, connect_unix(path), static_cast<int>(st.range(0)));
}
BENCHMARK(BM_SocketPeekUnix)->Arg(1)->Arg(64)->UseRealTime();

// Clients that keep their pipelines full of `peek 0` lines and read every reply, on one thread.
class Flood {
 public:
  Flood(std::uint16_t port, int clients) {
    for (int i = 0; i < clients; ++i) {
      const int fd = connect_tcp(port);
      // The first line (docs/protocol.md): a command, then the flood.
      if (::send(fd, "ping\n", 5, 0) != 5) std::abort();
      fds_.push_back(fd);
    }
    thread_ = std::thread([this] { run(); });
  }
  ~Flood() {
    stop_ = true;
    thread_.join();
    for (const int fd : fds_) ::close(fd);
  }
  Flood(const Flood&) = delete;
  Flood& operator=(const Flood&) = delete;
  [[nodiscard]] std::uint64_t replies() const { return replies_.load(); }

 private:
  void run() {
    std::string chunk;
    for (int i = 0; i < 512; ++i) chunk += "peek 0\n";
    const std::size_t line = 7;
    std::vector<std::size_t> pos(fds_.size(), 0);  // where in the endless line stream each is
    std::vector<pollfd> p;
    for (const int fd : fds_) p.push_back({fd, POLLIN | POLLOUT, 0});
    char buf[65536];
    while (!stop_.load(std::memory_order_relaxed)) {
      if (::poll(p.data(), p.size(), 10) <= 0) continue;
      for (std::size_t i = 0; i < p.size(); ++i) {
        if ((p[i].revents & POLLIN) != 0) {
          const ssize_t n = ::recv(p[i].fd, buf, sizeof buf, MSG_DONTWAIT);
          if (n > 0) {
            replies_ += static_cast<std::uint64_t>(std::count(buf, buf + n, '\n'));
          }
        }
        if ((p[i].revents & POLLOUT) != 0) {
          const std::size_t off = pos[i] % line;
          const ssize_t n =
              ::send(p[i].fd, chunk.data() + off, chunk.size() - off, MSG_DONTWAIT | MSG_NOSIGNAL);
          if (n > 0) pos[i] += static_cast<std::size_t>(n);
        }
      }
    }
  }

  std::vector<int> fds_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> replies_{0};
};

// One client's `peek 0` round trips while 13 others pipeline (the 14 of the finding:
// p99 363 ms when the server ran up to 64 lines per client and round). Counters: percentiles of
// the round trip in microseconds, and the flood's commands per second.
void BM_SocketFlood(benchmark::State& st) {
  dpc31::serve::ServerOptions opt;
  opt.tcp = "0";
  ServerThread s(opt);
  const int fd = connect_tcp(s.port());
  Flood flood(s.port(), static_cast<int>(st.range(0)));
  std::this_thread::sleep_for(std::chrono::milliseconds(20));  // the flood under way
  std::vector<double> us;
  char buf[256];
  const std::uint64_t flood_before = flood.replies();
  const auto t_begin = std::chrono::steady_clock::now();
  for (auto _ : st) {
    const auto t0 = std::chrono::steady_clock::now();
    if (::send(fd, "peek 0\n", 7, 0) != 7) std::abort();
    for (bool done = false; !done;) {
      const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
      if (n <= 0) std::abort();
      done = buf[n - 1] == '\n';
    }
    us.push_back(
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
  }
  const double secs =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t_begin).count();
  const std::uint64_t flood_replies = flood.replies() - flood_before;
  ::close(fd);
  std::sort(us.begin(), us.end());
  const auto pct = [&us](double p) {
    return us.empty() ? 0.0 : us[std::min(us.size() - 1, static_cast<std::size_t>(p * us.size()))];
  };
  st.counters["p50_us"] = pct(0.50);
  st.counters["p99_us"] = pct(0.99);
  st.counters["max_us"] = us.empty() ? 0.0 : us.back();
  st.counters["flood_per_s"] = secs > 0 ? static_cast<double>(flood_replies) / secs : 0;
  st.SetItemsProcessed(st.iterations());
}
BENCHMARK(BM_SocketFlood)->Arg(13)->UseRealTime();

// The interpreter without sockets: parse, peek, format.
void BM_SessionPeek(benchmark::State& st) {
  dpc31::serve::Session s({}, nullptr);
  dpc31::serve::ClientState c;
  for (auto _ : st) benchmark::DoNotOptimize(s.execute("peek 0", c));
  st.SetItemsProcessed(st.iterations());
}
BENCHMARK(BM_SessionPeek);

}  // namespace

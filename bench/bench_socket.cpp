// `dpc31 serve` round trips (docs/protocol.md): a client sends `peek 0` and waits for its reply,
// over loopback TCP and a Unix socket, against the server running on a thread of this process.
// Items per second = commands per second. The in-process interpreter alone gives the floor.
#include <benchmark/benchmark.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <thread>

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
void round_trips(benchmark::State& st, int fd, int batch) {
  std::string req;
  for (int i = 0; i < batch; ++i) req += "peek 0\n";
  char buf[65536];
  for (auto _ : st) {
    if (::send(fd, req.data(), req.size(), 0) != static_cast<ssize_t>(req.size())) std::abort();
    int replies = 0;
    while (replies < batch) {
      const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
      if (n <= 0) std::abort();
      for (ssize_t i = 0; i < n; ++i) replies += buf[i] == '\n' ? 1 : 0;
    }
  }
  st.SetItemsProcessed(st.iterations() * batch);
  ::close(fd);
}

void BM_SocketPeekTcp(benchmark::State& st) {
  dpc31::serve::ServerOptions opt;
  opt.tcp = "0";
  ServerThread s(opt);
  round_trips(st, connect_tcp(s.port()), static_cast<int>(st.range(0)));
}
BENCHMARK(BM_SocketPeekTcp)->Arg(1)->Arg(64)->UseRealTime();

void BM_SocketPeekUnix(benchmark::State& st) {
  const std::string path = "/tmp/dpc31-bench-" + std::to_string(::getpid()) + ".sock";
  dpc31::serve::ServerOptions opt;
  opt.unix_path = path;
  ServerThread s(opt);
  round_trips(st, connect_unix(path), static_cast<int>(st.range(0)));
}
BENCHMARK(BM_SocketPeekUnix)->Arg(1)->Arg(64)->UseRealTime();

// The interpreter without sockets: parse, peek, format.
void BM_SessionPeek(benchmark::State& st) {
  dpc31::serve::Session s({}, nullptr);
  dpc31::serve::ClientState c;
  for (auto _ : st) benchmark::DoNotOptimize(s.execute("peek 0", c));
  st.SetItemsProcessed(st.iterations());
}
BENCHMARK(BM_SessionPeek);

}  // namespace

// `dpc31 serve` against an attacker and a careless client (docs/security.md): file commands
// confined to the state directory, a first line that is not the protocol, the shared secret, the
// Unix socket's mode, bounded queues and buffers, idle connections, and the fair scheduler. The
// real binary as a child process, driven by tests/serve_client.hpp.
#include <arpa/inet.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "run_command.hpp"
#include "serve_client.hpp"
#include "serve_server.hpp"
#include "serve_session.hpp"
#include "test_files.hpp"

using namespace testutil;  // the server process, line client, temporary directory

namespace {

const std::string kCli = DPC31_CLI;

// --- confinement, first line, authentication, resources (docs/security.md) -------------------

// RSS figures mean nothing under AddressSanitizer (its allocator keeps freed memory in
// quarantine): the memory checks are made in the normal build only.
#if defined(__SANITIZE_ADDRESS__)
constexpr bool kRssMeaningful = false;
#else
constexpr bool kRssMeaningful = true;
#endif

// The resident set of a process, in KiB (/proc/PID/status).
std::size_t rss_kib(pid_t pid) {
  std::ifstream f(fmt::format("/proc/{}/status", pid));
  for (std::string line; std::getline(f, line);) {
    if (starts_with(line, "VmRSS:")) return std::stoul(line.substr(6));
  }
  throw std::runtime_error("no VmRSS");
}

// The state letter of /proc/PID/stat ('T' stopped, 'S' sleeping, 'R' running).
char proc_state(pid_t pid) {
  std::ifstream f(fmt::format("/proc/{}/stat", pid));
  std::string all;
  std::getline(f, all);
  const std::size_t paren = all.rfind(')');
  return paren != std::string::npos && paren + 2 < all.size() ? all[paren + 2] : '?';
}

// SIGSTOP until the process really is stopped, SIGCONT on destruction: what a test sends while
// the server is stopped is all there when it looks next.
class Frozen {
 public:
  explicit Frozen(pid_t pid) : pid_(pid) {
    ::kill(pid_, SIGSTOP);
    for (int i = 0; i < 2000 && proc_state(pid_) != 'T'; ++i) {
      std::this_thread::sleep_for(std::chrono::microseconds(500));
    }
    if (proc_state(pid_) != 'T') throw std::runtime_error("the server did not stop");
    // Loopback segments already sent by the server are delivered by the kernel meanwhile.
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ~Frozen() { ::kill(pid_, SIGCONT); }
  Frozen(const Frozen&) = delete;
  Frozen& operator=(const Frozen&) = delete;

 private:
  pid_t pid_;
};

TEST(ServeSecurity, FileCommandsAreRefusedWithoutAStateDir) {
  TempDir dir;
  ServerProcess server(kCli, {"--unix", dir.file("s")});
  LineClient c = LineClient::unix_socket(dir.file("s"));
  const std::string name = fmt::format("dpc31-serve-test-{}.snap", ::getpid());
  const std::string denied =
      "ERR denied file commands are disabled: the server was started without --state-dir";
  EXPECT_EQ(c.command("save " + name), denied);
  EXPECT_EQ(c.command("save " + dir.file("x")), denied);
  EXPECT_EQ(c.command("load " + name), denied);
  EXPECT_EQ(c.command("load /etc/passwd"), denied);
  EXPECT_FALSE(std::filesystem::exists(name));  // not in the server's working directory either
  EXPECT_EQ(dir.tree(), std::vector<std::string>{"s"});
}

// save/load stay inside --state-dir: no '..', no absolute name, no symlink (as the file or as a
// directory on the way), no FIFO, device or directory; nothing is written outside, and the
// replies do not tell what exists outside.
TEST(ServeSecurity, SaveAndLoadStayInsideTheStateDir) {
  TempDir root;
  const std::string state = root.file("state");
  const std::string outside = root.file("outside");
  std::filesystem::create_directory(state);
  std::filesystem::create_directory(outside);
  {
    std::ofstream f(outside + "/target");
    f << "keep\n";
  }
  std::filesystem::create_symlink("../outside/target", state + "/link");
  std::filesystem::create_directory_symlink("../outside", state + "/dirlink");
  std::filesystem::create_directory(state + "/sub");
  ASSERT_EQ(::mkfifo((state + "/fifo").c_str(), 0600), 0);
  const std::vector<std::string> before = root.tree();

  ServerProcess server(kCli, {"--tcp", "0", "--state-dir", state});
  LineClient c = LineClient::tcp(server.port());
  ASSERT_EQ(c.command("poke 0x900 0x5A"), "OK");
  const auto denied = [&](const std::string& line) {
    const std::string r = c.command(line);
    EXPECT_TRUE(starts_with(r, "ERR denied ")) << line << " -> " << r;
    return r;
  };
  // The form of the name, before anything is looked up.
  for (const std::string cmd : {"save", "load"}) {
    EXPECT_EQ(c.command(cmd + " ../x"),
              "ERR denied ../x: '..' is not allowed (names stay inside the state directory)");
    EXPECT_EQ(c.command(cmd + " sub/../../x"),
              "ERR denied sub/../../x: '..' is not allowed (names stay inside the state "
              "directory)");
    EXPECT_EQ(c.command(cmd + " " + outside + "/x"),
              fmt::format("ERR denied {}/x: absolute names are not allowed (names are relative "
                          "to the state directory)",
                          outside));
    denied(cmd + " ./x");
    denied(cmd + " sub//x");
    denied(cmd + " sub/");
    denied(cmd + " " + std::string(256, 'n'));
    // Links are not followed, as the file or on the way.
    EXPECT_EQ(c.command(cmd + " link"),
              "ERR denied link: link is a symbolic link (links are not followed)");
    EXPECT_EQ(c.command(cmd + " dirlink/target"),
              "ERR denied dirlink/target: dirlink is a symbolic link (links are not followed)");
    EXPECT_EQ(c.command(cmd + " dirlink/new"),
              "ERR denied dirlink/new: dirlink is a symbolic link (links are not followed)");
    // Regular files only: a FIFO neither blocks nor is replaced; a directory is not replaced.
    EXPECT_EQ(c.command(cmd + " fifo", 2000), "ERR denied fifo: not a regular file");
    EXPECT_EQ(c.command(cmd + " sub"), "ERR denied sub: not a regular file");
  }
  // Whether something exists outside makes no difference to the reply.
  const std::string existing = c.command("load ../outside/target");
  const std::string missing = c.command("load ../outside/nothere");
  EXPECT_EQ(existing.substr(0, existing.find(':')), "ERR denied ../outside/target");
  EXPECT_EQ(existing.substr(existing.find(':')), missing.substr(missing.find(':')));
  const auto why = [](const std::string& r) { return r.substr(r.find(": ")); };
  EXPECT_EQ(why(c.command("load /etc/passwd")), why(c.command("load /nonexistent/file")));
  EXPECT_EQ(why(c.command("load ../../../../../../etc/passwd")),
            why(c.command("load ../../../../../../nonexistent")));

  EXPECT_EQ(c.command("peek 0x900"), "OK 0x5a");  // nothing was loaded
  EXPECT_EQ(c.command("ping"), "OK pong");        // and the server never blocked
  EXPECT_EQ(root.tree(), before);                 // nothing written, nothing replaced
  EXPECT_EQ(slurp(outside + "/target"), "keep\n");
  EXPECT_TRUE(std::filesystem::is_symlink(state + "/link"));
  EXPECT_TRUE(std::filesystem::is_fifo(state + "/fifo"));
  // Inside, it works.
  EXPECT_EQ(c.command("save sub/ok.snap"), "OK 0");
  EXPECT_EQ(c.command("load sub/ok.snap"), "OK 0");
}

// A web page can make a browser POST to the server's port: the request line already closes the
// connection, and the body's commands are never executed.
TEST(ServeSecurity, HttpPostIsDisconnectedUnexecuted) {
  TempDir dir;
  const std::string state = dir.file("state");
  std::filesystem::create_directory(state);
  ServerProcess server(kCli, {"--tcp", "0", "--unix", dir.file("s"), "--state-dir", state});
  LineClient watcher = LineClient::unix_socket(dir.file("s"));
  ASSERT_EQ(watcher.command("ping"), "OK pong");
  const std::string body = "poke 0x900 0x66\nsave pwned\nshutdown\n";
  const std::vector<std::string> attacks = {
      "POST / HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: text/plain\r\nContent-Length: " +
          std::to_string(body.size()) + "\r\n\r\n" + body,
      "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n",
      "OPTIONS * HTTP/1.1\r\n\r\n" + body,
      "post / HTTP/1.1\r\n\r\n" + body,  // lower case, still no command
      "\r\n" + body,                     // a blank line first
      std::string("\x16\x03\x01\x02\x00\x01\x00\x01\xfc\x03\x03", 11),  // a TLS ClientHello
      std::string("\x00\x01\x02garbage\n", 11) + body,
      "peeq 0\n" + body,               // a near miss
      "poke\x01 0x900 0x66\n" + body,  // a command word, then a control byte
      std::string(5000, 'p'),          // no newline, never a command
  };
  for (const std::string& a : attacks) {
    for (const bool tcp : {true, false}) {
      LineClient c = tcp ? LineClient::tcp(server.port()) : LineClient::unix_socket(dir.file("s"));
      try {
        c.send(a);
      } catch (const std::runtime_error&) {  // the server may have closed already
      }
      std::vector<std::string> lines;
      try {
        lines = c.read_until_closed(3000);  // closed at once, not after the first-line timeout
      } catch (const std::runtime_error& e) {
        ADD_FAILURE() << "not closed: " << testing::PrintToString(a) << ": " << e.what();
      }
      // The reply may be lost to the reset that closing on unread input causes.
      EXPECT_LE(lines.size(), 1u);
      if (!lines.empty()) {
        EXPECT_EQ(lines[0],
                  "ERR protocol the first line must be a dpc31 serve command "
                  "(docs/protocol.md); closing");
      }
      EXPECT_TRUE(c.async.empty());
    }
  }
  EXPECT_EQ(watcher.command("peek 0x900"), "OK 0x00");  // nothing executed
  EXPECT_TRUE(watcher.async.empty());
  EXPECT_TRUE(std::filesystem::is_empty(state));
  // A real client may send its first line in pieces.
  LineClient slow = LineClient::tcp(server.port());
  slow.send("pi");
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  slow.send("ng");
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_EQ(slow.command(""), "OK pong");
}

TEST(ServeSecurity, UnixSocketIsMode0600) {
  TempDir dir;
  const mode_t old = ::umask(0);  // whatever the server inherits
  ServerProcess server(kCli, {"--unix", dir.file("s")});
  ::umask(old);
  struct stat st {};
  ASSERT_EQ(::lstat(dir.file("s").c_str(), &st), 0);
  EXPECT_TRUE(S_ISSOCK(st.st_mode));
  EXPECT_EQ(st.st_mode & 07777, 0600u);
  LineClient c = LineClient::unix_socket(dir.file("s"));
  EXPECT_EQ(c.command("ping"), "OK pong");
}

TEST(ServeSecurity, SecretHandshakeOnTcp) {
  TempDir dir;
  const std::string secret = "s3cret-0123456789-abcdef";
  const std::string file = dir.file("secret");
  {
    std::ofstream f(file);
    f << secret << "\n";
  }
  std::filesystem::permissions(
      file, std::filesystem::perms::owner_read | std::filesystem::perms::owner_write);
  ServerProcess server(kCli, {"--tcp", "0", "--unix", dir.file("s"), "--secret-file", file});
  ASSERT_EQ(server.listening().size(), 2u);
  // Right secret: served, also with commands pipelined behind it.
  LineClient good = LineClient::tcp(server.port());
  good.send("auth " + secret + "\npoke 0x900 7\n");
  EXPECT_EQ(good.reply(), "OK auth");
  EXPECT_EQ(good.reply(), "OK");
  EXPECT_EQ(good.command("peek 0x900"), "OK 0x07");
  EXPECT_EQ(good.command("auth " + secret),
            "ERR syntax auth is accepted only as the first line of a connection");
  // Wrong secret, a prefix of it, a longer one, none, a command instead: closed, nothing run.
  for (const std::string& first :
       std::vector<std::string>{"auth wrong", "auth " + secret.substr(0, secret.size() - 1),
                                "auth " + secret + "x", "auth", "auth " + secret + " extra"}) {
    LineClient c = LineClient::tcp(server.port());
    c.send(first + "\npoke 0x900 0x66\n");
    EXPECT_EQ(c.read_until_closed(), std::vector<std::string>{"ERR auth wrong secret; closing"})
        << first;
  }
  {
    LineClient c = LineClient::tcp(server.port());
    c.send("poke 0x900 0x66\n");
    const std::vector<std::string> lines = c.read_until_closed();
    EXPECT_EQ(lines, std::vector<std::string>{
                         "ERR protocol the first line must be 'auth SECRET' (docs/protocol.md); "
                         "closing"});
  }
  EXPECT_EQ(good.command("peek 0x900"), "OK 0x07");
  // The Unix socket (mode 0600) needs no secret; one given is checked all the same.
  LineClient u = LineClient::unix_socket(dir.file("s"));
  EXPECT_EQ(u.command("ping"), "OK pong");
  LineClient u2 = LineClient::unix_socket(dir.file("s"));
  EXPECT_EQ(u2.command("auth " + secret), "OK auth");
  LineClient u3 = LineClient::unix_socket(dir.file("s"));
  u3.send("auth nope\n");
  EXPECT_EQ(u3.read_until_closed(), std::vector<std::string>{"ERR auth wrong secret; closing"});
  // Without --secret-file, `auth` is accepted and changes nothing.
  ServerProcess open_server(kCli, {"--tcp", "0"});
  LineClient o = LineClient::tcp(open_server.port());
  EXPECT_EQ(o.command("auth anything"), "OK auth not required");
  EXPECT_EQ(o.command("ping"), "OK pong");
}

TEST(ServeSecurity, BadSecretFilesExit2WithOneLine) {
  TempDir dir;
  const auto write = [&](const std::string& name, const std::string& text, bool private_) {
    std::ofstream(dir.file(name)) << text;
    ::chmod(dir.file(name).c_str(), private_ ? 0600 : 0644);
    return dir.file(name);
  };
  const std::vector<std::pair<std::string, std::string>> cases = {
      {dir.file("missing"), "No such file or directory"},
      {write("open", "0123456789abcdef0123\n", false), "group or others may access it (mode 0644)"},
      {write("short", "0123456789\n", true), "16 to 1024 printable ASCII characters"},
      {write("blank", "0123456789 abcdef0123\n", true), "16 to 1024 printable ASCII characters"},
      {write("empty", "", true), "16 to 1024 printable ASCII characters"},
      {dir.path(), "not a regular file"},
  };
  for (const auto& [file, why] : cases) {
    const testutil::CommandResult r =
        testutil::run_command(kCli + " serve --tcp 0 --secret-file '" + file + "' 2>&1 >/dev/null");
    EXPECT_EQ(r.rc, 2) << file;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
    EXPECT_TRUE(starts_with(r.out, "dpc31 serve: --secret-file " + file + ": ")) << r.out;
    EXPECT_NE(r.out.find(why), std::string::npos) << r.out;
  }
}

// 16 KiB or 256 telegrams ahead of the chip, then ERR queue_full; the queue drains as time
// passes, and a reset frees it, memory included (the finding: 8000 x 1 KiB took the server to
// 1.58 GB, still 1.32 GB after reset).
TEST(ServeSecurity, InjectQueueIsBoundedAndFreedOnReset) {
  ServerProcess server(kCli, {"--tcp", "0"});
  LineClient c = LineClient::tcp(server.port());
  std::string kib;
  for (int i = 0; i < 1024; ++i) kib += "55";  // 0x55: an edge at every bit
  const std::string inject = "inject " + kib;
  ASSERT_TRUE(starts_with(c.command(inject), "OK "));
  const std::size_t base = rss_kib(server.pid());
  std::size_t peak = 0;
  std::uint64_t end = 0;
  for (int round = 0; round < 10; ++round) {
    for (int i = 1; i < 16; ++i) ASSERT_TRUE(starts_with(c.command(inject), "OK ")) << i;
    EXPECT_EQ(c.command(inject),
              "ERR queue_full 16 telegrams of 16384 bytes are not yet on the line (at most 256 "
              "telegrams, 16384 bytes): step past their END first");
    EXPECT_TRUE(starts_with(c.command("inject 00"), "ERR queue_full "));
    peak = std::max(peak, rss_kib(server.pid()));
    EXPECT_EQ(c.command("reset"), "OK 0");
    ASSERT_TRUE(starts_with(c.command(inject), "OK ")) << "after reset";
  }
  const std::size_t after = rss_kib(server.pid());
  RecordProperty("rss_base_kib", static_cast<int>(base));
  RecordProperty("rss_full_kib", static_cast<int>(peak));
  RecordProperty("rss_after_reset_kib", static_cast<int>(after));
  if (kRssMeaningful) {
    // Measured: 5.9 MB at the start, 12.4 MB full, 6.2 MB after the reset (before the fix the
    // storage stayed: 9.4 MB after it).
    EXPECT_LT(peak, base + 32 * 1024) << "the full queue takes some 6 MB";
    EXPECT_LT(after, base + 2 * 1024) << "reset gives the queue's memory back";
  }
  // The telegram count: 256 one-byte telegrams.
  EXPECT_EQ(c.command("reset"), "OK 0");
  for (int i = 0; i < 256; ++i) ASSERT_TRUE(starts_with(c.command("inject 00"), "OK ")) << i;
  const std::string full = c.command("inject 00");
  EXPECT_TRUE(starts_with(full, "ERR queue_full 256 telegrams of 256 bytes ")) << full;
  // Time drains it.
  EXPECT_EQ(c.command("reset"), "OK 0");
  for (int i = 0; i < 16; ++i) {
    const std::vector<std::string> r = words(c.command(inject));
    ASSERT_EQ(r.size(), 3u);
    end = std::stoull(r[2]);
  }
  EXPECT_TRUE(starts_with(c.command(inject), "ERR queue_full "));
  EXPECT_EQ(c.command(fmt::format("step {}", end)), fmt::format("OK {}", end));
  EXPECT_TRUE(starts_with(c.command(inject), "OK "));
  // A queue that never drains (each telegram injected before the last is through) stays
  // bounded: the chip's line queues drop what was consumed.
  EXPECT_EQ(c.command("reset"), "OK 0");
  const std::size_t base2 = rss_kib(server.pid());
  for (int i = 0; i < 300; ++i) {
    const std::vector<std::string> r = words(c.command(inject));
    ASSERT_EQ(r.size(), 3u) << i;
    const std::uint64_t start = std::stoull(r[1]);
    const std::uint64_t stop = std::stoull(r[2]);
    const std::uint64_t now = std::stoull(c.command("cycle").substr(3));
    const std::uint64_t middle = (start + stop) / 2;
    if (middle > now) {
      ASSERT_TRUE(starts_with(c.command(fmt::format("step {}", middle - now)), "OK "));
    }
  }
  if (kRssMeaningful) {
    // Before the Fifo kept only what was queued: 80 MB after these 300 KiB, and growing.
    EXPECT_LT(rss_kib(server.pid()), base2 + 24 * 1024) << "300 KiB went through the line";
  }
}

TEST(ServeSecurity, IdleTimeoutIsOnByDefault) {
  EXPECT_EQ(dpc31::serve::ServerOptions{}.idle_timeout, 300);
  EXPECT_EQ(dpc31::serve::ServerOptions{}.hello_timeout, 10);
  const testutil::CommandResult r = testutil::run_command(kCli + " serve --help 2>&1");
  EXPECT_EQ(r.rc, 0);
  std::string line;
  std::istringstream in(r.out);
  while (std::getline(in, line) && line.find("--idle-timeout") == std::string::npos) {
  }
  EXPECT_NE(line.find("=300"), std::string::npos) << r.out;
}

// Connections that never send a first line are closed after the first-line timeout, and give way
// to a newcomer when the server is full: they cannot lock the others out, even with the idle
// timeout off. Each is told why before it is closed (docs/protocol.md, "Asynchronous lines").
TEST(ServeSecurity, SilentConnectionsCannotLockOthersOut) {
  {
    ServerProcess server(kCli, {"--tcp", "0", "--max-clients", "3", "--idle-timeout", "0"});
    LineClient s1 = LineClient::tcp(server.port());
    LineClient s2 = LineClient::tcp(server.port());
    // Connections are accepted in order: once the probe is answered, both silent ones are in.
    LineClient probe = LineClient::tcp(server.port());
    EXPECT_EQ(probe.command("ping"), "OK pong");
    LineClient a = LineClient::tcp(server.port());
    EXPECT_EQ(a.command("ping"), "OK pong");
    LineClient b = LineClient::tcp(server.port());
    EXPECT_EQ(b.command("ping"), "OK pong");
    EXPECT_TRUE(s1.read_until_closed().empty());  // the oldest silent ones gave way
    EXPECT_EQ(s1.async, std::vector<std::string>{"! bye max_clients"});
    EXPECT_TRUE(s2.read_until_closed().empty());
    EXPECT_EQ(s2.async, std::vector<std::string>{"! bye max_clients"});
    LineClient c = LineClient::tcp(server.port());  // three established: busy, as before
    const std::vector<std::string> lines = c.read_until_closed();
    ASSERT_EQ(lines.size(), 1u);
    EXPECT_TRUE(starts_with(lines[0], "ERR busy ")) << lines[0];
    EXPECT_EQ(a.command("ping"), "OK pong");
  }
  {
    // The first-line timeout is the idle timeout where that is shorter.
    ServerProcess server(kCli, {"--tcp", "0", "--idle-timeout", "0.5"});
    LineClient silent = LineClient::tcp(server.port());
    const auto t0 = std::chrono::steady_clock::now();
    EXPECT_TRUE(silent.read_until_closed(5000).empty());
    const double secs =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(silent.async, std::vector<std::string>{"! bye hello_timeout"});
    EXPECT_GE(secs, 0.45);
    EXPECT_LT(secs, 3.0);
  }
}

// The bytes the server's end of the loopback TCP connection `fd` has written that this end has
// not acknowledged yet: tx_queue (write_seq - snd_una) of its row in /proc/net/tcp. 0: all it
// wrote is in our receive queue or read, whether or not the server runs. SIZE_MAX when the row
// was not seen: the file is read while other tests' sockets come and go, and may skip one.
std::size_t unacked_towards(int fd) {
  sockaddr_in mine{};
  sockaddr_in peer{};
  socklen_t n = sizeof mine;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&mine), &n);
  n = sizeof peer;
  ::getpeername(fd, reinterpret_cast<sockaddr*>(&peer), &n);
  const auto port = [](const std::string& address) {
    return std::stoul(address.substr(address.find(':') + 1), nullptr, 16);
  };
  std::ifstream f("/proc/net/tcp");
  std::string line;
  std::getline(f, line);  // the header
  while (std::getline(f, line)) {
    std::istringstream in(line);
    std::string slot, local, remote, state, queues;
    in >> slot >> local >> remote >> state >> queues;
    if (port(local) == ntohs(peer.sin_port) && port(remote) == ntohs(mine.sin_port)) {
      return std::stoul(queues.substr(0, queues.find(':')), nullptr, 16);
    }
  }
  return SIZE_MAX;
}

// Empty when the clients in `who` (the lines a command waited for, in the order they ran) fit
// docs/protocol.md's bound: the rest of the round in progress, one line per client or a lone
// client's round of up to 64 lines, then one line per client of the next round. Else `who`.
std::string within_the_bound(const std::vector<int>& who) {
  const auto distinct = [](auto b, auto e) {
    return std::set<int>(b, e).size() == static_cast<std::size_t>(e - b);
  };
  // One line per client: the longest such prefix is the round in progress if any split fits.
  auto split = who.begin();
  std::set<int> first;
  while (split != who.end() && first.insert(*split).second) ++split;
  if (distinct(split, who.end())) return {};
  // A lone client's round (its next round's line may follow it at once).
  auto lone = who.begin();
  while (lone != who.end() && lone - who.begin() < 64 && *lone == who.front()) ++lone;
  if (distinct(lone, who.end())) return {};
  std::string s;
  for (const int c : who) s += fmt::format("{} ", c);
  return s;
}

// The scheduler's bound, counted in commands: kFlood clients pipeline `step 1` (each advances
// the cycle by one), one more asks `cycle` while the server is stopped, so its line is there when
// the server goes on. Its reply minus the last cycle the flood clients had been told is the
// number of flood commands run while the command waited. Of 200 tries, a wait counts only if
// every flood client still had lines waiting at the stop; returns the worst wait and how many
// counted.
struct FloodWaits {
  std::size_t worst = 0;
  std::size_t counted = 0;
};
FloodWaits flood_against(ServerProcess& server, const TempDir& dir, std::string& phase, int kFlood,
                         std::size_t depth, unsigned max_sleep_us);
FloodWaits waits_behind_a_flood(int kFlood, std::size_t depth, unsigned max_sleep_us) {
  TempDir dir;
  ServerProcess server(kCli, {"--tcp", "0", "--unix", dir.file("s")});
  std::string phase = "start";
  try {
    return flood_against(server, dir, phase, kFlood, depth, max_sleep_us);
  } catch (const std::exception& e) {
    // Once in a 20-fold clang run beside two CPU hogs a send found its peer gone ("send: Broken
    // pipe", issue 35): say where, and whether the server was still alive.
    const int rc = server.wait_exit(0);
    ADD_FAILURE() << phase << ": " << e.what() << "; the server "
                  << (rc == ServerProcess::kRunning ? std::string("still runs")
                                                    : fmt::format("ended: {}", rc));
    return {SIZE_MAX, 0};
  }
}
FloodWaits flood_against(ServerProcess& server, const TempDir& dir, std::string& phase, int kFlood,
                         std::size_t depth, unsigned max_sleep_us) {
  std::vector<LineClient> flood;
  for (int i = 0; i < kFlood; ++i) {
    phase = fmt::format("flood client {} connects", i);
    flood.push_back(LineClient::tcp(server.port()));
    EXPECT_EQ(flood.back().command("ping"), "OK pong");
  }
  phase = "the good client connects";
  LineClient good = LineClient::unix_socket(dir.file("s"));
  EXPECT_EQ(good.command("ping"), "OK pong");

  std::vector<std::size_t> sent(kFlood, 0);
  std::vector<std::size_t> answered(kFlood, 0);
  std::vector<std::string> partial(kFlood);
  std::uint64_t told = 0;  // the highest cycle in a flood client's reply so far
  // Each `step 1` advances the cycle by one: a reply's cycle names the step, and so which client's
  // line ran there (kept from the last stop's `before` on).
  std::map<std::uint64_t, int> ran_for;
  const std::string lines = [] {
    std::string l;
    for (int i = 0; i < 100; ++i) l += "step 1\n";
    return l;
  }();
  // Takes the flood clients' replies; tops their pipelines up to `depth` lines each (7 bytes a
  // line; the server reads up to 64 KiB of a client ahead).
  const auto service = [&](bool top_up) {
    for (int i = 0; i < kFlood; ++i) {
      char buf[65536];
      for (;;) {
        const ssize_t n = ::recv(flood[i].fd(), buf, sizeof buf, MSG_DONTWAIT);
        if (n <= 0) break;
        partial[i].append(buf, static_cast<std::size_t>(n));
      }
      std::size_t b = 0;
      for (std::size_t nl; (nl = partial[i].find('\n', b)) != std::string::npos; b = nl + 1) {
        const std::string l = partial[i].substr(b, nl - b);
        ASSERT_TRUE(starts_with(l, "OK ")) << l;
        const std::uint64_t cycle = std::stoull(l.substr(3));
        told = std::max(told, cycle);
        ran_for[cycle] = i;
        ++answered[i];
      }
      partial[i].erase(0, b);
      while (top_up && sent[i] - answered[i] < depth) {
        const ssize_t n =
            ::send(flood[i].fd(), lines.data(), lines.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
        ASSERT_EQ(n, static_cast<ssize_t>(lines.size()));
        sent[i] += 100;
      }
    }
  };
  std::mt19937 rng(14);
  std::size_t worst = 0;
  std::vector<std::size_t> waits;
  bool flooding = true;
  std::uint64_t outstanding = 0;  // the flood clients' lines not yet answered at the stop
  for (int k = 0; k < 200; ++k) {
    phase = fmt::format("stop {}", k);
    service(true);
    std::this_thread::sleep_for(std::chrono::microseconds(rng() % max_sleep_us));  // any phase
    std::uint64_t before = 0;
    {
      Frozen stopped(server.pid());
      // Every reply the server wrote before it stopped is read: its end has nothing
      // unacknowledged left, then our receive queue is emptied. (Replies still on their way
      // through the loopback of a loaded host were read as waits: 2 ms of quiet were not enough
      // once, a "wait" of 5760 lines beside a build; 5 ms not beside two CPU hogs, 1792; issue
      // 35.) Reading opens the window for what the server's kernel still holds.
      const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
      for (int i = 0; i < kFlood; ++i) {
        while (unacked_towards(flood[i].fd()) != 0) {
          service(false);
          if (std::chrono::steady_clock::now() > until) {
            ADD_FAILURE() << "the server's replies stay unacknowledged";
            return {SIZE_MAX, 0};
          }
          std::this_thread::sleep_for(std::chrono::microseconds(200));
        }
      }
      service(false);
      before = told;
      flooding = true;
      outstanding = 0;
      for (int i = 0; i < kFlood; ++i) {
        flooding = flooding && sent[i] - answered[i] >= 3;
        outstanding += sent[i] - answered[i];
      }
      good.send("cycle\n");
    }
    const std::string r = good.reply();
    if (!starts_with(r, "OK ")) {
      ADD_FAILURE() << r;
      return {SIZE_MAX, 0};
    }
    const std::uint64_t at = std::stoull(r.substr(3));
    EXPECT_GE(at, before);
    // The documented bound, stop by stop, from who ran the steps before+1 .. at (their replies
    // come once their rounds end): the round in progress at the stop (also its lines that ran
    // before the stop: their replies were not sent yet), one line per client, or a lone client's
    // round of up to 64 lines; then at most one line of each client in the next round
    // (docs/protocol.md, "Several clients").
    phase = fmt::format("stop {}: the replies of the steps {}..{}", k, before + 1, at);
    const auto all_by = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    const auto replied = [&] {
      return static_cast<std::uint64_t>(
          std::distance(ran_for.upper_bound(before), ran_for.upper_bound(at)));
    };
    while (replied() < at - before && std::chrono::steady_clock::now() < all_by) {
      service(false);
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    std::vector<int> who;
    for (auto it = ran_for.upper_bound(before); it != ran_for.upper_bound(at); ++it) {
      who.push_back(it->second);
    }
    if (who.size() != at - before) {
      ADD_FAILURE() << phase << ": " << who.size() << " replies";
      return {SIZE_MAX, 0};
    }
    const std::string seen = within_the_bound(who);
    if (!seen.empty()) {
      ADD_FAILURE() << "stop " << k << ": the command waited for the lines of clients " << seen;
      return {SIZE_MAX, 0};
    }
    ran_for.erase(ran_for.begin(), ran_for.upper_bound(at));
    // A wait as long as the whole pipeline left at the stop is no stop that found a flood
    // running: the replies sent before the stop had not all arrived when it was read (a loaded
    // host; 8005 of 8000 lines once in a clang suite beside a build). A server that ignored the
    // bound would drain every pipeline at every stop, and the count of stops below fails then.
    if (!flooding || at - before >= outstanding) continue;
    waits.push_back(at - before);
    worst = std::max<std::size_t>(worst, at - before);
  }
  // The commands did wait for the flood.
  std::size_t total = 0;
  for (const std::size_t a : answered) total += a;
  ::testing::Test::RecordProperty("flood_commands", static_cast<int>(total));
  EXPECT_GE(worst, static_cast<std::size_t>(kFlood));
  std::sort(waits.begin(), waits.end());
  ::testing::Test::RecordProperty("worst_wait_commands", static_cast<int>(worst));
  if (!waits.empty()) {
    ::testing::Test::RecordProperty("median_wait_commands",
                                    static_cast<int>(waits[waits.size() / 2]));
  }
  phase = "the good client's last ping";
  EXPECT_EQ(good.command("ping"), "OK pong");
  return {worst, waits.size()};
}

// 13 clients flooding: at most the rest of the round in progress and one line of each flood
// client in the next, 2 x 13, checked at every stop from who ran the lines (flood_against). The
// exception the protocol names: a round in progress that was a lone client's, up to 64 lines, then
// 13. That needs every other pipeline drained in the server when the round began: beside two CPU
// hogs in the ASan build the test was descheduled that long, and topped up while the lone round
// ran (a wait of 64 once, which the whole-wait bound 2 x 13 took for a breach; issue 35). (Before
// issue 14: up to 64 lines per client and round, 832.) Only the stops that found every flood
// client still busy count, and nearly all must (199 of 200 once beside a CPU hog).
TEST(ServeSecurity, AFloodDelaysACommandByAtMostTwoLinesPerOtherClient) {
  const FloodWaits w = waits_behind_a_flood(13, 4000, 500);
  EXPECT_GE(w.counted, 150u);
  EXPECT_LE(w.worst, 64u + 13);
}

// One client pipelining alone runs up to 64 lines per round (docs/protocol.md): a command that
// arrives waits for at most the rest of that round, 63 lines, and one line in the next. The
// count here also takes the lines of the stopped round that ran before the stop (their replies
// were not sent yet): at most 64 + 1. A lone client's lines go fast: on a loaded machine the
// test's own pauses can outlast its pipeline, so only the stops that found it still busy count,
// and there must be enough of them: over up to three floods, each held to the bound (a run beside
// a build once counted too few in one flood).
TEST(ServeSecurity, ALonePipelineDelaysACommandByAtMost64Lines) {
  std::size_t counted = 0;
  for (int flood = 0; flood < 3 && counted < 20 && !HasFailure(); ++flood) {
    const FloodWaits w = waits_behind_a_flood(1, 8000, 50);
    EXPECT_LE(w.worst, 65u) << "flood " << flood;
    counted += w.counted;
  }
  EXPECT_GE(counted, 20u);
}

// New connections on both listeners are taken a few at a time, alternating: 50 TCP connections
// waiting to be accepted do not delay a Unix client beyond the first two accept rounds.
TEST(ServeSecurity, AcceptIsFairBetweenTcpAndUnix) {
  TempDir dir;
  ServerProcess server(kCli, {"--tcp", "0", "--unix", dir.file("s"), "--max-clients", "64"});
  LineClient probe = LineClient::tcp(server.port());
  ASSERT_EQ(probe.command("ping"), "OK pong");
  std::vector<LineClient> tcp;
  std::optional<LineClient> unix_client;
  {
    Frozen stopped(server.pid());
    for (int i = 0; i < 50; ++i) {
      tcp.push_back(LineClient::tcp(server.port()));
      tcp.back().send("step 1\n");
    }
    unix_client.emplace(LineClient::unix_socket(dir.file("s")));
    unix_client->send("cycle\n");
  }
  const std::string r = unix_client->reply();
  ASSERT_TRUE(starts_with(r, "OK ")) << r;
  EXPECT_LE(std::stoull(r.substr(3)), 8u) << "TCP clients served before the Unix one";
  for (auto& c : tcp) EXPECT_TRUE(starts_with(c.reply(), "OK "));
  EXPECT_EQ(probe.command("cycle"), "OK 50");
}

}  // namespace

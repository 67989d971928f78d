// `dpc31 serve` against the findings of issue 29 (docs/security.md, "dpc31 serve"): a secret file
// of another user, guessing the secret, a Unix socket whose backlog is full, a state directory
// without a quota, an idle timeout of almost nothing, a hard link in the state directory; and of
// the s31-serve audit: the temporaries' names, blanks at a name's end, legacy --tcp addresses,
// another interface without a secret, --max-clients above the descriptor limit, no descriptor left
// for a newcomer. Each test makes the attack and sees it refused or bounded; the real binary as a
// child process.
#include <fcntl.h>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "run_command.hpp"
#include "serve_client.hpp"
#include "serve_server.hpp"
#include "state_dir.hpp"
#include "test_files.hpp"

using namespace testutil;
using dpc31::serve::StateDir;

namespace {

const std::string kCli = DPC31_CLI;
using std::chrono::milliseconds;
using SteadyClock = std::chrono::steady_clock;

std::string secret_file(const TempDir& dir, const std::string& secret) {
  const std::string f = dir.write("secret", secret + "\n");
  ::chmod(f.c_str(), 0600);
  return f;
}

// The test's standard error goes to `file` while it lives (what a child spawned meanwhile
// inherits), and comes back after.
class StderrTo {
 public:
  explicit StderrTo(const std::string& file) : saved_(::dup(STDERR_FILENO)) {
    const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
    ::dup2(fd, STDERR_FILENO);
    ::close(fd);
  }
  ~StderrTo() {
    ::dup2(saved_, STDERR_FILENO);
    ::close(saved_);
  }
  StderrTo(const StderrTo&) = delete;
  StderrTo& operator=(const StderrTo&) = delete;

 private:
  int saved_;
};

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> v;
  std::size_t b = 0;
  for (std::size_t e; (e = text.find('\n', b)) != std::string::npos; b = e + 1) {
    v.push_back(text.substr(b, e - b));
  }
  return v;
}

}  // namespace

// Mode 0600 is not enough: the file's owner could read it and can change it at any time. A file
// of another user (here nobody, 65534) is refused with one line and exit 2.
TEST(ServeSecurity, ASecretFileOfAnotherUserIsRefused) {
  if (::geteuid() != 0) GTEST_SKIP() << "needs root to give a file to another user";
  TempDir dir;
  const std::string f = secret_file(dir, "0123456789abcdef0123");
  ASSERT_EQ(::chown(f.c_str(), 65534, 65534), 0);
  const CommandResult r =
      run_command(kCli + " serve --tcp 0 --secret-file '" + f + "' 2>&1 >/dev/null");
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(lines_of(r.out),
            std::vector<std::string>{"dpc31 serve: --secret-file " + f +
                                     ": owned by user 65534, not by this user (0): the secret "
                                     "must be yours alone"});
}

// The finding: about 9 500 guesses a second, each on a new connection. Now a peer's wrong
// secrets are looked at no faster than 50 ms x 2^(n-1) apart (n wrong so far, at most 5 s), on
// all its connections together, with one log line each; other clients are served meanwhile, and
// the right secret gets in once the delay has passed.
TEST(ServeSecurity, WrongSecretsFromOnePeerAreSlowedDownAndLogged) {
  TempDir dir;
  const std::string secret = "s3cret-0123456789-abcdef";
  const std::string log = dir.file("stderr");
  std::unique_ptr<ServerProcess> server;
  {
    const StderrTo to(log);
    server = std::make_unique<ServerProcess>(
        kCli, std::vector<std::string>{"--tcp", "0", "--unix", dir.file("s"), "--secret-file",
                                       secret_file(dir, secret)});
  }
  // Eight connections guessing in parallel for one second, each reconnecting after its answer.
  const auto t0 = SteadyClock::now();
  const auto stop = t0 + milliseconds(1000);
  std::vector<SteadyClock::time_point> judged;
  std::vector<std::unique_ptr<LineClient>> guessers;
  for (int i = 0; i < 8; ++i) {
    guessers.push_back(std::make_unique<LineClient>(LineClient::tcp(server->port())));
    guessers.back()->send("auth guess" + std::to_string(i) + "\n");
  }
  LineClient unix_client = LineClient::unix_socket(dir.file("s"));
  int unix_replies = 0;
  while (SteadyClock::now() < stop) {
    for (auto& g : guessers) {
      pollfd p{g->fd(), POLLIN, 0};
      if (::poll(&p, 1, 0) <= 0) continue;
      const std::vector<std::string> got = g->read_until_closed();
      ASSERT_EQ(got, std::vector<std::string>{"ERR auth wrong secret; closing"});
      judged.push_back(SteadyClock::now());
      g = std::make_unique<LineClient>(LineClient::tcp(server->port()));
      g->send("auth guess\n");
    }
    // The server is not held up by the delays: a Unix client is answered all along.
    ASSERT_EQ(unix_client.command("ping", 200), "OK pong");
    ++unix_replies;
    std::this_thread::sleep_for(milliseconds(2));
  }
  // Judged at 0, 50, 150, 350 and 750 ms at the soonest: at most five in the second (before: all).
  EXPECT_GE(judged.size(), 3u);  // the server judges on time (also on a loaded machine)
  EXPECT_LE(judged.size(), 5u);
  // The k-th answer (from 0) cannot come before the delays of the k wrong ones before it:
  // 50 x (2^k - 1) ms after the first guess was sent (the same monotonic clock in both processes).
  for (std::size_t k = 1; k < judged.size(); ++k) {
    EXPECT_GE(judged[k] - t0, milliseconds(50 * ((1 << k) - 1))) << "answer " << k;
  }
  EXPECT_GT(unix_replies, 10);  // each within 200 ms (the ASSERT above)
  guessers.clear();
  // The right secret is looked at when the delay is over, and the delay is forgotten then.
  LineClient good = LineClient::tcp(server->port());
  EXPECT_EQ(good.command("auth " + secret, 10'000), "OK auth");
  LineClient again = LineClient::tcp(server->port());
  EXPECT_EQ(again.command("auth " + secret, 1000), "OK auth");
  EXPECT_EQ(again.command("shutdown"), "OK shutdown");
  EXPECT_EQ(server->wait_exit(5000), 0);
  const std::vector<std::string> lines = lines_of(slurp(log));
  ASSERT_EQ(lines.size(), judged.size()) << slurp(log);
  for (std::size_t k = 0; k < lines.size(); ++k) {
    EXPECT_EQ(lines[k], fmt::format("dpc31 serve: a wrong secret from 127.0.0.0/8 ({} in a row); "
                                    "its next 'auth' is looked at in {} ms",
                                    k + 1, 50 << k));
  }
}

// The finding: a live server's socket whose backlog is full made `serve --unix` hang in
// connect() at its start. Now it is refused at once as in use: its probe connects without
// blocking. A hang would end at `timeout 10` with exit code 124, so the exit code tells; no
// wall-clock bound (1 s was not enough for the ASan binary's start beside two builds).
TEST(ServeSecurity, AUnixSocketWithAFullBacklogIsRefusedAtOnce) {
  TempDir dir;
  const std::string path = dir.file("busy.sock");
  const int l = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_un sa{};
  sa.sun_family = AF_UNIX;
  std::strncpy(sa.sun_path, path.c_str(), sizeof sa.sun_path - 1);
  ASSERT_EQ(::bind(l, reinterpret_cast<sockaddr*>(&sa), sizeof sa), 0);
  ASSERT_EQ(::listen(l, 0), 0);
  std::vector<int> waiting;  // connections nobody accepts, until the backlog is full
  for (int i = 0; i < 64; ++i) {
    const int c = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    const int rc = ::connect(c, reinterpret_cast<sockaddr*>(&sa), sizeof sa);
    waiting.push_back(c);
    if (rc != 0) {
      ASSERT_EQ(errno, EAGAIN);
      break;
    }
  }
  ASSERT_LT(waiting.size(), 64u) << "the backlog never filled";
  const CommandResult r =
      run_command("timeout 10 " + kCli + " serve --unix '" + path + "' 2>&1 >/dev/null");
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(lines_of(r.out), std::vector<std::string>{"dpc31 serve: --unix " + path +
                                                      ": in use by a running server"});
  for (const int c : waiting) ::close(c);
  ::close(l);
}

// The finding: 3 550 saves, 42 MB in 5 s, no end. The state directory holds at most 1024 files
// and 256 MiB (StateDir::Quota); beyond, `ERR snapshot` names the limit and nothing is written;
// saving over an old file stays possible.
TEST(ServeSecurity, TheStateDirectoryHasAQuotaOfFilesAndBytes) {
  const StateDir::Quota q;
  ASSERT_EQ(q.files, 1024u);
  ASSERT_EQ(q.bytes, std::uint64_t{256} << 20);
  TempDir dir;
  ::mkdir(dir.file("snaps").c_str(), 0700);
  ::mkdir(dir.file("snaps/sub").c_str(), 0700);
  for (int i = 0; i < 1022; ++i) {  // the files of earlier saves, some in a subdirectory
    std::ofstream(dir.file(fmt::format("snaps/{}{}", i % 2 == 0 ? "" : "sub/", i)));
  }
  ServerProcess server(kCli, {"--tcp", "0", "--state-dir", dir.file("snaps")});
  LineClient c = LineClient::tcp(server.port());
  EXPECT_EQ(c.command("save a"), "OK 0");      // the 1023rd file
  EXPECT_EQ(c.command("save sub/b"), "OK 0");  // the 1024th
  const std::size_t snapshot = std::filesystem::file_size(dir.file("snaps/a"));
  const std::vector<std::string> before = dir.tree();
  EXPECT_EQ(c.command("save c"),
            fmt::format("ERR snapshot c: the state directory is full (at most 1024 files and 256 "
                        "MiB; it holds 1024 files, {} bytes): delete snapshots or save over an "
                        "old one",
                        2 * snapshot));
  EXPECT_EQ(dir.tree(), before);
  EXPECT_EQ(c.command("save a"), "OK 0");  // over an old one
  // Bytes: 1023 files, one of them so large (as stat() tells its size) that the other two
  // snapshots fill 256 MiB exactly.
  std::filesystem::remove(dir.file("snaps/2"));
  std::filesystem::remove(dir.file("snaps/0"));
  { std::ofstream big(dir.file("snaps/0")); }
  std::filesystem::resize_file(dir.file("snaps/0"), (std::uint64_t{256} << 20) - 2 * snapshot);
  EXPECT_EQ(c.command("save new"),
            fmt::format("ERR snapshot new: the state directory is full (at most 1024 files and 256 "
                        "MiB; it holds 1023 files, {} bytes): delete snapshots or save over an "
                        "old one",
                        (std::uint64_t{256} << 20)));
  EXPECT_FALSE(std::filesystem::exists(dir.file("snaps/new")));
  std::filesystem::remove(dir.file("snaps/0"));
  EXPECT_EQ(c.command("save new"), "OK 0");
}

// The finding: --idle-timeout 1e-320 was taken (every client closed before its first line could
// arrive). Now 0 (never) or at least 0.1 s, from the CLI and the library.
TEST(ServeSecurity, TheIdleTimeoutHasAMinimum) {
  for (const std::string v : {"1e-320", "0.05", "0.0999"}) {
    const CommandResult r =
        run_command(kCli + " serve --tcp 0 --idle-timeout " + v + " 2>&1 >/dev/null");
    EXPECT_EQ(r.rc, 2) << v;
    EXPECT_EQ(lines_of(r.out).size(), 1u) << r.out;
    EXPECT_NE(r.out.find(": 0 (never) or at least 0.1 s"), std::string::npos) << r.out;
  }
  dpc31::serve::ServerOptions o;
  o.tcp = "0";
  o.idle_timeout = 1e-320;
  EXPECT_THROW(dpc31::serve::Server{o}, dpc31::serve::ServerError);
  o.idle_timeout = 0.1;
  EXPECT_NO_THROW(dpc31::serve::Server{o});
}

// docs/protocol.md said a hard link in the state directory is written through; `save` replaces
// it (a temporary renamed over the name), so the other name keeps its old content: a link to a
// file elsewhere cannot make `save` write there.
TEST(ServeSecurity, SaveReplacesAHardLinkInsteadOfWritingThroughIt) {
  TempDir dir;
  ::mkdir(dir.file("snaps").c_str(), 0700);
  const std::string outside = dir.write("outside", "precious\n");
  ASSERT_EQ(::link(outside.c_str(), dir.file("snaps/linked").c_str()), 0);
  ServerProcess server(kCli, {"--tcp", "0", "--state-dir", dir.file("snaps")});
  LineClient c = LineClient::tcp(server.port());
  EXPECT_EQ(c.command("save linked"), "OK 0");
  EXPECT_EQ(slurp(outside), "precious\n");
  struct stat a {};
  struct stat b {};
  ASSERT_EQ(::stat(outside.c_str(), &a), 0);
  ASSERT_EQ(::stat(dir.file("snaps/linked").c_str(), &b), 0);
  EXPECT_NE(a.st_ino, b.st_ino);
  EXPECT_EQ(a.st_nlink, 1u);
  EXPECT_EQ(c.command("load linked"), "OK 0");
}

// s31-serve, finding 3: a client saved under the 100 names `save`'s temporary may take
// (`.dpc31-PID.tmp`, `.dpc31-PID-K.tmp`, docs/protocol.md "Snapshots"), and every later `save`
// of every client failed ("every name is taken"). Names starting with `.dpc31-` are the
// server's: refused by their form, so `save` keeps working.
TEST(ServeSecurity, AClientCannotTakeTheTemporaryNamesOfSave) {
  TempDir dir;
  ServerProcess server(kCli, {"--tcp", "0", "--state-dir", dir.path()});
  LineClient c = LineClient::tcp(server.port());
  EXPECT_EQ(c.command("save old"), "OK 0");
  for (int k = 0; k < 100; ++k) {
    const std::string name = k == 0 ? fmt::format(".dpc31-{}.tmp", server.pid())
                                    : fmt::format(".dpc31-{}-{}.tmp", server.pid(), k);
    EXPECT_EQ(c.command("save " + name),
              "ERR denied " + name + ": a name starting with '.dpc31-' is the server's temporary");
  }
  EXPECT_EQ(c.command("load .dpc31-x"),
            "ERR denied .dpc31-x: a name starting with '.dpc31-' is the server's temporary");
  EXPECT_EQ(c.command("save sub/.dpc31-1.tmp"),
            "ERR denied sub/.dpc31-1.tmp: a name starting with '.dpc31-' is the server's "
            "temporary");
  EXPECT_EQ(c.command("save new"), "OK 0");
  EXPECT_EQ(c.command("save old"), "OK 0");
  EXPECT_EQ(c.command("save .dpc31"), "OK 0");  // not the prefix: an ordinary name
  EXPECT_EQ(dir.tree(), (std::vector<std::string>{".dpc31", "new", "old"}));
}

// s31-serve, finding 9: `save a ` wrote over `a` (the blanks at NAME's end were dropped, though
// docs/protocol.md said NAME is the rest of the line, blanks included). The blanks after the
// command separate it from NAME; a component that begins or ends with a blank is refused: it
// could not be told from the one without in a listing.
TEST(ServeSecurity, ANameEndingInABlankIsRefusedNotTrimmed) {
  TempDir dir;
  ::mkdir(dir.file("snaps").c_str(), 0700);
  ::mkdir(dir.file("snaps/sub").c_str(), 0700);
  ServerProcess server(kCli, {"--tcp", "0", "--state-dir", dir.file("snaps")});
  LineClient c = LineClient::tcp(server.port());
  EXPECT_EQ(c.command("save a"), "OK 0");
  EXPECT_EQ(c.command("step 8"), "OK 8");
  // As the reply shows NAME: the blanks after the command dropped, a tab as a blank (a reply is
  // printable ASCII).
  for (const auto& [name, shown] :
       std::vector<std::pair<std::string, std::string>>{{"a ", "a "},
                                                        {"a\t", "a "},
                                                        {"sub/ a", "sub/ a"},
                                                        {"sub /a", "sub /a"},
                                                        {" a ", "a "}}) {
    for (const std::string cmd : {"save", "load"}) {
      EXPECT_EQ(c.command(cmd + " " + name),
                "ERR denied " + shown + ": a component may not begin or end with a blank")
          << cmd << " '" << name << "'";
    }
  }
  EXPECT_EQ(c.command("save \t two  words"), "OK 8");  // the separator; inner blanks are NAME's
  EXPECT_EQ(c.command("load a"), "OK 0");              // `a` is the first save's
  EXPECT_EQ(dir.tree(),
            (std::vector<std::string>{"snaps", "snaps/a", "snaps/sub", "snaps/two  words"}));
}

// s31-serve, finding 4 (docs/protocol.md: ADDR is "numeric IPv4, `[v6]`, or a host name"): the
// resolver read inet_aton's legacy forms, so `--tcp 0:5555` listened on every interface
// (0.0.0.0). Each is now exit 2 with one line; `timeout` ends a server that listens instead.
TEST(ServeSecurity, TcpAddressesTakeOnlyTheDocumentedForms) {
  const std::vector<std::pair<std::string, std::string>> refused = {
      {"0:0", "'0' is neither a dotted-quad IPv4 address"},
      {"0x7f000001:0", "'0x7f000001' is neither a dotted-quad IPv4 address"},
      {"127.1:0", "'127.1' is neither a dotted-quad IPv4 address"},
      {"127.0.0.010:0", "'127.0.0.010' is neither a dotted-quad IPv4 address"},  // octal 8
      {"127.0.0.256:0", "'127.0.0.256' is neither a dotted-quad IPv4 address"},  // not to DNS
      {"::1:0", "an IPv6 address goes in brackets: [::1]:PORT"},
      {"[127.0.0.1]:0", "'[127.0.0.1]' is no IPv6 address"},
      {"[fe80::1%]:0", "'[fe80::1%]' is no IPv6 address"},  // a zone without its name
  };
  for (const auto& [addr, why] : refused) {
    const CommandResult r =
        run_command("timeout 10 " + kCli + " serve --tcp " + addr + " 2>&1 >/dev/null");
    EXPECT_EQ(r.rc, 2) << addr;
    EXPECT_EQ(r.out, "dpc31 serve: --tcp '" + addr + "': " +
                         (why.find("dotted") != std::string::npos
                              ? why + " (four decimal parts: 127.0.0.1, 0.0.0.0) nor a host name\n"
                              : why + "\n"))
        << addr;
  }
  // A link-local address with its zone (RFC 4007) is an address (the review of s31: inet_pton
  // alone refused the zone the resolver takes); fe80::1 is on no interface here, so the bind
  // says why, not the form.
  const CommandResult zoned =
      run_command("timeout 10 " + kCli + " serve --tcp '[fe80::1%lo]:0' 2>&1 >/dev/null");
  EXPECT_EQ(zoned.rc, 2);
  EXPECT_TRUE(starts_with(zoned.out, "dpc31 serve: cannot listen on tcp [fe80::1%lo]:0: "))
      << zoned.out;
  for (const std::string addr : {"127.0.0.1:0", "[::1]:0", "localhost:0"}) {
    ServerProcess server(kCli, {"--tcp", addr});
    ASSERT_EQ(server.listening().size(), 1u) << addr;
    const std::string& l = server.listening()[0];
    EXPECT_TRUE((addr[0] != '[' && starts_with(l, "listening tcp 127.0.0.1:")) ||
                (addr[0] != '1' && starts_with(l, "listening tcp [::1]:")))
        << l;
  }
}

// s31-serve, finding 4: another interface than the loopback without --secret-file is what the
// threat model (docs/protocol.md) says not to do: one warning line on stderr at start, before
// the listening line; none on the loopback or with a secret.
TEST(ServeSecurity, AnotherInterfaceWithoutASecretIsWarnedAbout) {
  TempDir dir;
  const std::string secret = secret_file(dir, "0123456789abcdef-the-secret");
  const std::vector<std::pair<std::vector<std::string>, bool>> cases = {
      {{"--tcp", "0.0.0.0:0"}, true},
      {{"--tcp", "0.0.0.0:0", "--secret-file", secret}, false},
      {{"--tcp", "127.0.0.1:0"}, false},
      {{"--tcp", "127.0.0.2:0"}, false},
      {{"--tcp", "[::ffff:127.0.0.1]:0"}, false},  // the loopback mapped into IPv6
  };
  for (const auto& [args, warned] : cases) {
    const std::string log = dir.file("err");
    std::string port;
    {
      const StderrTo to(log);
      ServerProcess server(kCli, args);
      ASSERT_EQ(server.listening().size(), 1u);
      port = std::to_string(server.port());
    }
    EXPECT_EQ(slurp(log), warned ? "dpc31 serve: warning: tcp 0.0.0.0:" + port +
                                       " is not a loopback address and there is no "
                                       "--secret-file: every host that reaches it is a full "
                                       "client\n"
                                 : "")
        << args[1];
  }
}

// s31-serve, finding 5: with --max-clients above what RLIMIT_NOFILE allows, newcomers waited
// unanswered in the backlog once accept() failed (EMFILE). The server raises its soft limit as
// far as the hard one allows; under `ulimit -n 24` (both limits) that is not enough for 1000:
// one line on stderr says how many it serves, and a newcomer beyond them gets `ERR busy`.
TEST(ServeSecurity, MaxClientsAboveTheDescriptorLimitIsClampedAndSaid) {
  TempDir dir;
  const std::string log = dir.file("err");
  std::unique_ptr<ServerProcess> server;
  {
    const StderrTo to(log);
    server = std::make_unique<ServerProcess>(
        kCli, std::vector<std::string>{"--tcp", "0", "--max-clients", "1000"},
        std::vector<std::string>{"/bin/sh", "-c", "ulimit -n 24 && exec \"$@\"", "sh"});
  }
  const std::vector<std::string> err = lines_of(slurp(log));
  ASSERT_EQ(err.size(), 1u) << slurp(log);
  // "... the descriptor limit is 24 (ulimit -n, hard limit 24) and K are in use or kept: at
  // most N clients", N = 24 - K; K is the 8 kept and those open (at least stdin, stdout,
  // stderr, the listener, the wake-up pipe's two ends and the spare: 7).
  const std::string head =
      "dpc31 serve: --max-clients 1000: the descriptor limit is 24 (ulimit -n, hard limit 24) "
      "and ";
  ASSERT_TRUE(starts_with(err[0], head)) << err[0];
  const std::vector<std::string> w = words(err[0].substr(head.size()));
  ASSERT_EQ(w.size(), 10u) << err[0];
  const int kept = std::stoi(w[0]);
  const int n = std::stoi(w[8]);
  EXPECT_GE(kept, 8 + 7);
  EXPECT_EQ(n, 24 - kept);
  EXPECT_EQ(err[0], head + fmt::format("{} are in use or kept: at most {} clients", kept, n));
  std::vector<LineClient> clients;
  for (int i = 0; i < n; ++i) {
    clients.push_back(LineClient::tcp(server->port()));
    EXPECT_EQ(clients.back().command("ping"), "OK pong") << i;
  }
  for (int i = 0; i < 20; ++i) {
    LineClient late = LineClient::tcp(server->port());
    EXPECT_EQ(late.read_line(), fmt::format("ERR busy too many clients (at most {})", n)) << i;
  }
  EXPECT_EQ(clients.front().command("ping"), "OK pong");
}

// The spare descriptor (lib/serve/serve_server.cpp, refuse_without_descriptor): when the limit
// falls below what --max-clients was fitted to (here lowered from outside with prlimit(2) once
// the server runs, as an administrator's `prlimit --pid` does), accept() fails with EMFILE. A
// newcomer then gets `ERR busy the server has no descriptor left for a client` at once instead of
// waiting unanswered in the backlog, the server keeps serving the clients it has, and a client
// that leaves makes room for the next one (docs/protocol.md, `--max-clients`).
TEST(ServeSecurity, ANewcomerWithoutADescriptorLeftIsToldBusyAndTheOthersGoOn) {
  ServerProcess server(kCli, {"--tcp", "0"});
  // A new descriptor takes the lowest free number, and RLIMIT_NOFILE bounds the numbers: a
  // limit of the lowest free number + 1 leaves room for one client (the spare, opened at the
  // start, lies below it).
  std::set<long> open;
  for (const auto& e :
       std::filesystem::directory_iterator(fmt::format("/proc/{}/fd", server.pid())))
    open.insert(std::stol(e.path().filename().string()));
  rlim_t lowest_free = 0;
  while (open.count(static_cast<long>(lowest_free)) != 0) ++lowest_free;
  const rlimit one_more{lowest_free + 1, lowest_free + 1};
  ASSERT_EQ(::prlimit(server.pid(), RLIMIT_NOFILE, &one_more, nullptr), 0) << std::strerror(errno);
  std::optional<LineClient> first = LineClient::tcp(server.port());
  EXPECT_EQ(first->command("ping"), "OK pong");
  for (int i = 0; i < 5; ++i) {
    LineClient late = LineClient::tcp(server.port());
    EXPECT_EQ(late.read_line(), "ERR busy the server has no descriptor left for a client") << i;
  }
  EXPECT_EQ(first->command("ping"), "OK pong");
  first.reset();
  // The first one's descriptor is free again once the server has seen it leave. A refused
  // newcomer reads its line unasked; an accepted one reads nothing until it asks.
  bool served = false;
  for (int i = 0; i < 50 && !served; ++i) {
    LineClient next = LineClient::tcp(server.port());
    std::optional<std::string> told;
    try {
      told = next.read_line(200);
    } catch (const std::runtime_error&) {
      served = next.command("ping") == "OK pong";
      continue;
    }
    EXPECT_EQ(told, "ERR busy the server has no descriptor left for a client") << i;
    std::this_thread::sleep_for(milliseconds(20));
  }
  EXPECT_TRUE(served);
}

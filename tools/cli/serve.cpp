#include "serve.hpp"

#include <fmt/core.h>

#include <atomic>
#include <cerrno>
#include <cstring>

#include "chip_choice.hpp"
#include "cleanup.hpp"
#include "dpc31/regdesc.hpp"
#include "numbers.hpp"
#include "path_option.hpp"
#include "serve_server.hpp"

namespace dpc31::cli {

namespace {

std::atomic<serve::Server*> g_server{nullptr};
std::atomic<bool> g_stop{false};  // a stop signal came before the server was there to tell

extern "C" void on_stop_signal(int /*sig*/) {
  g_stop.store(true);
  if (serve::Server* s = g_server.load()) s->stop();
}

// --cpu and the options that only go with it; "" or the one-line complaint.
std::string cpu_choice(const ServeArgs& a, serve::ServerOptions& opt) {
  if (a.cpu.empty()) {
    for (const auto& [name, given] :
         {std::pair{"--firmware", &a.firmware}, std::pair{"--code", &a.code},
          std::pair{"--board-address", &a.board_address}, std::pair{"--ports", &a.ports},
          std::pair{"--address", &a.address}}) {
      if (!given->empty()) return fmt::format("{} needs --cpu (docs/protocol.md)", name);
    }
    return {};
  }
  if (a.firmware.empty()) return "--cpu needs --firmware FILE.ihx, the CPU's Intel HEX image";
  serve::CpuSetup setup;
  if (std::string why = apply_cpu51_choice(cpu51_choice_of(a), opt.chip, setup.cfg, setup.image);
      !why.empty())
    return why;
  if (!a.address.empty()) setup.address = static_cast<std::uint8_t>(std::stoul(a.address));
  opt.cpu = std::move(setup);
  return {};
}

}  // namespace

CLI::App* add_serve_subcommand(CLI::App& app, ServeArgs& a) {
  auto* cmd = app.add_subcommand(
      "serve", "serve one chip over a line-based socket protocol (docs/protocol.md)");
  cmd->add_option("--tcp", a.tcp,
                  "listen on TCP: PORT (on 127.0.0.1) or ADDR:PORT; port 0 picks a free one")
      ->check(outfile::given());
  cmd->add_option("--unix", a.unix_path,
                  "listen on a Unix socket at this path (created mode 0600: this user only)")
      ->transform(outfile::named(outfile::Use::place));
  cmd->add_option("--state-dir", a.state_dir,
                  "the directory save and load may use (names relative to it); without it they "
                  "are refused")
      ->transform(outfile::named(outfile::Use::place));
  cmd->add_option("--secret-file", a.secret_file,
                  "TCP clients must send 'auth SECRET' first; SECRET is this file's first line "
                  "(16+ characters, file mode 600)")
      ->transform(outfile::named(outfile::Use::read));
  cmd->add_option("--profile", a.profile, "chip profile")
      ->check(CLI::IsMember({"spc3", "vpc3plus", "dpc31"}));
  cmd->add_option("--bus", a.bus, "bus byte order")->check(CLI::IsMember({"intel", "motorola"}));
  add_chip_options(cmd, a.chip);
  cmd->add_option("--cpu", a.cpu,
                  "80c32[:HZ]: run --firmware on an 80C32 beside the chip, the bus master; "
                  "c31[:HZ] (--profile dpc31): on the DPC31's own C31")
      ->check(outfile::given());
  cmd->add_option("--firmware", a.firmware, "with --cpu: the Intel HEX image (SDCC, Keil)")
      ->transform(outfile::named(outfile::Use::read));
  cmd->add_option("--code", a.code,
                  "with --cpu c31: the C31's code area in the chip's RAM (0x1000)")
      ->check(outfile::given());
  cmd->add_option("--board-address", a.board_address,
                  "with --cpu 80c32: the chip's 4 KB window in XDATA (0x8000)")
      ->check(outfile::given());
  cmd->add_option("--ports", a.ports,
                  "with --cpu 80c32: the board's output latch bytes (XDATA 4000h on) by name "
                  "(outputs,modul_ok)")
      ->check(outfile::given());
  cmd->add_option("--address", a.address,
                  "with --cpu: the station address on the address switch, port 1 (5)")
      ->transform(numbers::whole(0, 125));
  cmd->add_option("--max-clients", a.max_clients,
                  "connections at once; when full, the oldest one without its first line gives "
                  "way ('! bye max_clients'), else the newcomer gets 'ERR busy'")
      ->transform(numbers::whole(1, 100000))
      ->capture_default_str();
  cmd->add_option("--idle-timeout", a.idle_timeout,
                  "close a client after this many seconds without input (0 = never)")
      ->check(numbers::real(0.0, 1e7))
      ->capture_default_str();
  return cmd;
}

int run_serve(const ServeArgs& a, std::FILE* out, std::FILE* err) {
  serve::ServerOptions opt;
  parse_profile(a.profile, opt.chip.profile);  // CLI11's check already refused unknown names
  opt.chip.bus = a.bus == "intel" ? BusMode::intel : BusMode::motorola;
  if (const std::string why = apply_chip_choice(a.chip, opt.chip); !why.empty()) {
    fmt::print(err, "dpc31 serve: {}\n", why);
    return 2;
  }
  if (const std::string why = cpu_choice(a, opt); !why.empty()) {
    fmt::print(err, "dpc31 serve: {}\n", why);
    return 2;
  }
  if (!a.tcp.empty()) opt.tcp = a.tcp;
  if (!a.unix_path.empty()) opt.unix_path = a.unix_path;
  opt.max_clients = a.max_clients;
  opt.idle_timeout = a.idle_timeout;
  opt.log = err;
  if (!a.state_dir.empty()) opt.state_dir = a.state_dir;
  // Before anything is bound, so that a client that signals as soon as it reads the listening
  // line stops the server in order (exit 0, the socket removed) instead of killing it.
  // Its terminal closed (SIGHUP): a stop like the others, unless the signal was ignored at start.
  cleanup::stop_on_signals(on_stop_signal);
  try {
    if (!a.secret_file.empty()) opt.secret = serve::read_secret_file(a.secret_file);
    serve::Server server(opt);
    g_server.store(&server);
    const struct Unset {
      ~Unset() { g_server.store(nullptr); }
    } unset;
    if (g_stop.load()) server.stop();  // the handler ran before the store: run() returns at once
    for (const std::string& l : server.listening()) fmt::print(out, "{}\n", l);
    // Where it listens is what a client needs (port 0 picks one): unsaid, nobody can connect.
    errno = 0;
    if (std::fflush(out) != 0 || std::ferror(out) != 0) {
      fmt::print(err, "dpc31 serve: cannot write the standard output: {}\n",
                 std::strerror(errno != 0 ? errno : EIO));
      return 2;
    }
    return server.run();
  } catch (const serve::ServerError& e) {
    fmt::print(err, "dpc31 serve: {}\n", e.what());
    return 2;
  }
}

}  // namespace dpc31::cli

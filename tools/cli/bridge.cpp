#include "bridge.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>
#include <span>
#include <system_error>
#include <utility>

#include "../bridge/engine.hpp"
#include "../bridge/pacing.hpp"
#include "../bridge/pty.hpp"
#include "../bridge/tcp.hpp"
#include "numbers.hpp"
#include "outfile.hpp"
#include "path_option.hpp"
#include "pcapng.hpp"
#include "textfile.hpp"
#include "vocabulary.hpp"
#include "whole_number.hpp"

namespace dpc31::cli {

namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

// Loop period while a client is connected: the realtime lead (the chip runs this far ahead of
// the wall clock) and the latency of an answer at most.
constexpr milliseconds kTick{1};
// While no client is connected: how often the bridge looks for one (and runs the chip).
constexpr milliseconds kIdleTick{5};
// An incomplete telegram goes on the bus after the client paused this long.
constexpr milliseconds kPause{20};
// Realtime: falling this far behind the wall clock is reported (at most every 10 s).
constexpr milliseconds kLagReport{50};
// Free pacing: chip time one settle() may take (several requests in a row).
constexpr std::uint64_t kSettleSeconds = 1;

int g_signal_pipe[2] = {-1, -1};
volatile std::sig_atomic_t g_signal = 0;

extern "C" void on_signal(int sig) {
  g_signal = sig;
  const char c = 1;
  const int keep = errno;
  [[maybe_unused]] const ssize_t n = ::write(g_signal_pipe[1], &c, 1);
  errno = keep;
}

bool parse_uint(const std::string& s, std::uint64_t max, std::uint64_t& v) {
  return numbers::parse_whole(s, v) == std::errc{} && v <= max;
}

struct Checked {
  bridge::Setup setup;
  bool realtime = true;
  std::optional<bridge::ListenAddress> tcp;  // --tcp: a TCP port instead of the pty
};

// One --slave ADDR:FIRMWARE[:PROFILE[:VARIANT]][:OPTION=V...] (VARIANT: the VPC3+'s b|c|s, the
// DPC31's interrupt controller external|c31). "" or why not.
std::vector<std::string> slave_fields(const std::string& spec) {
  std::vector<std::string> f;
  for (std::size_t from = 0;;) {
    const std::size_t colon = spec.find(':', from);
    f.push_back(spec.substr(from, colon - from));
    if (colon == std::string::npos) return f;
    from = colon + 1;
  }
}

// The built-in user side's options after the positional fields of a --slave (user_wd=0|1,
// user_wd_value=N), checked as a segment scenario's `station` checks them. "" or why not.
std::string slave_options(const std::string& spec, std::span<const std::string> options,
                          bridge::SlaveSpec& s) {
  const auto key_of = [](const std::string& o) { return o.substr(0, o.find('=')); };
  // Before any other check, as the scenario's line: the last value would win silently.
  for (auto it = options.begin(); it != options.end(); ++it) {
    if (std::any_of(options.begin(), it,
                    [&](const std::string& o) { return key_of(o) == key_of(*it); })) {
      return fmt::format("--slave '{}': option '{}' given twice", spec, key_of(*it));
    }
  }
  bool value_given = false;
  for (const std::string& o : options) {
    const std::size_t eq = o.find('=');
    const std::string key = o.substr(0, eq);
    const std::string value = o.substr(eq + 1);
    std::uint64_t v = 0;
    if (s.firmware != nullptr && (key == "user_wd" || key == "user_wd_value")) {
      return fmt::format("--slave '{}': {}", spec, refused_beside_firmware(key));
    }
    if (key == "user_wd" && (value == "0" || value == "1")) {
      s.user_watchdog = value == "1";
    } else if (key == "user_wd") {
      return fmt::format("--slave '{}': bad value '{}' for user_wd: 0 or 1", spec, value);
    } else if (key == "user_wd_value" && parse_uint(value, 0xFFFF, v)) {
      s.user_wd_value = static_cast<std::uint16_t>(v);
      value_given = true;
    } else if (key == "user_wd_value") {
      return fmt::format("--slave '{}': user_wd_value '{}' must be 0..65535", spec, value);
    } else {
      return fmt::format("--slave '{}': unknown option '{}' (user_wd, user_wd_value)", spec, key);
    }
  }
  if (value_given && s.chip.profile == Profile::dpc31 && !s.user_watchdog) {
    return fmt::format("--slave '{}': {}", spec, user_wd_value_needs_user_wd("user_wd_value="));
  }
  return {};
}

std::string parse_slave(const std::string& spec, bridge::SlaveSpec& s) {
  std::vector<std::string> f = slave_fields(spec);
  // The fields with '=' after FIRMWARE (whose plug-in path may hold one) are options; they
  // follow the positional ones.
  const auto first_option =
      std::find_if(f.begin() + static_cast<std::ptrdiff_t>(std::min<std::size_t>(f.size(), 2)),
                   f.end(), [](const std::string& x) { return x.find('=') != std::string::npos; });
  const std::vector<std::string> options(first_option, f.end());
  f.erase(first_option, f.end());
  const std::string usage = fmt::format(
      "--slave '{}' must be ADDR:FIRMWARE[:PROFILE[:VARIANT]][:user_wd=0|1][:user_wd_value=N] "
      "(FIRMWARE {}, {} or a plug-in path; PROFILE spc3, vpc3plus, dpc31)",
      spec, bridge::kResponderName, builtin_firmware_names());
  const bool positional_after_option =
      std::any_of(options.begin(), options.end(),
                  [](const std::string& x) { return x.find('=') == std::string::npos; });
  if (f.size() < 2 || f.size() > 4 || f[1].empty() || positional_after_option) return usage;
  std::uint64_t v = 0;
  if (!parse_uint(f[0], 125, v)) {
    return fmt::format("--slave '{}': the address '{}' must be a station address 0..125", spec,
                       f[0]);
  }
  s.address = static_cast<std::uint8_t>(v);
  if (f.size() > 2 && !parse_profile(f[2], s.chip.profile)) {
    return fmt::format("--slave '{}': unknown profile '{}' (spc3, vpc3plus, dpc31)", spec, f[2]);
  }
  if (f.size() > 3) {
    // The field's own words: the --variant / --irq-controller the user never gave are not named.
    Vpc3Variant variant{};
    IrqController irq{};
    if (s.chip.profile == Profile::spc3) {
      return fmt::format("--slave '{}': the SPC3 has no variant", spec);
    }
    if (s.chip.profile == Profile::vpc3plus && parse_vpc3_variant(f[3], variant)) {
      s.chip.variant = variant;
    } else if (s.chip.profile == Profile::dpc31 && parse_irq_controller(f[3], irq)) {
      s.chip.irq_controller = irq;
    } else {
      return fmt::format(
          "--slave '{}': VARIANT '{}' of {} must be {}", spec, f[3], profile_name(s.chip.profile),
          s.chip.profile == Profile::vpc3plus ? "b, c or s"
                                              : "external or c31 (its interrupt controller)");
    }
  }
  if (f[1] != bridge::kResponderName) {
    try {
      s.firmware = &find_firmware(f[1], kHexAtSegment);
    } catch (const FirmwareError& e) {
      return fmt::format("--slave '{}': {}", spec, e.what());
    }
  }
  return slave_options(spec, options, s);
}

// One line on `err` and nullopt for a bad option.
std::optional<Checked> check(const BridgeOptions& o, std::FILE* err) {
  const auto bad = [err](const std::string& msg) {
    fmt::print(err, "dpc31 bridge: {}\n", shown_line(msg));
    return std::nullopt;
  };
  if (!o.extra.empty()) return bad(fmt::format("unexpected argument '{}'", o.extra.front()));
  Checked c;
  if (o.pty.empty() && o.tcp.empty()) {  // both given: CLI11 refused them (excludes)
    return bad(
        "one of --pty PATH (the symlink the master program opens) or --tcp [HOST:]PORT is "
        "required");
  }
  if (!o.tcp.empty()) {
    bridge::ListenAddress a;
    if (const std::string why = bridge::parse_listen(o.tcp, a); !why.empty()) {
      return bad(fmt::format("--tcp {}", why));
    }
    // The bridge has no authentication (docs/security.md): another host only when asked.
    if (!bridge::is_loopback(a.host) && !o.allow_remote) {
      return bad(fmt::format(
          "--tcp {}: not a loopback address; the bridge has no authentication, so listening "
          "where other hosts reach it needs --allow-remote (docs/security.md)",
          o.tcp));
    }
    c.tcp = a;
  } else if (o.allow_remote) {
    return bad("--allow-remote needs --tcp");
  }
  // Given, even as '', it is the firmware's to refuse ("unknown firmware ''", as in soak and demo).
  if (std::ranges::find(o.single, "--firmware") == o.single.end() && o.slaves.empty()) {
    return bad(
        fmt::format("--firmware (the one slave's: {} or a plug-in path) or --slave is required",
                    builtin_firmware_names()));
  }
  if (!o.slaves.empty() && !o.single.empty()) {
    return bad(fmt::format(
        "{} is for the one slave without --slave; --slave ADDR:FIRMWARE[:PROFILE[:VARIANT]] "
        "gives each station its address, firmware, profile and variant",
        o.single.front()));
  }
  // Truncating the mapped plug-in would end the process with SIGBUS.
  std::vector<outfile::Named> inputs{
      {"--firmware", is_plugin_path(o.firmware) || !o.cpu.empty() ? o.firmware : std::string()},
      {"the SDCC map", o.cpu.empty() ? std::string() : cpu51_map_path(o.firmware)},
      {"--pty", o.pty}};
  for (const std::string& spec : o.slaves) {
    bridge::SlaveSpec s;
    if (const std::string why = parse_slave(spec, s); !why.empty()) return bad(why);
    c.setup.slaves.push_back(s);
    if (const std::string fw = slave_fields(spec)[1]; is_plugin_path(fw)) {
      inputs.push_back({"--slave", fw});
    }
  }
  if (const std::string same = outfile::distinct(
          inputs, {{"--log", o.log}, {"--trace-cpu", o.trace_cpu}, {"--pcap", o.pcap}});
      !same.empty()) {
    return bad(same);
  }
  if (const std::string why = bridge::stations_problem(c.setup.slaves); !why.empty()) {
    return bad(why);
  }
  if ((o.trace_cpu_from || o.trace_cpu_to) && o.trace_cpu.empty()) {
    return bad(fmt::format("{} needs --trace-cpu",
                           o.trace_cpu_from ? "--trace-cpu-from" : "--trace-cpu-to"));
  }
  if (o.trace_cpu_from && o.trace_cpu_to && *o.trace_cpu_from >= *o.trace_cpu_to) {
    return bad(fmt::format("--trace-cpu-from {} must lie before --trace-cpu-to {}: an empty window",
                           *o.trace_cpu_from, *o.trace_cpu_to));
  }
  std::uint64_t v = 0;
  if (!o.slaves.empty()) {
    // Each station's chip, address and user side come from its --slave.
  } else if (!o.cpu.empty()) {  // --firmware is then its Intel HEX image
    if (o.firmware.empty()) return bad("--firmware: an empty file name: nothing can be read there");
    c.setup.cpu = Cpu51Config{};  // filled once the profile is known (below)
  } else {
    if (!o.trace_cpu.empty()) return bad("--trace-cpu needs --cpu");
    if (!o.ports.empty()) return bad("--ports needs --cpu 80c32");
    if (!o.code.empty() || !o.board_address.empty()) {
      return bad(fmt::format("{} needs --cpu", o.code.empty() ? "--board-address" : "--code"));
    }
    try {
      c.setup.firmware = &find_firmware(o.firmware);
    } catch (const FirmwareError& e) {
      return bad(e.what());
    }
  }
  if (const std::string e = not_a_profibus_rate(o.baud, c.setup.baud); !e.empty()) {
    return bad("--baud " + e);
  }
  if (!parse_profile(o.profile, c.setup.chip.profile)) {
    return bad(fmt::format("unknown profile '{}' (spc3, vpc3plus, dpc31)", o.profile));
  }
  if (const std::string why = apply_chip_choice(o.chip, c.setup.chip); !why.empty())
    return bad(why);
  // The CPU's choice needs the profile (the C31 is the dpc31's) and may set the controller.
  if (c.setup.cpu) {
    if (const std::string why =
            apply_cpu51_choice(cpu51_choice_of(o), c.setup.chip, *c.setup.cpu, c.setup.cpu_image);
        !why.empty()) {
      return bad(why);
    }
  }
  if (!parse_uint(o.address, 125, v)) {
    return bad(fmt::format("--address '{}' must be a station address 0..125", o.address));
  }
  c.setup.address = static_cast<std::uint8_t>(v);
  if (o.pacing != "realtime" && o.pacing != "free") {
    return bad(fmt::format("--pacing '{}' must be realtime or free", o.pacing));
  }
  c.realtime = o.pacing == "realtime";
  // A segment's range at every door (kSlotBits): under 37 no answer could come in time.
  if (!parse_uint(o.slot, kSlotBits.max, v) || !kSlotBits.holds(v)) {
    return bad(
        fmt::format("--slot '{}' must be {}..{} bit times", o.slot, kSlotBits.min, kSlotBits.max));
  }
  c.setup.slot_bits = static_cast<std::uint32_t>(v);
  if (o.log_level != "events" && o.log_level != "telegrams") {
    return bad(fmt::format("--log-level '{}' must be events or telegrams", o.log_level));
  }
  c.setup.log_detail =
      o.log_level == "events" ? bridge::LogDetail::events : bridge::LogDetail::telegrams;
  return c;
}

// Line 1 of the log: every setting that acts on this run, and only those (a variant only for
// the profile that has variants, the interrupt controller only for the dpc31). The address is the
// one the chip holds after the firmware's init (a plug-in may choose its own); an 80C32 has not
// run yet, so for it the address is what its switch on port 1 offers.
std::string profile_text(const ChipOptions& chip) {
  std::string profile(profile_name(chip.profile));
  if (chip.profile == Profile::vpc3plus) {
    profile +=
        fmt::format(", variant {}", vpc3_variant_name(chip.variant.value_or(Vpc3Variant::c)));
  }
  if (chip.profile == Profile::dpc31) {
    profile += fmt::format(", irq-controller {}", irq_controller_name(chip.irq_controller));
  }
  return profile;
}

// A firmware as line 1 names it: a plug-in by its descriptor name and the path it came from
// ("DO4 (./libdpc31_fw_do4.so)"), so that one that keeps a built-in's name is told from it.
std::string firmware_text(const dpc31_firmware& fw, const std::string& given) {
  return is_plugin_path(given) ? fmt::format("{} ({})", fw.name, given) : std::string(fw.name);
}

// With --slave: each station in the order given, "slave5 (profile dpc31, irq-controller
// external, firmware DO4)".
std::string header(const Checked& c, const BridgeOptions& o, const std::string& port,
                   const bridge::Engine& e) {
  if (!c.setup.slaves.empty()) {
    std::string stations;
    for (std::size_t i = 0; i < c.setup.slaves.size(); ++i) {
      const bridge::SlaveSpec& s = c.setup.slaves[i];
      stations += fmt::format("{}{} (profile {}, firmware {})", i == 0 ? "" : ", ",
                              e.stations()[i].name, profile_text(s.chip),
                              s.firmware != nullptr
                                  ? firmware_text(*s.firmware, slave_fields(o.slaves[i])[1])
                                  : std::string(bridge::kResponderName));
    }
    return fmt::format(
        "dpc31 bridge: pacing {}, baud {}, {} slave{}: {}, slot {} bit times, log level {}, {}",
        c.realtime ? "realtime" : "free", c.setup.baud, c.setup.slaves.size(),
        c.setup.slaves.size() == 1 ? "" : "s", stations, c.setup.slot_bits, o.log_level, port);
  }
  const Chip& chip_after_init = e.chip();
  const std::string profile = profile_text(c.setup.chip);
  return fmt::format(
      "dpc31 bridge: pacing {}, baud {}, profile {}, firmware {}, {}, slot {} bit times, "
      "log level {}, {}",
      c.realtime ? "realtime" : "free", c.setup.baud, profile,
      c.setup.cpu ? fmt::format("{} on {} at {} Hz{}", o.firmware,
                                c.setup.cpu->c31 ? "the C31" : "an 80C32", c.setup.cpu->hz,
                                symbols_text(c.setup.cpu_image))
                  : firmware_text(*c.setup.firmware, o.firmware),
      c.setup.cpu ? fmt::format("address switch {} (port 1)", c.setup.address)
                  : fmt::format("address {}", chip_after_init.station_address()),
      c.setup.slot_bits, o.log_level, port);
}

class Log {
 public:
  explicit Log(std::FILE* f) : f_(f) {}
  // A write that fails (a full disk) is kept: the bridge stops on it with exit 2.
  void line(const std::string& text) {
    if (errno_ != 0) return;
    errno = 0;
    if (std::fputs(text.c_str(), f_) < 0 || std::fputc('\n', f_) == EOF || std::fflush(f_) != 0) {
      errno_ = errno != 0 ? errno : EIO;
    }
  }
  [[nodiscard]] int failed() const { return errno_; }
  void event(std::uint64_t cycle, std::string_view tag, std::string_view station,
             const std::string& text) {
    line(fmt::format("{:>12} {:<5} {:<8} {}", cycle, tag, station, text));
  }

 private:
  std::FILE* f_;
  int errno_ = 0;
};

class SignalGuard {
 public:
  SignalGuard() {
    if (::pipe2(g_signal_pipe, O_NONBLOCK | O_CLOEXEC) != 0) return;
    struct sigaction sa {};
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    // A signal ignored at start stays ignored (`nohup dpc31 bridge ... &` survives its terminal's
    // hangup), as cleanup::install() and `serve` leave it.
    for (auto [sig, old] : {std::pair{SIGINT, &old_int_}, std::pair{SIGTERM, &old_term_},
                            std::pair{SIGHUP, &old_hup_}}) {
      sigaction(sig, nullptr, old);
      if (old->sa_handler != SIG_IGN) sigaction(sig, &sa, nullptr);
    }
    ok_ = true;
  }
  ~SignalGuard() {
    if (!ok_) return;
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
    sigaction(SIGHUP, &old_hup_, nullptr);
    ::close(g_signal_pipe[0]);
    ::close(g_signal_pipe[1]);
    g_signal_pipe[0] = g_signal_pipe[1] = -1;
  }
  SignalGuard(const SignalGuard&) = delete;
  SignalGuard& operator=(const SignalGuard&) = delete;
  [[nodiscard]] bool ok() const { return ok_; }

 private:
  bool ok_ = false;
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
  struct sigaction old_hup_ {};
};

// --trace-cpu (docs/cpu.md, "The CPU trace"): each line starts with the chip cycle of the step's
// first clock and its machine cycle; an instruction is "PC OPCODE NAME", the hardware LCALL of
// an interrupt "interrupt SOURCE VECTOR from PC NAME", and a stretch of idle (or power-down)
// machine cycles one line "idle N machine cycles to CHIP_CYCLE MACHINE_CYCLE" (the first after
// it): one line per idle cycle flooded the file with steps of the instruction at PC. Only the lines
// whose first chip cycle lies in [from, to) are written (--trace-cpu-from, --trace-cpu-to).
class CpuTrace {
 public:
  CpuTrace(Cpu51Board& board, const Cpu51Image& image, std::FILE* f, std::uint64_t from,
           std::uint64_t to)
      : board_(board), image_(image), f_(f), from_(from), to_(to) {
    board.on_step = [this](std::uint16_t pc, std::uint64_t cycle) { step(pc, cycle); };
  }
  CpuTrace(const CpuTrace&) = delete;
  CpuTrace& operator=(const CpuTrace&) = delete;
  ~CpuTrace() { board_.on_step = nullptr; }

  // The stretch the CPU is in when the bridge stops.
  void finish() { end_stretch(board_.cpu().cycles()); }

 private:
  enum class Waiting : std::uint8_t { none, idle, power_down };

  [[nodiscard]] std::uint64_t chip_cycle(std::uint64_t machine_cycle) const {
    return board_.chip_cycle_of(machine_cycle * mcs51::clocks_per_cycle);
  }
  [[nodiscard]] bool shown(std::uint64_t machine_cycle) const {
    const std::uint64_t c = chip_cycle(machine_cycle);
    return c >= from_ && c < to_;
  }
  void step(std::uint16_t pc, std::uint64_t cycle) {
    const mcs51::Cpu& cpu = board_.cpu();
    // The step's kind as Cpu::step will take it: power-down, then a due call, then idle.
    const Waiting w = cpu.powered_down()                   ? Waiting::power_down
                      : !cpu.interrupt_due() && cpu.idle() ? Waiting::idle
                                                           : Waiting::none;
    if (w == waiting_ && w != Waiting::none) return;
    end_stretch(cycle);
    waiting_ = w;
    since_ = cycle;
    if (w != Waiting::none || !shown(cycle)) return;
    if (cpu.interrupt_due()) {
      static constexpr std::array<const char*, 6> kSource{"ie0", "tf0",    "ie1",
                                                          "tf1", "serial", "timer2"};
      const auto source = static_cast<unsigned>(cpu.due_source());
      fmt::print(f_, "{} {} interrupt {} {:04X} from {:04X} {}\n", chip_cycle(cycle), cycle,
                 kSource.at(source), 3 + 8 * source, pc, code_name(image_, pc));
      return;
    }
    fmt::print(f_, "{} {} {:04X} {:02X} {}\n", chip_cycle(cycle), cycle, pc, cpu.code(pc),
               code_name(image_, pc));
  }
  void end_stretch(std::uint64_t cycle) {
    if (waiting_ == Waiting::none) return;
    if (shown(since_))
      fmt::print(f_, "{} {} {} {} machine cycles to {} {}\n", chip_cycle(since_), since_,
                 waiting_ == Waiting::idle ? "idle" : "power-down", cycle - since_,
                 chip_cycle(cycle), cycle);
    waiting_ = Waiting::none;
  }

  Cpu51Board& board_;
  const Cpu51Image& image_;
  std::FILE* f_;
  std::uint64_t from_, to_;
  Waiting waiting_ = Waiting::none;
  std::uint64_t since_ = 0;  // the stretch's first machine cycle
};

class Bridge {
 public:
  Bridge(const Checked& c, bridge::ClientPort& port, Log& log)
      : realtime_(c.realtime), port_(port), log_(log) {
    engine_ = std::make_unique<bridge::Engine>(
        c.setup, [this](std::uint64_t cycle, std::string_view tag, std::string_view station,
                        const std::string& text) { log_.event(cycle, tag, station, text); });
  }

  // Returns the exit code.
  int run() {
    const std::uint32_t f = engine_->chip().clock_hz();
    bridge::Pacing pacing(realtime_, f, kIdleTick);
    const Clock::time_point start = Clock::now();
    pacing.anchor(start, engine_->cycle());
    last_input_ = start;
    Clock::time_point last_lag_report = start - std::chrono::hours(1);
    engine_->note("waiting for a client");
    while (g_signal == 0) {
      if (log_.failed() != 0) return 2;
      const Clock::time_point now = Clock::now();
      Clock::duration wait = port_.present() ? kTick : kIdleTick;
      if (engine_->partial()) {
        if (now - last_input_ >= kPause) {
          engine_->flush_partial();
        } else {
          wait = std::min(wait, kPause - (now - last_input_));
        }
      }
      // Realtime runs the chip to the wall-clock time of the next wake-up, so chip time never
      // falls behind the wall clock; free runs it to now, and settle() lets an exchange take no
      // wall time (chip time then runs ahead by the exchanges' durations). A bounded turn either
      // way (bridge::Pacing).
      const std::uint64_t target = pacing.target(now, wait, engine_->cycle());
      if (target > engine_->cycle()) engine_->run_until(target);
      if (!realtime_ && engine_->busy()) {
        engine_->settle(kSettleSeconds * f);
        pacing.anchor(Clock::now(), engine_->cycle());
      }
      deliver();
      if (port_.sent_all()) {
        // A half-closed client (`nc -N`): no more bytes come, so an incomplete telegram goes out
        // now; the connection closes once every request it sent is answered (or timed out).
        if (engine_->partial()) engine_->flush_partial();
        if (!engine_->busy()) port_.hang_up(events_);
      }
      const Clock::time_point after = Clock::now();
      if (realtime_) {
        const std::uint64_t wall = pacing.wall_cycle(after);
        if (wall > engine_->cycle() + pacing.cycles(kLagReport) &&
            after - last_lag_report > std::chrono::seconds(10)) {
          engine_->note(fmt::format("running {} ms behind the wall clock",
                                    (wall - engine_->cycle()) / (f / 1000)));
          last_lag_report = after;
        }
        const Clock::time_point until = now + wait;  // the wake-up the chip ran to
        wait = until > after ? until - after : Clock::duration::zero();
      } else {
        wait = engine_->busy() ? Clock::duration::zero() : wait;
      }
      if (!wait_events(wait)) return 1;
    }
    engine_->note(fmt::format("stopping on {}", g_signal == SIGINT    ? "SIGINT"
                                                : g_signal == SIGTERM ? "SIGTERM"
                                                                      : "SIGHUP"));
    engine_->flush_log();
    return 0;
  }

  bridge::Engine& engine() { return *engine_; }

 private:
  // Writes what the chip sent to the client (if there is one).
  void deliver() {
    const std::vector<std::uint8_t> out = engine_->take_output();
    if (!port_.present()) {
      // The answer to a request the last client left on the line: one line when it is over
      // (its bytes come over several loop turns), stamped then, not when the next client comes.
      dropped_ += out.size();
      if (dropped_ != 0 && !engine_->busy()) {
        engine_->note(fmt::format("no client: {} answer bytes dropped", dropped_));
        dropped_ = 0;
      }
      return;
    }
    if (out.empty()) return;
    const std::size_t n = port_.write(out);
    if (n < out.size()) {
      engine_->note(
          fmt::format("the client does not read: {} answer bytes dropped", out.size() - n));
    }
  }

  // Polls the port's descriptors (the pty only while a client is connected: with no slave fd
  // open the master reports POLLHUP continuously) and the signal pipe, then lets the port look.
  bool wait_events(Clock::duration wait) {
    std::vector<pollfd> fds{{g_signal_pipe[0], POLLIN, 0}};
    const std::vector<pollfd> own = port_.poll_fds();
    fds.insert(fds.end(), own.begin(), own.end());
    const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(wait).count();
    const timespec ts{static_cast<time_t>(ns / 1'000'000'000),
                      static_cast<long>(ns % 1'000'000'000)};
    const int r = ::ppoll(fds.data(), fds.size(), &ts, nullptr);
    if (r < 0 && errno != EINTR) {
      engine_->note(fmt::format("poll: {}", std::strerror(errno)));
      return false;
    }
    if (g_signal != 0) return true;
    try {
      port_.service(std::span(fds).subspan(1), events_);
    } catch (const bridge::PtyError& e) {
      engine_->note(fmt::format("{}: {}", port_.describe(), e.what()));
      return false;
    }
    return true;
  }

  bool realtime_;
  bridge::ClientPort& port_;
  Log& log_;
  std::unique_ptr<bridge::Engine> engine_;
  const bridge::PortEvents events_{
      .bytes =
          [this](std::span<const std::uint8_t> b) {
            last_input_ = Clock::now();
            engine_->feed(b);
          },
      .gone = [this] { engine_->client_gone(); },
      .note = [this](const std::string& text) { engine_->note(text); }};
  Clock::time_point last_input_;
  std::size_t dropped_ = 0;  // answer bytes dropped (no client) and not yet logged
};

}  // namespace

CLI::App* add_bridge_subcommand(CLI::App& app, BridgeOptions& o) {
  auto* b = app.add_subcommand("bridge",
                               "the RS-485 line of one slave (or of several, --slave) as a "
                               "pseudo-terminal or a loopback TCP port for a DP master program");
  auto* pty = b->add_option("--pty", o.pty,
                            "symlink to create to the pty's slave side (or --tcp); an existing "
                            "PATH must be a symlink into /dev/pts/ (a bridge's)")
                  ->transform(outfile::named(outfile::Use::place));
  b->add_option("--tcp", o.tcp,
                "[HOST:]PORT: a raw TCP port instead of the pty (127.0.0.1 unless HOST; 0: any "
                "free port, named in the log)")
      ->check(outfile::given())
      ->excludes(pty);
  b->add_flag("--allow-remote", o.allow_remote,
              "let --tcp listen on an address other hosts reach (no authentication!)");
  b->add_option("--pcap", o.pcap, "write every telegram on the line here as pcapng at the end")
      ->transform(outfile::named(outfile::Use::write));
  b->add_option("--baud", o.baud, "baud rate of the bus (a PROFIBUS rate)")->capture_default_str();
  b->add_option("--profile", o.profile, "chip profile: spc3, vpc3plus, dpc31")
      ->capture_default_str();
  add_chip_options(b, o.chip);
  b->add_option("--firmware", o.firmware,
                "firmware: " + builtin_firmware_names() +
                    ", or a plug-in ./libmine.so (required without --slave, refused with it: "
                    "each --slave names its station's)");
  b->add_option("--cpu", o.cpu,
                "80c32[:HZ]: run --firmware, an Intel HEX image, on an 80C32 beside the chip; "
                "c31[:HZ] (--profile dpc31): on the DPC31's own C31")
      ->check(outfile::given());
  b->add_option("--code", o.code, "with --cpu c31: the C31's code area in the chip's RAM (0x1000)")
      ->check(outfile::given());
  b->add_option("--board-address", o.board_address,
                "with --cpu 80c32: the chip's 4 KB window in XDATA (0x8000)")
      ->check(outfile::given());
  b->add_option("--trace-cpu", o.trace_cpu, "write every CPU instruction with its cycle here")
      ->transform(outfile::named(outfile::Use::write));
  b->add_option("--trace-cpu-from", o.trace_cpu_from,
                "with --trace-cpu: only the steps from this chip cycle on")
      ->transform(numbers::whole(0));
  b->add_option("--trace-cpu-to", o.trace_cpu_to,
                "with --trace-cpu: only the steps before this chip cycle")
      ->transform(numbers::whole(0));
  b->add_option("--ports", o.ports,
                "N1,N2...: the 80C32 board's output latch bytes (XDATA 4000h on) by name; "
                "default DO4's: outputs,modul_ok")
      ->check(outfile::given());
  b->add_option("--address", o.address, "station address 0..125")->capture_default_str();
  b->add_option("--slave", o.slaves,
                "ADDR:FIRMWARE[:PROFILE[:VARIANT]][:user_wd=0|1][:user_wd_value=N], repeated: "
                "several stations on the one line (FIRMWARE responder for the built-in user "
                "side, whose user watchdog user_wd=1 serves; instead of --firmware, --address, "
                "--profile)")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  b->add_option("--pacing", o.pacing,
                "realtime: chip time follows the wall clock; free: "
                "exchanges take no wall time")
      ->capture_default_str();
  b->add_option("--slot", o.slot, "slot time in bit times: how long a request waits for an answer")
      ->capture_default_str();
  b->add_option("--log", o.log, "write the log to this file instead of stdout")
      ->transform(outfile::named(outfile::Use::write));
  b->add_option("--log-level", o.log_level,
                "events: state changes and faults; telegrams: also every telegram and port write")
      ->capture_default_str();
  b->allow_extras();
  b->callback([b, &o] {
    o.extra = b->remaining();
    for (const char* name : {"--firmware", "--address", "--profile", "--variant",
                             "--irq-controller", "--cpu", "--code", "--board-address",
                             "--trace-cpu", "--trace-cpu-from", "--trace-cpu-to", "--ports"}) {
      if (b->get_option(name)->count() > 0) o.single.emplace_back(name);
    }
  });
  return b;
}

namespace {

// The client's door: the pty (and its symlink, removed on every way out) or the TCP port.
struct Door {
  std::unique_ptr<bridge::Pty> pty;
  std::unique_ptr<bridge::ClientPort> port;
  std::string link;  // the --pty symlink, "" for TCP
  Door() = default;
  Door(const Door&) = delete;
  Door& operator=(const Door&) = delete;
  ~Door() {
    if (pty) bridge::remove_link(link, pty->slave_name());
  }
};

// One line on `err` and false when the door cannot be opened.
bool open_door(const Checked& c, const BridgeOptions& o, Door& d, std::FILE* err) {
  try {
    if (c.tcp) {
      d.port = std::make_unique<bridge::TcpPort>(*c.tcp);
      return true;
    }
    d.pty = std::make_unique<bridge::Pty>();
  } catch (const bridge::PtyError& e) {
    fmt::print(err, "dpc31 bridge: cannot set up {}: {}\n",
               c.tcp ? "the TCP port" : "a pseudo-terminal", e.what());
    return false;
  }
  if (const std::string why = bridge::make_link(o.pty, d.pty->slave_name()); !why.empty()) {
    fmt::print(err, "dpc31 bridge: {}\n", shown_line(why));  // a name's newline: still one line
    return false;
  }
  d.link = o.pty;
  d.port = std::make_unique<bridge::PtyPort>(*d.pty, o.pty, c.setup.baud);
  return true;
}

// --pcap: every telegram on the line, timestamped from line time (docs/capture.md), the sender
// named in the packet's comment and its direction (inbound: the master's; outbound: a station's).
void capture_line(bridge::Engine& e, capture::PcapngWriter& pcap) {
  const std::uint32_t hz = e.chip().clock_hz();
  e.on_line([&pcap, hz](const bridge::LineTelegram& t) {
    const std::optional<std::uint64_t> ns = capture::cycles_to_ns(t.start, hz);
    if (!ns) return;  // beyond 584 years of chip time
    pcap.add(capture::Packet{.timestamp_ns = *ns,
                             .direction = t.sender == bridge::kMasterName
                                              ? capture::Direction::inbound
                                              : capture::Direction::outbound,
                             .bytes = t.bytes,
                             .comment = fmt::format("cycles {}-{}, {}", t.start, t.end, t.sender)});
  });
}

}  // namespace

int run_bridge(const BridgeOptions& o, std::FILE* out, std::FILE* err) {
  const std::optional<Checked> c = check(o, err);
  if (!c) return 2;
  Door door;
  if (!open_door(*c, o, door, err)) return 2;
  SignalGuard signals;
  if (!signals.ok()) {
    fmt::print(err, "dpc31 bridge: cannot install the signal handlers: {}\n", std::strerror(errno));
    return 2;
  }
  // The log is live (a master's user tails it), so it is not written through a temporary; it is
  // opened last, when every input has been checked, so that bad input never creates it.
  std::FILE* log_file = out;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> owned(nullptr, std::fclose);
  const auto refuse = [&](const std::string& why) {
    fmt::print(err, "dpc31 bridge: {}\n", why);
    return 2;
  };
  // The outputs written through temporaries first: one that cannot be written leaves an earlier
  // session's log as it was (s33 audit finding 5), and a refused log leaves no temporary.
  outfile::OutFile trace;
  if (!o.trace_cpu.empty() && !trace.open(o.trace_cpu)) return refuse(trace.error());
  capture::PcapngWriter pcap;
  if (!o.pcap.empty() && !pcap.open(o.pcap)) return refuse(pcap.error());
  if (!o.log.empty()) {
    if (std::string foreign = outfile::foreign_symlink(o.log); !foreign.empty()) {
      return refuse(foreign);
    }
    owned.reset(outfile::open_live(o.log));
    // A FIFO waits in open() for its reader: a stop signal then is a stop, not a failed log.
    if (!owned && errno == EINTR && g_signal != 0) return 0;
    if (!owned) {
      return refuse(fmt::format("cannot write the log {}: {}", o.log, std::strerror(errno)));
    }
    // The log into the bridge's own pty would be read back as telegrams by the master side.
    struct stat log_st {};
    struct stat pty_st {};
    if (door.pty && ::fstat(::fileno(owned.get()), &log_st) == 0 &&
        ::stat(door.pty->slave_name().c_str(), &pty_st) == 0 && log_st.st_dev == pty_st.st_dev &&
        log_st.st_ino == pty_st.st_ino) {
      return refuse(
          fmt::format("--log {}: is the bridge's own pseudo-terminal {}: the log would "
                      "feed back into it",
                      o.log, door.pty->slave_name()));
    }
    log_file = owned.get();
  }
  Log log(log_file);
  // A firmware stuck in a loop without a bus access cannot be stopped from this thread: the guard
  // ends the process with one line (and takes the symlink away first).
  // Its line goes into the --log too, as a firmware fault's does.
  const int log_fd = owned ? ::fileno(owned.get()) : -1;
  if (!c->setup.slaves.empty()) {
    // Every station's firmware is guarded; the built-in user side always makes bus accesses.
    for (const bridge::SlaveSpec& s : c->setup.slaves) {
      if (s.firmware != nullptr) {
        board::guard_hangs("dpc31 bridge", s.firmware->name, door.link, board::kHangLimit, log_fd);
      }
    }
  } else if (!c->setup.cpu) {
    board::guard_hangs("dpc31 bridge", c->setup.firmware->name, door.link, board::kHangLimit,
                       log_fd);
  }
  int rc = 0;
  try {
    Bridge b(*c, *door.port, log);
    log.line(header(*c, o, door.port->describe(), b.engine()));
    std::optional<CpuTrace> cpu_trace;
    if (trace.is_open()) {
      cpu_trace.emplace(b.engine().cpu51()->board(), c->setup.cpu_image, trace.stream(),
                        o.trace_cpu_from.value_or(0), o.trace_cpu_to.value_or(UINT64_MAX));
    }
    if (pcap.is_open()) capture_line(b.engine(), pcap);
    rc = b.run();
    if (cpu_trace) cpu_trace->finish();
  } catch (const FirmwareError& e) {
    log.line(fmt::format("dpc31 bridge: {}", e.what()));
    return refuse(e.what());
  } catch (const std::system_error& e) {
    // fmt::print throws where the trace's write fails (a full disk, ulimit -f): the file named,
    // as every output's (docs/bad-input.md, "Output files"); its temporary goes with `trace`.
    if (!trace.is_open() || std::ferror(trace.stream()) == 0) throw;
    return refuse(fmt::format("{}: cannot write: {}", o.trace_cpu, e.code().message()));
  }
  // The log's failure stopped the bridge: said first, and the outputs are not written (their
  // temporaries go with them), as after any failed write.
  if (log.failed() != 0) {
    fmt::print(err, "dpc31 bridge: cannot write the log {}: {}\n",
               o.log.empty() ? std::string("to the standard output") : o.log,
               std::strerror(log.failed()));
    return 2;
  }
  if (trace.is_open() && !trace.commit()) return refuse(trace.error());
  if (pcap.is_open() && !pcap.close()) return refuse(pcap.error());
  if (rc != 0) fmt::print(err, "dpc31 bridge: stopped on an error (see the log)\n");
  return rc;
}

}  // namespace dpc31::cli

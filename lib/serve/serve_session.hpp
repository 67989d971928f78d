// The command interpreter of `dpc31 serve` (docs/protocol.md): one chip, one line in, one reply
// line out. No sockets here: the server (serve_server.hpp) feeds it lines and distributes what it
// emits, so the interpreter can be driven and tested on its own.
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "dpc31/chip.hpp"
#include "dpc31/log.hpp"
#include "serve_cpu.hpp"
#include "state_dir.hpp"

namespace dpc31::serve {

// Bumped on every incompatible change of docs/protocol.md; `info` reports it. 2: save/load
// names are relative to --state-dir (refused without it), the first line must be a command or
// `auth` (issue 14).
inline constexpr int kProtocolVersion = 2;

// Limits of single commands (docs/protocol.md, "Limits").
inline constexpr std::uint64_t kMaxStep = std::uint64_t{1} << 40;  // cycles per step/run_until_irq
// With --cpu the CPU runs too, about 4 times real time where the chip alone runs some 20 000
// (an idle 80C32 at 24 MHz): 2^30 cycles, 22 s of chip time, is some 5 s of the server's time.
inline constexpr std::uint64_t kMaxStepCpu = std::uint64_t{1} << 30;
inline constexpr std::size_t kMaxBlock = 4096;            // bytes per *block command
inline constexpr std::size_t kMaxInject = 1024;           // bytes per inject
inline constexpr std::uint32_t kMaxIdleBits = 1'000'000;  // inject idle=
// Injected bytes and telegrams not yet on the line (their END still ahead of the chip's cycle):
// one more `inject` is `ERR queue_full` (docs/protocol.md, "Limits"). Each queued byte holds
// about 11 RxD edges and a received character in the chip (some 250 bytes of memory).
inline constexpr std::size_t kMaxInjectQueueBytes = 16u << 10;
inline constexpr std::size_t kMaxInjectQueue = 256;

// The command words, in `help`'s order.
inline constexpr std::string_view kCommandNames =
    "help info ping cycle status read write peek poke readblock writeblock peekblock pokeblock "
    "addr peek_reg poke_reg step run_until_irq reset inject inject_fdl counters log save load "
    "auth quit shutdown cpu cpu_port latch";
// Whether `word` is one of kCommandNames.
bool is_command(std::string_view word);

// A line that is not the reply to a command ("! ..."), as the chip produced it.
struct AsyncLine {
  enum class Kind : std::uint8_t { irq, pb3, telegram, log, port } kind;
  LogLevel level;    // kind log only
  std::string text;  // without the newline
};

// What one client asked for that outlives a command.
struct ClientState {
  std::optional<LogLevel> log_level;  // forward chip log records at or above; nullopt = none
};

class Session {
 public:
  enum class Action : std::uint8_t { none, quit, shutdown };
  struct Result {
    std::string reply;  // "OK ..." or "ERR <code> <message>", without the newline
    Action action = Action::none;
  };

  // `emit` receives every async line at the moment the chip produces it, so they reach clients
  // before the reply of the command during which they happened.
  Session(ChipOptions opt, std::function<void(const AsyncLine&)> sink);

  // Executes one line (without its newline; a trailing CR is ignored).
  Result execute(std::string_view line, ClientState& client);
  // The client goes: the log level it asked for no longer counts (show_log).
  void leave(ClientState& client);

  Chip& chip() { return chip_; }

  // `dpc31 serve --cpu`: the CPU runs the image as the chip's bus master from now on (before the
  // first command: the chip is still at cycle 0); `! port` lines tell of its latch writes.
  void attach_cpu(CpuSetup setup);

  // Where `save` and `load` may go; without one they are refused (`ERR denied`).
  void set_state_dir(StateDir dir) { state_dir_ = std::move(dir); }

  // Injected bytes and telegrams still ahead of the chip's cycle (the queue kMaxInjectQueue*
  // bound).
  [[nodiscard]] std::size_t inject_queue_bytes();
  [[nodiscard]] std::size_t inject_queue_telegrams();

 private:
  void emit(AsyncLine::Kind kind, std::string text, LogLevel level = LogLevel::info);
  // `client` asks for the chip's log from `level` up (none: off).
  void follow_log(ClientState& client, std::optional<LogLevel> level);
  // The chip's log sink shows the lowest level any client asked for and up (none asked: no
  // sink), so its repeat counts are those of the lines a client may see (Chip::set_log_sink).
  void show_log();
  [[nodiscard]] std::uint32_t default_bit_cycles() const;
  [[nodiscard]] std::uint32_t address_limit() const;
  // Forgets the injected telegrams whose END the chip has reached.
  void prune_injected();
  void clear_injected();

  Chip chip_;
  std::function<void(const AsyncLine&)> emit_;
  std::uint64_t rx_free_ = 0;  // end of the last injected telegram: RxD is ours until then
  std::deque<std::pair<std::uint64_t, std::size_t>> injected_;  // END, bytes; oldest first
  std::size_t injected_bytes_ = 0;
  StateDir state_dir_;
  std::vector<std::string_view> tokens_;      // the words of the line being executed
  std::unique_ptr<BoardCpu> cpu_;             // --cpu: the bus master
  std::array<std::size_t, 4> log_clients_{};  // per LogLevel: the clients that asked for it
  std::optional<LogLevel> log_shown_;         // the lowest of them, what the chip's sink shows
};

}  // namespace dpc31::serve

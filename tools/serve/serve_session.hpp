// The command interpreter of `dpc31 serve` (docs/protocol.md): one chip, one line in, one reply
// line out. No sockets here: the server (serve_server.hpp) feeds it lines and distributes what it
// emits, so the interpreter can be driven and tested on its own.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

#include "dpc31/chip.hpp"
#include "dpc31/log.hpp"

namespace dpc31::serve {

// Bumped on every incompatible change of docs/protocol.md; `info` reports it.
inline constexpr int kProtocolVersion = 1;

// Limits of single commands (docs/protocol.md, "Limits").
inline constexpr std::uint64_t kMaxStep = std::uint64_t{1} << 40;  // cycles per step/run_until_irq
inline constexpr std::size_t kMaxBlock = 4096;                     // bytes per *block command
inline constexpr std::size_t kMaxInject = 1024;                    // bytes per inject
inline constexpr std::uint32_t kMaxIdleBits = 1'000'000;           // inject idle=

// A line that is not the reply to a command ("! ..."), as the chip produced it.
struct AsyncLine {
  enum class Kind : std::uint8_t { irq, telegram, log } kind;
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

  Chip& chip() { return chip_; }

 private:
  void emit(AsyncLine::Kind kind, std::string text, LogLevel level = LogLevel::info);
  // After reset / load: report a changed interrupt level the chip did not report itself.
  void resync_irq();
  [[nodiscard]] std::uint32_t default_bit_cycles() const;
  [[nodiscard]] std::uint32_t address_limit() const;

  Chip chip_;
  std::function<void(const AsyncLine&)> emit_;
  bool irq_reported_ = false;  // the interrupt level the clients were last told
  std::uint64_t rx_free_ = 0;  // end of the last injected telegram: RxD is ours until then
};

}  // namespace dpc31::serve

// `dpc31 serve --cpu` (docs/protocol.md, "A CPU on the bus"): an 80C32 beside the served chip or
// the DPC31's C31 running an Intel HEX image. The CPU is then the chip's bus master: time moves
// only inside a client's command, and the CPU runs in the same time base as the chip.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>

#include "cpu51_module.hpp"
#include "dpc31/chip.hpp"
#include "dpc31/log.hpp"

namespace dpc31::serve {

// What the command line chose and loaded (apply_cpu51_choice).
struct CpuSetup {
  Cpu51Config cfg;
  Cpu51Image image;
  std::uint8_t address = 5;  // the address switch on port 1
};

class BoardCpu {
 public:
  // `port_line` receives "! port CYCLE NAME 0xVV" for the writes of the board's output latch,
  // at most LogLimiter::kBurst in each LogLimiter::kWindow chip cycles, and "! port_log CYCLE
  // TEXT" for how many it left out (the walk's bound, docs/decisions.md "Logs that never flood");
  // "! serial CYCLE 0xVV" for each character the CPU's serial port sent, bounded the same way
  // ("! serial_log CYCLE TEXT").
  BoardCpu(Chip& chip, CpuSetup setup, std::function<void(std::string)> port_line);
  BoardCpu(const BoardCpu&) = delete;
  BoardCpu& operator=(const BoardCpu&) = delete;

  // CPU and chip together until the chip reaches `cycle` (Cpu51Board::run_until: exactly, but
  // for a MOVX to the chip whose access starts before it).
  void run_until(std::uint64_t cycle);
  // The same, ending after the CPU's step in which the interrupt became active (true).
  bool run_until_irq(std::uint64_t cycle);
  // `reset`: the board's RESET, CPU and chip together at the chip's cycle (Cpu51Board::reset).
  void reset() { module_->board().reset(); }
  // `cpu`: "core=80c32 hz=F pc=0x.. a=.. b=.. psw=.. sp=.. dptr=.. r0=.. .. r7=.. ie=.. ip=..
  // in_service=N idle=0|1 machine_cycles=N".
  [[nodiscard]] std::string registers() const;
  // `cpu_port N`: "latch=0xVV pins=0xVV".
  [[nodiscard]] std::string port(unsigned n) const;
  // `latch`: the output latch's bytes by name ("outputs=0x0a modul_ok=0x01"); empty on the C31.
  [[nodiscard]] std::string latch() const;
  // `info`'s words: "cpu=80c32 cpu_hz=F board_address=0xAAAA" or "cpu=c31 cpu_hz=F code=0xAAAA".
  [[nodiscard]] std::string describe() const;
  // A debugger's poke into the C31's code area is its program from the next fetch, as the C31's
  // own MOVX into it is (docs/dpc31.md, "The C31").
  void poked(std::uint32_t addr, std::uint8_t value);

 private:
  Chip& chip_;
  CpuSetup s_;
  void bounded(LogLimiter& limit, std::uint64_t cycle, const std::string& text,
               std::string_view kind);

  std::function<void(std::string)> line_;
  LogLimiter port_lines_;
  LogLimiter serial_lines_;
  std::unique_ptr<Cpu51Module> module_;
  bool watch_irq_ = false;  // run_until_irq in progress
  bool irq_seen_ = false;
};

}  // namespace dpc31::serve

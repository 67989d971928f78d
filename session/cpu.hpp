// The host CPU that runs firmware against the chip. Firmware is level-triggered on X/INT and
// makes ordinary bus accesses (4 clocks each); its code runs as a coroutine with its own stack on
// the caller's thread (ucontext, then setjmp/longjmp), strictly one side at a time, so a run is
// deterministic and a hand-over costs a context switch in user space, not a wake-up of another
// thread. The bus side (the DP master) and the firmware interleave at the granularity of one bus
// access: firmware never holds the bus side back.
//
// Two kinds of program (docs/bring-up.md section 4): an interrupt-driven one (only an ISR: the
// CPU sleeps until X/INT), and one with a main loop, which runs whenever no interrupt is served;
// X/INT with the board's interrupt input enabled preempts it between two of its bus accesses.
#pragma once

#include <setjmp.h>
#include <ucontext.h>

#include <cstddef>
#include <cstdint>
#include <exception>
#include <functional>
#include <memory>
#include <span>

#include "board.hpp"
#include "dpc31/bus_port.hpp"
#include "dpc31/chip.hpp"

namespace dpc31 {

class Cpu final : public BusPort {
 public:
  using Isr = std::function<void(BusPort&)>;
  struct Program {
    Isr isr;        // X/INT; empty: never taken (a polling firmware)
    Isr main_step;  // one pass of main()'s loop; empty: the CPU sleeps until X/INT
    // The board's interrupt input (dpc31_board_int_enable); nullptr: always enabled.
    const bool* interrupts_enabled = nullptr;
  };
  // What an ISR run without a bus access costs: one bus access time, so time always advances.
  static constexpr std::uint64_t kNoAccessCycles = 4;
  // A main-loop pass takes at least 1 us of chip time: its bus accesses, and the rest of the
  // microsecond as the loop's own instructions (docs/decisions.md).
  static constexpr std::uint64_t kMainPassNs = 1000;

  Cpu(Chip& chip, Isr isr);
  Cpu(Chip& chip, Program program);
  ~Cpu() override;
  Cpu(const Cpu&) = delete;
  Cpu& operator=(const Cpu&) = delete;

  // Bus side: advance the chip to `cycle`, running the ISR whenever X/INT is active. The last
  // firmware access may end up to 3 clocks after `cycle` (an access is never split). Returns
  // early when Chip::request_stop is pending (the caller clears it). An exception from the
  // firmware's code is rethrown here; a program with a main loop is halted by it (from then on
  // only the chip runs).
  void run_until(std::uint64_t cycle);

  // Firmware side (called from its code).
  std::uint8_t read(std::uint32_t addr) override;
  void write(std::uint32_t addr, std::uint8_t value) override;
  // Block transfers: the accesses of read() / write() one by one, a quiet stretch of plain RAM
  // at once (stretch()).
  void write_block(std::uint32_t addr, std::span<const std::uint8_t> bytes) override;
  void read_block(std::uint32_t addr, std::span<std::uint8_t> out) override;
  void fill(std::uint32_t addr, std::uint8_t value, std::size_t len) override;
  bool equal(std::uint32_t a, std::uint32_t b, std::size_t len) override;
  // Busy-waits `cycles` clocks; an enabled interrupt preempts the main loop meanwhile.
  void idle(std::uint64_t cycles) override;
  [[nodiscard]] const Chip& chip() const override { return chip_; }
  // Whether run_until would run the firmware before the chip's next event (an ISR in progress or
  // due, a main loop) rather than only step the chip: where its bus accesses fall depends on
  // where a run ends (session/segment.cpp).
  [[nodiscard]] bool busy() const;

 private:
  static void entry(unsigned hi, unsigned lo);  // the coroutine's first frame: runs body()
  void body();
  void run_main();  // firmware: main()'s loop, forever
  void serve();     // firmware: one run of the ISR
  [[nodiscard]] bool interrupts_enabled() const;
  [[nodiscard]] bool preempts() const;  // X/INT interrupts the main loop now
  void gate();                          // firmware: wait for the bus side's grant before an access
  // firmware: gate(), then how many of the next accesses (at most quiet(), asked after the gate)
  // start before the limit
  template <typename Quiet>
  std::size_t stretch(Quiet quiet);
  void hand_to_firmware();  // bus side: let the firmware run until it yields
  void hand_to_bus_side();  // firmware: give control back

  Chip& chip_;
  Program program_;
  std::uint64_t accesses_ = 0;  // bus accesses and idle calls of the firmware
  // The coroutine: its stack, its first context, and where each side continues. in_isr_ and
  // stop_ are set by the side that hands over, read by the other.
  std::unique_ptr<char[]> stack_;
  ucontext_t firmware_ctx_{};
  jmp_buf bus_jmp_{};
  jmp_buf firmware_jmp_{};
  bool started_ = false;  // the coroutine has run (and holds frames to unwind on destruction)
  bool finished_ = false;
  bool in_isr_ = false;
  bool halted_ = false;  // the main loop ended with an exception
  bool stop_ = false;
  std::exception_ptr error_;  // thrown by the ISR, rethrown on the bus side
  std::uint64_t limit_ = 0;
  // The HAL selection (hal::Scope) of the side that is not running: the firmware's while the bus
  // side runs, and the other way round; being thread-local, it would otherwise leak between them.
  hal::Selection other_hal_;
  board::Hooks* other_board_ = nullptr;  // the same for the board hooks (board.hpp)
};

}  // namespace dpc31

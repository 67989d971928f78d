// The host CPU that runs firmware against the chip. Firmware is level-triggered on X/INT and
// makes ordinary bus accesses (4 clocks each); its ISR runs as a coroutine with its own stack on
// the caller's thread (ucontext, then setjmp/longjmp), strictly one side at a time, so a run is
// deterministic and a hand-over costs a context switch in user space, not a wake-up of another
// thread. The bus side (the DP master) and the firmware interleave at the granularity of one bus
// access: an ISR never holds the bus side back.
#pragma once

#include <setjmp.h>
#include <ucontext.h>

#include <cstdint>
#include <exception>
#include <functional>
#include <memory>

#include "dpc31/bus_port.hpp"
#include "dpc31/chip.hpp"

namespace dpc31 {

class Cpu final : public BusPort {
 public:
  using Isr = std::function<void(BusPort&)>;
  Cpu(Chip& chip, Isr isr);
  ~Cpu() override;
  Cpu(const Cpu&) = delete;
  Cpu& operator=(const Cpu&) = delete;

  // Bus side: advance the chip to `cycle`, running the ISR whenever X/INT is active. The last
  // firmware access may end up to 3 clocks after `cycle` (an access is never split). Returns
  // early when Chip::request_stop is pending (the caller clears it).
  void run_until(std::uint64_t cycle);

  // Firmware side (called from the ISR).
  std::uint8_t read(std::uint32_t addr) override;
  void write(std::uint32_t addr, std::uint8_t value) override;
  [[nodiscard]] const Chip& chip() const override { return chip_; }

 private:
  static void entry(unsigned hi, unsigned lo);  // the coroutine's first frame: runs body()
  void body();
  void gate();              // firmware: wait for the bus side's grant before an access
  void hand_to_firmware();  // bus side: let the firmware run until it yields
  void hand_to_bus_side();  // firmware: give control back

  Chip& chip_;
  Isr isr_;
  // The coroutine: its stack, its first context, and where each side continues. in_isr_ and
  // stop_ are set by the side that hands over, read by the other.
  std::unique_ptr<char[]> stack_;
  ucontext_t firmware_ctx_{};
  jmp_buf bus_jmp_{};
  jmp_buf firmware_jmp_{};
  bool started_ = false;  // the coroutine has run (and holds frames to unwind on destruction)
  bool finished_ = false;
  bool in_isr_ = false;
  bool stop_ = false;
  std::exception_ptr error_;  // thrown by the ISR, rethrown on the bus side
  std::uint64_t limit_ = 0;
  // The HAL selection (hal::Scope) of the side that is not running: the firmware's while the bus
  // side runs, and the other way round; being thread-local, it would otherwise leak between them.
  hal::Selection other_hal_;
};

}  // namespace dpc31

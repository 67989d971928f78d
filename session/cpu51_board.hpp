// An 80C32 beside the chip (docs/cpu.md): the MCS-51 core's XDATA space reaches the chip through
// the parallel bus in Intel mode at a base address the board chooses, X/INT drives INT0, and the
// CPU's oscillator and the chip's clock are merged in one time base.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "cpu51_config.hpp"
#include "dpc31/chip.hpp"
#include "mcs51/cpu.hpp"

namespace dpc31 {

class Cpu51Board final : public mcs51::XdataBus {
 public:
  // The chip's window: [base, base + window) of XDATA; the rest is the board's plain RAM.
  static constexpr std::uint32_t window = kCpu51Window;

  // Throws std::invalid_argument for a CPU clock outside 1..40 MHz (kCpuClock, every door's range)
  // or so fast that a MOVX strobe would end less than one bus access after its instruction
  // starts, for a chip that has run (its
  // cycle is not 0: the CPU's clock counts from the chip's cycle 0) and for a chip that has a
  // board already (the second would never run).
  Cpu51Board(Chip& chip, std::uint32_t cpu_hz, std::uint16_t base);
  ~Cpu51Board() override;
  Cpu51Board(const Cpu51Board&) = delete;
  Cpu51Board& operator=(const Cpu51Board&) = delete;

  // The DPC31's internal C31 instead (docs/dpc31.md, "The C31"): XDATA 0000h..1FFFh is the
  // chip's own address space (the manual: "the interface is identical in both cases"), nothing
  // above it; program memory from 0000h is the chip's RAM from `code_base` up to 1FFFh (its code
  // area, copied there by load_c31_code); INT0 is the output of the C31's interrupt controller.
  // Throws std::invalid_argument unless the chip is a dpc31 serving the C31's controller and
  // code_base lies in the RAM's user area (08A0h..1FFFh).
  struct C31 {
    std::uint16_t code_base;
  };
  Cpu51Board(Chip& chip, std::uint32_t cpu_hz, C31 c31);
  // Puts the image's bytes into the code area (back door: before the C31 runs, as a loader
  // would) and the core's program memory; false, nothing loaded, when one lies past 1FFFh.
  bool load_c31_code(const std::vector<std::uint8_t>& bytes, const std::vector<bool>& used);

  mcs51::Cpu& cpu() { return cpu_; }
  [[nodiscard]] const mcs51::Cpu& cpu() const { return cpu_; }
  // The board's plain RAM (XDATA outside the chip's window; an output latch decoded there).
  [[nodiscard]] std::uint8_t ram(std::uint16_t addr) const { return ram_[addr]; }
  // A debugger's poke into the chip at `addr` of its space (no bus time): on the C31 a byte of
  // its code area is its program from the next fetch, as its own MOVX's is.
  void poked(std::uint16_t addr, std::uint8_t value);
  // The chip cycle of an instant given in CPU oscillator clocks from reset: the first chip clock
  // edge at or after it, ceil(clock * chip_hz / cpu_hz) (docs/timing.md, "An 80C32 beside the
  // chip"). Throws std::invalid_argument for a clock whose chip cycle lies past
  // Chip::kLastCycle, where the chip's time ends (it would not fit in 64 bits either).
  std::uint64_t chip_cycle_of(std::uint64_t cpu_clock) const;
  // Runs CPU and chip together until the chip's cycle is `chip_cycle` (the CPU at the last step
  // boundary before it; past it only by a MOVX to the chip whose access starts before it), or
  // until the chip asked to stop (Chip::request_stop, wake_on_txd) at the step's end.
  void run_until(std::uint64_t chip_cycle);
  // The board's instant: the chip cycle where the last run_until ended (0 before the first). A
  // reset of the chip under the board is an event there: Chip::reset() starts the chip's new time
  // line and tells its edges at it (docs/cpu.md, "The board").
  [[nodiscard]] std::uint64_t instant() const { return ended_; }
  // The board's RESET, which CPU and chip share (docs/cpu.md, "The board's reset"): both reset at
  // the board's instant; the CPU starts from 0000h in the first machine cycle that begins at or
  // after it (an idle or a power-down ends), its RAM and the board's RAM kept. The C31's code
  // area, cleared with the chip's RAM, gets load_c31_code's last image again.
  void reset();

  // A write to the board's RAM (outside the chip's window), with the chip cycle of its strobe's
  // end: an output latch decoded there (Cpu51Module's ports).
  std::function<void(std::uint16_t addr, std::uint8_t value, std::uint64_t cycle)> on_ram_write;

  // Before every step of the CPU (an instruction, an interrupt's hardware LCALL with the PC it
  // interrupts, an idle machine cycle): its PC and machine cycle (`dpc31 bridge --trace-cpu`;
  // BridgeCpu.c31_ack_trace). Empty: nothing.
  std::function<void(std::uint16_t pc, std::uint64_t cycle)> on_step;

  std::uint8_t read(std::uint16_t addr, std::uint64_t clock) override;
  void write(std::uint16_t addr, std::uint8_t value, std::uint64_t clock) override;

 private:
  void chip_to(std::uint64_t cycle);
  // The C31's program memory: the chip's RAM from code_base_ up to 1FFFh, FFh past it.
  void c31_code_from_ram();
  // The first CPU clock whose chip cycle (chip_cycle_of) is at least `cycle`.
  [[nodiscard]] std::uint64_t clock_reaching(std::uint64_t cycle) const;
  // The lazy walk (run_until): the board brings the chip to chip_cycle_of(clock) for the INT0
  // samples only where the chip has an event; true when it did and X/INT was read again.
  bool reach(std::uint64_t clock);
  // The chip's cycle, next event and X/INT after the chip was stepped or accessed.
  void note_chip();
  // Steps the chip so that an access starting now completes at the strobe's end.
  void access_at(std::uint64_t clock);
  // The walk of the next step's instants before clock `limit` (run_until); whether the step
  // may run now; the address of the MOVX that is the next step; a MOVX's second sample.
  void walk(std::uint64_t limit);
  [[nodiscard]] bool step_fits() const;
  [[nodiscard]] std::uint16_t next_movx_address() const;
  void movx_sample(std::uint64_t clock);
  [[nodiscard]] std::uint64_t run_end() const;
  // INT0's level: X/INT for the 80C32, the C31's interrupt (low-active) for the C31.
  [[nodiscard]] bool int0_level() const;
  [[nodiscard]] bool in_window(std::uint16_t addr) const {
    return addr >= base_ && static_cast<std::uint32_t>(addr - base_) < window_;
  }

  Chip& chip_;
  mcs51::Cpu cpu_;
  std::uint32_t cpu_hz_;
  std::uint16_t base_;
  std::uint32_t window_ = window;
  bool c31_ = false;
  std::uint16_t code_base_ = 0;
  std::vector<std::uint8_t> c31_bytes_;  // load_c31_code's last image, for reset()
  std::vector<bool> c31_used_;
  std::vector<std::uint8_t> ram_ = std::vector<std::uint8_t>(0x10000, 0);
  // The lazy walk's state: the CPU clock the chip is due at (its chip cycle is where a board
  // stepping the chip to every sample would have it); the chip's own cycle, X/INT and the first
  // CPU clock that reaches its next event, as of the last time it was stepped or accessed.
  std::uint64_t due_ = 0;
  std::uint64_t chip_at_ = 0;
  std::uint64_t event_clock_ = 0;
  bool level_ = true;
  // The run's end (chip cycle and the first CPU clock reaching it); whether run_until lets the
  // CPU run steps in one go.
  std::uint64_t chip_end_ = 0;
  std::uint64_t end_clock_ = 0;
  bool in_run_ = false;
  std::uint64_t ended_ = 0;  // the chip's cycle where the last run ended: the board's instant
  // The next step's instants walked so far (walk): its first clock, how many, whether X/INT
  // changed at one (placed in its cycle), the level at the last one. A run that ends inside the
  // step leaves the rest to the next run.
  struct Walked {
    std::uint64_t start;
    unsigned done;
    bool changed;
    bool level;
  } walked_{0, 0, false, true};
};

}  // namespace dpc31

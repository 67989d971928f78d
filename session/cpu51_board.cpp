#include "cpu51_board.hpp"

#include <stdexcept>

namespace dpc31 {

Cpu51Board::Cpu51Board(Chip& chip, std::uint32_t cpu_hz, std::uint16_t base)
    : chip_(chip), cpu_hz_(cpu_hz), base_(base) {
  if (cpu_hz == 0 || chip_cycle_of(mcs51::movx_strobe_end) < chip.bus_access_cycles())
    throw std::invalid_argument("CPU clock out of range for the chip's bus");
  cpu_.set_xdata(this);
}

std::uint64_t Cpu51Board::chip_cycle_of(std::uint64_t cpu_clock) const {
  // Exact in 64 bits: whole CPU seconds, then the remainder (< cpu_hz) times chip_hz (< 2^64).
  const std::uint64_t chip_hz = chip_.clock_hz();
  const std::uint64_t rem = cpu_clock % cpu_hz_ * chip_hz;
  return cpu_clock / cpu_hz_ * chip_hz + (rem + cpu_hz_ - 1) / cpu_hz_;
}

void Cpu51Board::chip_to(std::uint64_t cycle) {
  if (cycle > chip_.cycle()) chip_.step(cycle - chip_.cycle());
}

// Before each step the chip runs to the S5P2 sample of each of the step's machine cycles (the end
// of oscillator clock 10 of 12) until X/INT changes; INT0 changes from the first cycle whose
// sample sees it. A MOVX's own access brings the chip to its strobe (docs/cpu.md, "INT0 from
// X/INT").
void Cpu51Board::run_until(std::uint64_t chip_cycle) {
  constexpr unsigned s5p2 = 10;
  while (chip_.cycle() < chip_cycle && !chip_.stop_requested()) {
    chip_to(chip_cycle_of(cpu_.clocks()));
    const bool level = chip_.x_int_pin();
    cpu_.set_int0(level);
    if (!cpu_.next_is_movx()) {
      const unsigned n = cpu_.next_step_cycles();
      for (unsigned j = 0; j < n; ++j) {
        chip_to(chip_cycle_of(cpu_.clocks() + j * mcs51::clocks_per_cycle + s5p2));
        if (chip_.x_int_pin() != level) {
          cpu_.schedule_int0(cpu_.cycles() + j, !level);
          break;
        }
      }
    }
    if (on_step) on_step(cpu_.pc(), cpu_.cycles());
    cpu_.step();
  }
}

void Cpu51Board::access_at(std::uint64_t clock) {
  std::uint64_t end = chip_cycle_of(clock);
  chip_to(end - chip_.bus_access_cycles());
}

std::uint8_t Cpu51Board::read(std::uint16_t addr, std::uint64_t clock) {
  if (addr < base_ || addr >= base_ + window) return ram_[addr];
  access_at(clock);
  const std::uint8_t v = chip_.read(addr - base_);
  cpu_.set_int0(chip_.x_int_pin());  // a command read may end the interrupt
  return v;
}

void Cpu51Board::write(std::uint16_t addr, std::uint8_t value, std::uint64_t clock) {
  if (addr < base_ || addr >= base_ + window) {
    ram_[addr] = value;
    if (on_ram_write) on_ram_write(addr, value, chip_cycle_of(clock));
    return;
  }
  access_at(clock);
  chip_.write(addr - base_, value);
  cpu_.set_int0(chip_.x_int_pin());
}

}  // namespace dpc31

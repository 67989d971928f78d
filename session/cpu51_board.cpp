#include "cpu51_board.hpp"

#include <span>
#include <stdexcept>

namespace dpc31 {

Cpu51Board::Cpu51Board(Chip& chip, std::uint32_t cpu_hz, std::uint16_t base)
    : chip_(chip), cpu_hz_(cpu_hz), base_(base) {
  if (cpu_hz == 0 || chip_cycle_of(mcs51::movx_strobe_end) < chip.bus_access_cycles())
    throw std::invalid_argument("CPU clock out of range for the chip's bus");
  cpu_.set_xdata(this);
}

namespace {
// The DPC31's address space and its RAM's user area (manual p.12, docs/dpc31.md "The map").
constexpr std::uint32_t c31_space = 0x2000;
constexpr std::uint16_t c31_user_area = 0x08A0;
}  // namespace

Cpu51Board::Cpu51Board(Chip& chip, std::uint32_t cpu_hz, C31 c31)
    : Cpu51Board(chip, cpu_hz, std::uint16_t{0}) {
  if (chip.profile().id != Profile::dpc31 || chip.irq_controller() != IrqController::c31)
    throw std::invalid_argument("the C31 is the dpc31's, with its interrupt controller (c31)");
  if (c31.code_base < c31_user_area || c31.code_base >= c31_space)
    throw std::invalid_argument("the C31's code area lies in the RAM from 08A0h to 1FFFh");
  window_ = c31_space;
  c31_ = true;
  code_base_ = c31.code_base;
}

bool Cpu51Board::load_c31_code(const std::vector<std::uint8_t>& bytes,
                               const std::vector<bool>& used) {
  const std::uint32_t room = c31_space - code_base_;
  for (std::uint32_t a = room; a < used.size(); ++a)
    if (!c31_ || used[a]) return false;
  for (std::uint32_t a = 0; a < room && a < used.size() && a < bytes.size(); ++a) {
    if (!used[a]) continue;
    chip_.poke(code_base_ + a, bytes[a]);
    cpu_.load_code(static_cast<std::uint16_t>(a), std::span(&bytes[a], 1));
  }
  return true;
}

bool Cpu51Board::int0_level() const { return c31_ ? !chip_.irq_active() : chip_.x_int_pin(); }

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
    const bool level = int0_level();
    cpu_.set_int0(level);
    if (!cpu_.next_is_movx()) {
      const unsigned n = cpu_.next_step_cycles();
      for (unsigned j = 0; j < n; ++j) {
        chip_to(chip_cycle_of(cpu_.clocks() + j * mcs51::clocks_per_cycle + s5p2));
        if (int0_level() != level) {
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
  if (!in_window(addr)) return c31_ ? 0xFF : ram_[addr];  // the C31: nothing above 1FFFh
  access_at(clock);
  const std::uint8_t v = chip_.read(addr - base_);
  cpu_.set_int0(int0_level());  // a command read may end the interrupt
  return v;
}

void Cpu51Board::write(std::uint16_t addr, std::uint8_t value, std::uint64_t clock) {
  if (c31_ && !in_window(addr)) return;
  if (!in_window(addr)) {
    ram_[addr] = value;
    if (on_ram_write) on_ram_write(addr, value, chip_cycle_of(clock));
    return;
  }
  access_at(clock);
  chip_.write(addr - base_, value);
  poked(addr, value);
  cpu_.set_int0(int0_level());
}

// The C31 fetches its code from the chip's RAM: a write to the code area is its program.
void Cpu51Board::poked(std::uint16_t addr, std::uint8_t value) {
  if (c31_ && addr >= code_base_ && addr < window_)
    cpu_.load_code(static_cast<std::uint16_t>(addr - code_base_), std::span(&value, 1));
}

}  // namespace dpc31

#include "cpu51_board.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <mutex>
#include <set>
#include <span>
#include <stdexcept>

namespace dpc31 {

namespace {
// The chips that have a board: a second one would never run (the first one's run takes the
// chip's time), and its accesses would interleave with the first one's.
std::mutex boarded_mutex;
std::set<const Chip*> boarded;
}  // namespace

Cpu51Board::Cpu51Board(Chip& chip, std::uint32_t cpu_hz, std::uint16_t base)
    : chip_(chip), cpu_hz_(cpu_hz), base_(base) {
  if (cpu_hz == 0 || chip_cycle_of(mcs51::movx_strobe_end) < chip.bus_access_cycles())
    throw std::invalid_argument("CPU clock out of range for the chip's bus");
  // The CPU's clock 0 is the chip's cycle 0 (chip_cycle_of): on a chip that has run, every
  // instant would be off by the chip's cycle.
  if (chip.cycle() != 0) {
    throw std::invalid_argument(fmt::format(
        "the chip has run (cycle {}): a board starts with a chip at cycle 0", chip.cycle()));
  }
  const std::scoped_lock lock(boarded_mutex);
  if (!boarded.insert(&chip).second)
    throw std::invalid_argument("the chip has a board already: one CPU drives a chip's bus");
  cpu_.set_xdata(this);
}

Cpu51Board::~Cpu51Board() {
  const std::scoped_lock lock(boarded_mutex);
  boarded.erase(&chip_);
}

namespace {
constexpr unsigned cycle_clocks = mcs51::clocks_per_cycle;
constexpr unsigned s5p2 = 10;  // INT0's sample: the end of oscillator clock 10 of 12
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
  // Exact in 64 bits: whole CPU seconds, then the remainder (< cpu_hz) times chip_hz (< 2^64);
  // the seconds are checked first, so that their product cannot wrap.
  const std::uint64_t chip_hz = chip_.clock_hz();
  const std::uint64_t seconds = cpu_clock / cpu_hz_;
  const std::uint64_t rem = cpu_clock % cpu_hz_ * chip_hz;
  if (seconds > Chip::kLastCycle / chip_hz ||
      seconds * chip_hz + (rem + cpu_hz_ - 1) / cpu_hz_ > Chip::kLastCycle) {
    throw std::invalid_argument(
        fmt::format("cpu_clock {} out of range (0..{}): past the chip's last cycle", cpu_clock,
                    clock_reaching(Chip::kLastCycle + 1) - 1));
  }
  return seconds * chip_hz + (rem + cpu_hz_ - 1) / cpu_hz_;
}

std::uint64_t Cpu51Board::clock_reaching(std::uint64_t cycle) const {
  // ceil(c * chip_hz / cpu_hz) >= cycle  <=>  c > (cycle - 1) * cpu_hz / chip_hz; split as in
  // chip_cycle_of so that nothing overflows; a cycle beyond any clock gives UINT64_MAX.
  if (cycle == 0) return 0;
  const std::uint64_t chip_hz = chip_.clock_hz();
  const std::uint64_t q = (cycle - 1) / chip_hz, r = (cycle - 1) % chip_hz;
  if (q > (UINT64_MAX - cpu_hz_) / cpu_hz_) return UINT64_MAX;
  return q * cpu_hz_ + r * cpu_hz_ / chip_hz + 1;
}

void Cpu51Board::chip_to(std::uint64_t cycle) {
  if (cycle > chip_.cycle()) chip_.step(cycle - chip_.cycle());
}

void Cpu51Board::note_chip() {
  chip_at_ = chip_.cycle();
  const std::uint64_t next = chip_.next_deadline();
  // An event not yet processed (due at or before the chip's cycle): every instant reaches it.
  event_clock_ = next > chip_at_ ? clock_reaching(next) : 0;
  level_ = int0_level();
}

bool Cpu51Board::reach(std::uint64_t clock) {
  due_ = clock;
  if (clock < event_clock_) return false;  // no event on the way: X/INT holds still
  chip_to(chip_cycle_of(clock));
  note_chip();
  return true;
}

// The last machine cycle + 1 that the steps run without the board may end in: before the first
// cycle whose S5P2 sample reaches the chip's next event, and so that each step's last sample lies
// before the end of the run (the walk then goes on after it); none once the chip reached the end
// or asked to stop.
std::uint64_t Cpu51Board::run_end() const {
  if (chip_at_ >= chip_end_ || chip_.stop_requested()) return 0;
  const std::uint64_t event =
      event_clock_ > s5p2 ? (event_clock_ - s5p2 - 1) / cycle_clocks + 1 : 0;
  const std::uint64_t end =
      end_clock_ >= cycle_clocks - 1 ? (end_clock_ - (cycle_clocks - 1)) / cycle_clocks + 1 : 0;
  return std::min(event, end);
}

// The walk of the manual's sampling (docs/cpu.md, "INT0 from X/INT"): before each step the chip
// is due at the step's start, then at the S5P2 sample of each of the step's machine cycles (the
// end of oscillator clock 10 of 12) until X/INT changes; INT0 changes from the first cycle whose
// sample sees it. A MOVX's own access brings the chip to its strobe. X/INT changes only at the
// chip's events and bus accesses, so the chip is stepped only where an instant reaches its next
// event, at the accesses and at the end: the chip sees every access, every event and every X/INT
// sample at the same cycle as when it is stepped to each instant (docs/performance.md, row m).
// Steps that reach no event run in one go (Cpu::run_within), an access lowering their end.
void Cpu51Board::run_until(std::uint64_t chip_cycle) {
  note_chip();
  event_clock_ = 0;  // the first step reads X/INT whatever happened to the chip before
  due_ = 0;
  chip_end_ = chip_cycle;
  end_clock_ = clock_reaching(chip_cycle);
  in_run_ = !on_step;
  while (chip_at_ < chip_cycle && due_ < end_clock_ && !chip_.stop_requested()) {
    const std::uint64_t start = cpu_.clocks();
    if (in_run_ && cpu_.run_within(run_end()) != 0) {
      // The walk's last instant: the last step's last sample, or a MOVX's start.
      const std::uint64_t now = cpu_.clocks();
      const std::uint64_t movx = 2 * cycle_clocks;
      due_ = now >= movx && last_movx_ == now - movx ? last_movx_ : now - (cycle_clocks - s5p2);
      continue;
    }
    if (reach(start)) cpu_.set_int0(level_);
    if (!cpu_.next_is_movx()) {
      const unsigned n = cpu_.next_step_cycles();
      for (unsigned j = 0; j < n; ++j) {
        const bool level = level_;
        if (reach(start + j * cycle_clocks + s5p2) && level_ != level) {
          cpu_.schedule_int0(cpu_.cycles() + j, level_);
          break;
        }
      }
    }
    if (on_step) {
      chip_to(chip_cycle_of(due_));
      on_step(cpu_.pc(), cpu_.cycles());
    }
    cpu_.step();
  }
  in_run_ = false;
  chip_to(chip_cycle_of(due_));
}

// The MOVX started at clock - 18, where the walk had the chip.
void Cpu51Board::access_at(std::uint64_t clock) {
  const std::uint64_t start = chip_cycle_of(clock) - chip_.bus_access_cycles();
  chip_to(std::max(chip_cycle_of(clock - mcs51::movx_strobe_end), start));
}

void Cpu51Board::after_access() {
  note_chip();
  cpu_.set_int0(level_);  // a command read, an acknowledge or an EOI may end the interrupt
  if (in_run_) cpu_.set_run_end(run_end());
}

std::uint8_t Cpu51Board::read(std::uint16_t addr, std::uint64_t clock) {
  last_movx_ = clock - mcs51::movx_strobe_end;
  if (!in_window(addr)) return c31_ ? 0xFF : ram_[addr];  // the C31: nothing above 1FFFh
  access_at(clock);
  const std::uint8_t v = chip_.read(addr - base_);
  after_access();
  return v;
}

void Cpu51Board::write(std::uint16_t addr, std::uint8_t value, std::uint64_t clock) {
  last_movx_ = clock - mcs51::movx_strobe_end;
  if (c31_ && !in_window(addr)) return;
  if (!in_window(addr)) {
    ram_[addr] = value;
    if (on_ram_write) {
      // The chip where the walk has it for the latch's user, who may look at it.
      chip_to(chip_cycle_of(last_movx_));
      on_ram_write(addr, value, chip_cycle_of(clock));
      if (in_run_) cpu_.set_run_end(run_end());
    }
    return;
  }
  access_at(clock);
  chip_.write(addr - base_, value);
  poked(addr, value);
  after_access();
}

// The C31 fetches its code from the chip's RAM: a write to the code area is its program.
void Cpu51Board::poked(std::uint16_t addr, std::uint8_t value) {
  if (c31_ && addr >= code_base_ && addr < window_)
    cpu_.load_code(static_cast<std::uint16_t>(addr - code_base_), std::span(&value, 1));
}

}  // namespace dpc31

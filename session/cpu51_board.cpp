#include "cpu51_board.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <mutex>
#include <set>
#include <span>
#include <stdexcept>

#include "vocabulary.hpp"

namespace dpc31 {

namespace {
// The chips that have a board: a second one would never run (the first one's run takes the
// chip's time), and its accesses would interleave with the first one's.
std::mutex boarded_mutex;
std::set<const Chip*> boarded;
}  // namespace

Cpu51Board::Cpu51Board(Chip& chip, std::uint32_t cpu_hz, std::uint16_t base)
    : chip_(chip), cpu_hz_(cpu_hz), base_(base) {
  // The range every door checks (kCpuClock); the strobe must end at least one bus access after
  // the MOVX starts (18 clocks, exactly, not rounded up to a chip clock).
  if (!kCpuClock.holds(cpu_hz)) {
    throw std::invalid_argument(
        fmt::format("CPU clock {} Hz out of range ({}..{})", cpu_hz, kCpuClock.min, kCpuClock.max));
  }
  if (std::uint64_t{mcs51::movx_strobe_end} * chip.clock_hz() <
      std::uint64_t{chip.bus_access_cycles()} * cpu_hz) {
    throw std::invalid_argument(fmt::format(
        "CPU clock {} Hz: a MOVX strobe of 18 clocks is shorter than the chip's bus access of {} "
        "clocks at {} Hz",
        cpu_hz, chip.bus_access_cycles(), chip.clock_hz()));
  }
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
  BoardAccess::hold(chip_, &ended_);
}

Cpu51Board::~Cpu51Board() {
  BoardAccess::hold(chip_, nullptr);
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
  c31_code_from_ram();
}

// Code address c is RAM address code_base + c: the RAM as it is, and FFh past 1FFFh, where
// nothing answers (docs/dpc31.md, "The C31").
void Cpu51Board::c31_code_from_ram() {
  std::vector<std::uint8_t> code(0x10000, 0xFF);
  for (std::uint32_t a = 0; a < c31_space - code_base_; ++a) code[a] = chip_.peek(code_base_ + a);
  cpu_.load_code(0, code);
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
  c31_bytes_ = bytes;
  c31_used_ = used;
  return true;
}

void Cpu51Board::reset() {
  chip_.reset(ended_);
  // The first machine cycle starting at or after the instant's first CPU clock: the instruction
  // in progress there ends with the reset.
  cpu_.reset((clock_reaching(ended_) + cycle_clocks - 1) / cycle_clocks);
  walked_ = {cpu_.clocks(), 0, false, level_};  // the next step is another: nothing walked yet
  if (c31_) {
    c31_code_from_ram();
    load_c31_code(c31_bytes_, c31_used_);
  }
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
// sample sees it. A MOVX's first sample is walked before it, its access brings the chip to its
// strobe and its second sample follows the access (movx_sample). X/INT changes only at the
// chip's events and bus accesses, so the chip is stepped only where an instant reaches its next
// event, at the accesses and at the end: the chip sees every access, every event and every X/INT
// sample at the same cycle as when it is stepped to each instant (docs/performance.md, row m).
// Steps that reach no event run in one go (Cpu::run_within), an access lowering their end.
//
// The run ends with the chip at `chip_cycle` exactly (docs/timing.md, "An 80C32 beside the
// chip"): a step whose last sample lies at or after it waits for the next run, its instants
// before it walked now (walked_), so that what happens at the end (the master's next request)
// is seen by the samples after it; only a MOVX whose access to the chip starts before the end
// runs across it (the access keeps its cycle).
void Cpu51Board::run_until(std::uint64_t chip_cycle) {
  // The chip stands at the board's instant or after it (an access since, a reset or a load
  // there: Chip::reset, Chip::load_state), never before.
  note_chip();
  event_clock_ = 0;  // the first instant walked reads X/INT whatever happened to the chip before
  due_ = 0;
  chip_end_ = chip_cycle;
  end_clock_ = clock_reaching(chip_cycle);
  in_run_ = !on_step;
  while (chip_at_ < chip_cycle && !chip_.stop_requested()) {
    if (in_run_ && cpu_.run_within(run_end()) != 0) {
      due_ = cpu_.clocks() - (cycle_clocks - s5p2);  // the last step's last sample
      continue;
    }
    walk(end_clock_);
    if (!step_fits()) break;
    if (on_step) {
      chip_to(chip_cycle_of(due_));
      on_step(cpu_.pc(), cpu_.cycles());
    }
    cpu_.step();
  }
  in_run_ = false;
  chip_to(chip_.stop_requested() ? chip_cycle_of(due_) : chip_cycle);
  ended_ = chip_.cycle();
}

// The instants of the step starting at clock `start`: 0 its start, 1 + j the sample of its cycle
// j (a MOVX's second sample is movx_sample's, after its access).
void Cpu51Board::walk(std::uint64_t limit) {
  const std::uint64_t start = cpu_.clocks();
  if (walked_.start != start) walked_ = {start, 0, false, level_};
  const bool movx = cpu_.next_is_movx();
  // A MOVX's first sample, unless the CPU is so fast that it falls inside the access.
  const unsigned instants = !movx ? 1 + cpu_.next_step_cycles()
                            : chip_cycle_of(start + s5p2) + chip_.bus_access_cycles() <=
                                    chip_cycle_of(start + mcs51::movx_strobe_end)
                                ? 2
                                : 1;
  while (walked_.done < instants && !walked_.changed) {
    const std::uint64_t at =
        walked_.done == 0 ? start : start + (walked_.done - 1) * cycle_clocks + s5p2;
    if (at >= limit) return;
    if (walked_.done == 0) {
      if (reach(at)) cpu_.set_int0(level_);
      walked_.level = level_;
    } else if (reach(at) && level_ != walked_.level) {
      cpu_.schedule_int0(cpu_.cycles() + walked_.done - 1, level_);
      walked_.changed = true;
    }
    ++walked_.done;
  }
  walked_.done = instants;  // complete: the step may run
}

// Whether the next step runs in this run: its instants all lie before the end, or it is a MOVX
// whose access to the chip starts before the end (its second sample at its access).
bool Cpu51Board::step_fits() const {
  const std::uint64_t start = cpu_.clocks();
  if (walked_.start != start) return false;
  if (!cpu_.next_is_movx()) return walked_.changed || walked_.done == 1 + cpu_.next_step_cycles();
  if (start + cycle_clocks + s5p2 < end_clock_) return true;
  const std::uint64_t strobe = chip_cycle_of(start + mcs51::movx_strobe_end);
  return in_window(next_movx_address()) && strobe - chip_.bus_access_cycles() < chip_end_;
}

// The address of the MOVX that is the next step: DPTR, or P2 and R0 / R1.
std::uint16_t Cpu51Board::next_movx_address() const {
  const std::uint8_t op = cpu_.code(cpu_.pc());
  if ((op & 0x02) == 0) return cpu_.dptr();
  return static_cast<std::uint16_t>(cpu_.sfr_latch(mcs51::sfr::P2) << 8 | cpu_.reg(op & 1));
}

// A MOVX's second sample (S5P2 of its second cycle, 4 clocks after the strobe's end at `clock`):
// it sees what the access did and the chip's events up to it.
void Cpu51Board::movx_sample(std::uint64_t clock) {
  reach(clock + cycle_clocks + s5p2 - mcs51::movx_strobe_end);
  cpu_.set_int0(level_);
  if (in_run_) cpu_.set_run_end(run_end());
}

// The MOVX started at clock - 18, where the walk had the chip.
void Cpu51Board::access_at(std::uint64_t clock) {
  const std::uint64_t start = chip_cycle_of(clock) - chip_.bus_access_cycles();
  chip_to(std::max(chip_cycle_of(clock - mcs51::movx_strobe_end), start));
}

std::uint8_t Cpu51Board::read(std::uint16_t addr, std::uint64_t clock) {
  std::uint8_t v = 0xFF;  // the C31: nothing above 1FFFh
  if (in_window(addr)) {
    access_at(clock);
    v = chip_.read(addr - base_);
    note_chip();
  } else if (!c31_) {
    v = ram_[addr];
  }
  movx_sample(clock);
  return v;
}

void Cpu51Board::write(std::uint16_t addr, std::uint8_t value, std::uint64_t clock) {
  if (in_window(addr)) {
    access_at(clock);
    chip_.write(addr - base_, value);
    poked(addr, value);
    note_chip();
  } else if (!c31_) {
    ram_[addr] = value;
    // The chip where the walk has it for the latch's user, who may look at it.
    if (on_ram_write) {
      chip_to(chip_cycle_of(clock - mcs51::movx_strobe_end));
      on_ram_write(addr, value, chip_cycle_of(clock));
    }
  }
  movx_sample(clock);
}

// The C31 fetches its code from the chip's RAM: a write to the code area is its program.
void Cpu51Board::poked(std::uint16_t addr, std::uint8_t value) {
  if (c31_ && addr >= code_base_ && addr < window_)
    cpu_.load_code(static_cast<std::uint16_t>(addr - code_base_), std::span(&value, 1));
}

}  // namespace dpc31

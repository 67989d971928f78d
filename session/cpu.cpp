#include "cpu.hpp"

#include <setjmp.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <system_error>
#include <utility>

// AddressSanitizer must be told when the stack changes under it (its fake stacks and its
// bookkeeping of the current stack's bounds); without the calls it reports false errors.
#if defined(__SANITIZE_ADDRESS__)
#define DPC31_ASAN_FIBERS 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define DPC31_ASAN_FIBERS 1
#endif
#endif
#ifdef DPC31_ASAN_FIBERS
#include <sanitizer/common_interface_defs.h>
#endif

namespace dpc31 {

namespace {

struct Stopped {};  // unwinds an ISR that is still waiting when the CPU goes away

// The firmware's stack. Firmware ISRs are small C functions; 1 MiB of address space is touched
// only as far as they reach.
constexpr std::size_t kStackSize = std::size_t{1} << 20;

#ifdef DPC31_ASAN_FIBERS
// The bus side's stack as ASan knows it, learnt on the first switch into the firmware.
struct AsanStack {
  const void* bottom = nullptr;
  std::size_t size = 0;
};
thread_local AsanStack t_bus_stack;
#endif

// Tell ASan that the running side leaves for the stack [bottom, bottom + size) (`fake`: where
// the leaving side's fake stack is kept; nullptr when the leaving side ends), and that it is
// back (`fake` as saved).
void leaving(void** fake, const void* bottom, std::size_t size) {
#ifdef DPC31_ASAN_FIBERS
  __sanitizer_start_switch_fiber(fake, bottom, size);
#else
  (void)fake;
  (void)bottom;
  (void)size;
#endif
}

void back(void* fake) {
#ifdef DPC31_ASAN_FIBERS
  __sanitizer_finish_switch_fiber(fake, nullptr, nullptr);
#else
  (void)fake;
#endif
}

}  // namespace

Cpu::Cpu(Chip& chip, Isr isr) : Cpu(chip, Program{std::move(isr), {}, nullptr}) {}

Cpu::Cpu(Chip& chip, Program program)
    : chip_(chip), program_(std::move(program)), stack_(std::make_unique<char[]>(kStackSize)) {
  if (::getcontext(&firmware_ctx_) != 0) {
    throw std::system_error(errno, std::generic_category(), "getcontext");
  }
  firmware_ctx_.uc_stack.ss_sp = stack_.get();
  firmware_ctx_.uc_stack.ss_size = kStackSize;
  firmware_ctx_.uc_link = nullptr;  // entry() never returns: it jumps back to the bus side
  // makecontext passes int arguments only: `this` in two halves.
  const auto self = reinterpret_cast<std::uintptr_t>(this);
  ::makecontext(&firmware_ctx_, reinterpret_cast<void (*)()>(&Cpu::entry), 2,
                static_cast<unsigned>(static_cast<std::uint64_t>(self) >> 32),
                static_cast<unsigned>(self & 0xFFFF'FFFFu));
}

Cpu::~Cpu() {
  // An ISR waiting in the middle of its accesses has frames (and objects) on the coroutine's
  // stack: resume it once with stop_ set so that it unwinds, and body() returns.
  if (started_ && !finished_) {
    stop_ = true;
    hand_to_firmware();
  }
}

void Cpu::entry(unsigned hi, unsigned lo) {
  auto* self = reinterpret_cast<Cpu*>((static_cast<std::uintptr_t>(hi) << 32) | lo);
#ifdef DPC31_ASAN_FIBERS
  __sanitizer_finish_switch_fiber(nullptr, &t_bus_stack.bottom, &t_bus_stack.size);
#endif
  self->body();
  self->finished_ = true;
#ifdef DPC31_ASAN_FIBERS
  leaving(nullptr, t_bus_stack.bottom, t_bus_stack.size);
#else
  leaving(nullptr, nullptr, 0);
#endif
  _longjmp(self->bus_jmp_, 1);
}

void Cpu::body() {
  try {
    if (program_.main_step) run_main();
    for (;;) {
      try {
        serve();
      } catch (const Stopped&) {
        throw;
      } catch (...) {
        // An exception cannot cross from one stack to the other: the bus side rethrows it.
        error_ = std::current_exception();
      }
      in_isr_ = false;
      hand_to_bus_side();
    }
  } catch (const Stopped&) {
  }
}

void Cpu::run_main() {
  const std::uint64_t pass = chip_.clock_hz() * kMainPassNs / 1'000'000'000;
  try {
    for (;;) {
      const std::uint64_t start = chip_.cycle();
      program_.main_step(*this);
      const std::uint64_t spent = chip_.cycle() - start;
      if (spent < pass) idle(pass - spent);
    }
  } catch (const Stopped&) {
    throw;
  } catch (...) {
    error_ = std::current_exception();
  }
  // Halted: the bus side runs only the chip from now on; the coroutine waits to be unwound.
  halted_ = true;
  for (;;) hand_to_bus_side();
}

void Cpu::serve() {
  in_isr_ = true;
  const std::uint64_t before = accesses_;
  program_.isr(*this);
  if (accesses_ == before) idle(kNoAccessCycles);
  in_isr_ = false;
}

bool Cpu::interrupts_enabled() const {
  return program_.isr && (program_.interrupts_enabled == nullptr || *program_.interrupts_enabled);
}

bool Cpu::preempts() const {
  return program_.main_step && !in_isr_ && interrupts_enabled() && chip_.irq_active();
}

// The switches are QEMU's (util/coroutine-ucontext.c): makecontext gives the coroutine its
// stack and setcontext enters it the first time; every later switch is _setjmp/_longjmp, which
// save and restore no signal mask (no system call) and are not swapcontext, which ASan only
// half supports (it warns on stderr at the first call).
void Cpu::hand_to_firmware() {
  other_hal_ = hal::exchange_selection(other_hal_);
  other_board_ = board::exchange(other_board_);
  board::firmware_entered();
  void* fake = nullptr;
  leaving(&fake, stack_.get(), kStackSize);
  if (_setjmp(bus_jmp_) == 0) {
    if (!started_) {
      started_ = true;
      ::setcontext(&firmware_ctx_);  // returns only on failure
      throw std::system_error(errno, std::generic_category(), "setcontext");
    }
    _longjmp(firmware_jmp_, 1);
  }
  back(fake);
  board::firmware_left();
  other_board_ = board::exchange(other_board_);
  other_hal_ = hal::exchange_selection(other_hal_);
  if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
}

void Cpu::hand_to_bus_side() {
  void* fake = nullptr;
#ifdef DPC31_ASAN_FIBERS
  leaving(&fake, t_bus_stack.bottom, t_bus_stack.size);
#else
  leaving(&fake, nullptr, 0);
#endif
  if (_setjmp(firmware_jmp_) == 0) _longjmp(bus_jmp_, 1);
  back(fake);
  if (stop_) throw Stopped{};
}

void Cpu::gate() {
  board::progress();
  ++accesses_;
  for (;;) {
    // A stop request (an observer of the bus side, e.g. the master seeing an answer start) takes
    // control back before the next access, as reaching the limit does.
    while (chip_.cycle() >= limit_ || chip_.stop_requested()) hand_to_bus_side();
    if (!preempts()) return;
    serve();  // between two accesses of the main loop, as the CPU takes an interrupt
  }
}

std::uint8_t Cpu::read(std::uint32_t addr) {
  gate();
  return chip_.read(addr);
}

void Cpu::write(std::uint32_t addr, std::uint8_t value) {
  gate();
  chip_.write(addr, value);
}

// A block's accesses go one by one through gate(), except a stretch that the chip says is quiet
// plain RAM (Chip::quiet_ram_run) and that starts before the limit: between its accesses gate()
// would find nothing to do (no event inside it can request a stop or change X/INT, and plain RAM
// moves neither), so it goes at once and the run is the same as byte by byte.
template <typename Quiet>
std::size_t Cpu::stretch(Quiet quiet) {
  gate();  // returns with cycle() < limit_
  const std::uint64_t per = chip_.bus_access_cycles();
  const std::uint64_t starting = (limit_ - chip_.cycle() + per - 1) / per;
  const auto k = static_cast<std::size_t>(std::min<std::uint64_t>(quiet(), starting));
  if (k > 1) accesses_ += k - 1;
  return k;
}

void Cpu::write_block(std::uint32_t addr, std::span<const std::uint8_t> bytes) {
  while (!bytes.empty()) {
    std::size_t k = stretch([&] { return chip_.quiet_ram_run(addr, bytes.size(), true); });
    if (k <= 1) {
      chip_.write(addr, bytes.front());
      k = 1;
    } else {
      chip_.write_block(addr, bytes.first(k));
    }
    addr += static_cast<std::uint32_t>(k);
    bytes = bytes.subspan(k);
  }
}

void Cpu::read_block(std::uint32_t addr, std::span<std::uint8_t> out) {
  while (!out.empty()) {
    std::size_t k = stretch([&] { return chip_.quiet_ram_run(addr, out.size(), false); });
    if (k <= 1) {
      out.front() = chip_.read(addr);
      k = 1;
    } else {
      chip_.read_block(addr, out.first(k));
    }
    addr += static_cast<std::uint32_t>(k);
    out = out.subspan(k);
  }
}

void Cpu::fill(std::uint32_t addr, std::uint8_t value, std::size_t len) {
  while (len != 0) {
    std::size_t k = stretch([&] { return chip_.quiet_ram_run(addr, len, true); });
    if (k <= 1) {
      chip_.write(addr, value);
      k = 1;
    } else {
      chip_.fill(addr, value, k);
    }
    addr += static_cast<std::uint32_t>(k);
    len -= k;
  }
}

bool Cpu::equal(std::uint32_t a, std::uint32_t b, std::size_t len) {
  for (std::size_t i = 0; i < len;) {
    const auto ai = a + static_cast<std::uint32_t>(i);
    const auto bi = b + static_cast<std::uint32_t>(i);
    // Two accesses per pair, both quiet plain RAM.
    const std::size_t k = stretch([&] {
                            return std::min(chip_.quiet_ram_run(ai, len - i, false),
                                            chip_.quiet_ram_run(bi, len - i, false));
                          }) /
                          2;
    if (k == 0) {
      const std::uint8_t first = chip_.read(ai);  // gated by stretch(); this order on the bus
      if (first != read(bi)) return false;
      ++i;
      continue;
    }
    if (!chip_.equal(ai, bi, k)) return false;
    i += k;
  }
  return true;
}

void Cpu::idle(std::uint64_t cycles) {
  const std::uint64_t end = chip_.cycle() + cycles;
  for (;;) {
    gate();
    if (chip_.cycle() >= end) return;  // an ISR served in gate() took the rest of the wait
    const std::uint64_t n = std::min(end, limit_) - chip_.cycle();
    // An interrupt that would preempt the wait ends this piece where it becomes active, and so
    // does a stop request (the master seeing its answer start, wake_on_txd) in every case, an
    // ISR's busy wait too: gate() then hands the bus side its turn, which a plain step() would
    // have held back to the limit.
    chip_.step_until_irq(n);
    if (chip_.cycle() >= end) return;
  }
}

bool Cpu::busy() const {
  if (halted_) return false;
  if (in_isr_ || program_.main_step) return true;
  return interrupts_enabled() && chip_.irq_active();
}

void Cpu::run_until(std::uint64_t cycle) {
  while (chip_.cycle() < cycle && !chip_.stop_requested()) {
    limit_ = cycle;
    if (halted_) {
      chip_.step(cycle - chip_.cycle());
      continue;
    }
    if (in_isr_ || program_.main_step) {
      hand_to_firmware();  // an ISR in progress, or the main loop, continues
      continue;
    }
    if (!interrupts_enabled()) {
      chip_.step(cycle - chip_.cycle());  // asleep with X/INT masked: only the chip runs
      continue;
    }
    if (chip_.irq_active()) {
      in_isr_ = true;  // X/INT is level-triggered: the firmware enters its ISR
      hand_to_firmware();
      continue;
    }
    chip_.step_until_irq(cycle - chip_.cycle());
  }
}

}  // namespace dpc31

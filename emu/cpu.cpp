#include "cpu.hpp"

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

// Leaves the running context for `to`, saving it in `from`. `to_stack`/`to_size` is the stack
// being entered (ASan only).
void switch_context(ucontext_t& from, const ucontext_t& to, const void* to_stack,
                    std::size_t to_size) {
#ifdef DPC31_ASAN_FIBERS
  void* fake = nullptr;
  __sanitizer_start_switch_fiber(&fake, to_stack, to_size);
#else
  (void)to_stack;
  (void)to_size;
#endif
  if (::swapcontext(&from, &to) != 0) {
    throw std::system_error(errno, std::generic_category(), "swapcontext");
  }
#ifdef DPC31_ASAN_FIBERS
  __sanitizer_finish_switch_fiber(fake, nullptr, nullptr);
#endif
}

}  // namespace

Cpu::Cpu(Chip& chip, Isr isr)
    : chip_(chip), isr_(std::move(isr)), stack_(std::make_unique<char[]>(kStackSize)) {
  if (::getcontext(&firmware_ctx_) != 0) {
    throw std::system_error(errno, std::generic_category(), "getcontext");
  }
  firmware_ctx_.uc_stack.ss_sp = stack_.get();
  firmware_ctx_.uc_stack.ss_size = kStackSize;
  firmware_ctx_.uc_link = &bus_ctx_;  // body() returning ends up where the bus side switched
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
  __sanitizer_start_switch_fiber(nullptr, t_bus_stack.bottom, t_bus_stack.size);
#endif
  // Returning resumes uc_link: the bus side, where it last switched.
}

void Cpu::body() {
  try {
    for (;;) {
      try {
        isr_(*this);
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

void Cpu::hand_to_firmware() {
  started_ = true;
  other_hal_ = hal::exchange_selection(other_hal_);
  switch_context(bus_ctx_, firmware_ctx_, stack_.get(), kStackSize);
  other_hal_ = hal::exchange_selection(other_hal_);
  if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
}

void Cpu::hand_to_bus_side() {
#ifdef DPC31_ASAN_FIBERS
  switch_context(firmware_ctx_, bus_ctx_, t_bus_stack.bottom, t_bus_stack.size);
#else
  switch_context(firmware_ctx_, bus_ctx_, nullptr, 0);
#endif
  if (stop_) throw Stopped{};
}

void Cpu::gate() {
  // A stop request (an observer of the bus side, e.g. the master seeing an answer start) takes
  // control back before the next access, as reaching the limit does.
  while (chip_.cycle() >= limit_ || chip_.stop_requested()) hand_to_bus_side();
}

std::uint8_t Cpu::read(std::uint32_t addr) {
  gate();
  return chip_.read(addr);
}

void Cpu::write(std::uint32_t addr, std::uint8_t value) {
  gate();
  chip_.write(addr, value);
}

void Cpu::run_until(std::uint64_t cycle) {
  while (chip_.cycle() < cycle && !chip_.stop_requested()) {
    limit_ = cycle;
    if (in_isr_) {
      hand_to_firmware();  // an ISR in progress continues with its next access
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

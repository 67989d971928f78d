// Interrupt controller: Int_Reg is computed, acknowledges and user writes never swallow an
// event latched in the same cycle, and the X/INT line follows IR and the EOI inactive time.
#include "irq.hpp"

namespace dpc31 {

void InterruptController::install_hooks(HookTable& h) {
  bind_hooks(h, RegId::Int_Reg, *this).read = [](const void* b) {
    const RegisterFile& regs = self<InterruptController>(b).regs_;
    return static_cast<std::uint16_t>(regs.latch(RegId::Int_Req_Reg) &
                                      ~regs.latch(RegId::Int_Mask_Reg));
  };
  // "If a new event and an acknowledge for the same bit coincide, the event stays set."
  const auto keep_events = [](void* b, std::uint16_t /*old*/, std::uint16_t next) {
    return static_cast<std::uint16_t>(next | self<InterruptController>(b).events_now());
  };
  bind_hooks(h, RegId::Int_Req_Reg, *this).pre_write = keep_events;
  bind_hooks(h, RegId::Int_Ack_Reg, *this).pre_write = keep_events;
}

// After the register file's reset (X/INT follows the reset IRR and IMR). The reset clears DX_Out
// and C31_Control, so PB3 falls in the reset's cycle, and an active interrupt ends there: their
// observers are told (docs/timing.md).
void InterruptController::reset() {
  const State before = s_;
  s_ = State{};
  s_.line = active();
  tell_since(before.line, before.pb3);
}

void InterruptController::tell_since(bool line, bool pb3) {
  const State now = s_;
  s_.pb3 = pb3;
  set_pb3(now.pb3);
  s_.line = line;
  if (now.line != line) line_changed(now.line);
}

void InterruptController::note_events(std::uint16_t bits, std::uint64_t cycle) {
  if (s_.event_cycle != cycle) {
    s_.event_cycle = cycle;
    s_.event_mask = 0;
  }
  s_.event_mask |= bits;
}

std::uint16_t InterruptController::events_now() const {
  return s_.event_cycle == clock_.now ? s_.event_mask : std::uint16_t{0};
}

void InterruptController::raise(std::uint16_t bits) {
  bits = static_cast<std::uint16_t>(bits & ~regs_.reg(RegId::Int_Req_Reg)->rsvd);
  regs_.latch(RegId::Int_Req_Reg) |= bits;
  note_events(bits, clock_.now);
}

// EOI (Mode_Reg1): X/INT stays inactive for 1 us, or 1 ms with Mode_Reg0.EOI_Time_Base, even
// if IR is still set (docs/timing.md, "Interrupt line", [S-TIM]).
void InterruptController::end_of_interrupt() {
  const std::uint64_t cycles =
      clock_.cycles_for_us(regs_.mode0(fields::Mode_Reg0::EOI_Time_Base) ? 1000 : 1);
  clock_.arm(s_.eoi, cycles);
  sig_.log(LogLevel::debug, "EOI: X/INT inactive until cycle {}", clock_.now + cycles);
}

void InterruptController::line_changed(bool active) {
  s_.line = active;
  if (sig_.irq) sig_.irq(clock_.now, active);
}

void InterruptController::set_pb3(bool level) {
  if (s_.pb3 == level) return;
  s_.pb3 = level;
  if (sig_.pb3) sig_.pb3(clock_.now, level);
}

}  // namespace dpc31

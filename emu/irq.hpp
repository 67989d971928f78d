// Interrupt controller (chip-facts §2): IRR latched independent of IMR, IR = IRR & ~IMR,
// X/INT = OR of IR unless inside the inactive time that follows an EOI. On the DPC31 the
// DX_Out interrupt can also drive port PB3 (seed 003, p.32).
// The DPC31 has the controller twice at the same addresses, for the external processor and for
// the C31 core; this block is the one the bus reaches (ChipOptions::irq_controller). The other
// one is never written: its mask keeps its reset value FFFFh, so its line never becomes active,
// and its registers, which no one can read, are not kept (docs/dpc31.md).
#pragma once

#include <cstdint>
#include <limits>

#include "reg_hooks.hpp"
#include "regfile.hpp"
#include "signals.hpp"
#include "timer.hpp"

namespace dpc31 {

class InterruptController {
 public:
  struct State {
    // The EOI inactive time: X/INT may not become active while it runs.
    Timer eoi = Timer::elapsed();
    // Events latched in the current cycle survive an acknowledge in that same cycle.
    std::uint64_t event_cycle = std::numeric_limits<std::uint64_t>::max();
    std::uint16_t event_mask = 0;
    bool line = false;  // last computed X/INT activity (for change notifications)
    bool pb3 = false;   // port PB3 (below)
  };

  InterruptController(Clock& clock, RegisterFile& regs, const Signals& sig, IrqController served)
      : clock_(clock), regs_(regs), sig_(sig), served_(served) {}
  void reset();
  // The observers last saw X/INT's activity `line` and PB3 `pb3` (before a reset or the load of
  // a snapshot): tells them each level that differs now, at this cycle.
  void tell_since(bool line, bool pb3);
  // Binds the hooks of the registers this block owns (reg_hooks.hpp).
  void install_hooks(HookTable& h);

  // IRR |= bits, noted as this cycle's events. X/INT is not looked at here: whoever ends the
  // cycle's events (the engine's step, a bus access's completion, the harness) calls update_line
  // once, so an observer sees IRR with all of that cycle's events (docs/timing.md, step 6).
  void raise(std::uint16_t bits);
  void end_of_interrupt();  // EOI (Mode_Reg1): the inactive time starts
  [[nodiscard]] bool active() const {
    return !clock_.running(s_.eoi) &&
           (regs_.latch(RegId::Int_Req_Reg) & ~regs_.latch(RegId::Int_Mask_Reg)) != 0;
  }
  // X/INT from IR and the inactive time; tells on_irq_change. Inline: every step and every IMR
  // write asks.
  void update_line() {
    if (s_.pb3 && (regs_.latch(RegId::Int_Req_Reg) & irq::DX_Out) == 0) set_pb3(false);
    if (const bool now_active = active(); now_active != s_.line) line_changed(now_active);
  }
  [[nodiscard]] bool line() const { return s_.line; }
  [[nodiscard]] IrqController served() const { return served_; }
  // The external processor's controller drives X/INT; with the C31's served, that is the other,
  // fully masked one.
  [[nodiscard]] bool x_int_active() const { return served_ == IrqController::external && active(); }
  // What an acknowledge or IRR write in this cycle must keep (the events of this cycle).
  [[nodiscard]] std::uint16_t events_now() const;
  void note_events(std::uint16_t bits, std::uint64_t cycle);
  [[nodiscard]] std::uint64_t inactive_until() const { return clock_.due(s_.eoi); }
  Timer& eoi_timer() { return s_.eoi; }  // the engine counts it

  // dpc31 port PB3 with Enable_DX_Out_Port (C31_Control bit 0): high from the DX_Out of a
  // Global_Control with Sync (without Unsync: that is an Unsync) until the user acknowledges
  // DX_Out (seed 003, p.32).
  void set_pb3(bool level);
  [[nodiscard]] bool pb3() const { return s_.pb3; }

 private:
  friend struct BlockAccess;
  void line_changed(bool active);  // the slow half of update_line: the observers
  Clock& clock_;
  RegisterFile& regs_;
  const Signals& sig_;
  const IrqController served_;
  State s_;
};

}  // namespace dpc31

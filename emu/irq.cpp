// Interrupt controller hooks: Int_Reg is computed, acknowledges and user writes never swallow an
// event latched in the same cycle, and the X/INT line follows IR and the EOI inactive time.
#include "core.hpp"

namespace dpc31 {

namespace {

std::uint16_t int_reg(const ChipCore& c) {
  return static_cast<std::uint16_t>(c.latch[ChipCore::idx(RegId::Int_Req_Reg)] &
                                    ~c.latch[ChipCore::idx(RegId::Int_Mask_Reg)]);
}

// "If a new event and an acknowledge for the same bit coincide, the event stays set."
std::uint16_t keep_events(ChipCore& c, std::uint16_t /*old*/, std::uint16_t next) {
  return static_cast<std::uint16_t>(next | c.irq.events_at(c.now));
}

}  // namespace

void install_irq_hooks(HookTable& h) {
  h[ChipCore::idx(RegId::Int_Reg)].read = int_reg;
  h[ChipCore::idx(RegId::Int_Req_Reg)].pre_write = keep_events;
  h[ChipCore::idx(RegId::Int_Ack_Reg)].pre_write = keep_events;
}

namespace {

template <typename Ar, typename S>
void members(Ar& ar, S& s) {
  static_assert(snap::member_count<IrqController>() == 3, "a new member: add it here");
  ar(s.eoi.at);
  ar(s.eoi.left);
  ar(s.event_cycle);
  ar(s.event_mask);
}

}  // namespace

void save_state(snap::Writer& w, const IrqController& s) {
  w.section("IRQC");
  members(w, s);
}
void load_state(snap::Reader& r, IrqController& s) {
  r.section("IRQC");
  members(r, s);
}

void ChipCore::raise(std::uint16_t bits) {
  const RegDesc* irr = reg(RegId::Int_Req_Reg);
  bits = static_cast<std::uint16_t>(bits & ~irr->rsvd);
  latch[idx(RegId::Int_Req_Reg)] |= bits;
  irq.note_events(bits, now);
  update_irq_line();
}

// EOI (Mode_Reg1): X/INT stays inactive for 1 us, or 1 ms with Mode_Reg0.EOI_Time_Base, even
// if IR is still set (docs/timing.md, "Interrupt line", [S-TIM]).
void ChipCore::end_of_interrupt() {
  const std::uint64_t cycles = cycles_for_us(mode0(fields::Mode_Reg0::EOI_Time_Base) ? 1000 : 1);
  arm(irq.eoi, cycles);
  log(LogLevel::debug, "EOI: X/INT inactive until cycle {}", now + cycles);
}

bool ChipCore::irq_active() const {
  return !running(irq.eoi) &&
         (latch[idx(RegId::Int_Req_Reg)] & ~latch[idx(RegId::Int_Mask_Reg)]) != 0;
}

void ChipCore::update_irq_line() {
  if (pb3 && (latch[idx(RegId::Int_Req_Reg)] & irq::DX_Out) == 0) set_pb3(false);
  const bool active = irq_active();
  if (active == irq_line) return;
  irq_line = active;
  if (irq_observer) irq_observer(now, active);
}

}  // namespace dpc31

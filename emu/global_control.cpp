// Global_Control (SAP58), as the DPC31 manual describes it (seed 003): Sync, Unsync, Freeze,
// Unfreeze, Clear_Data; reserved bits 7, 6, 0 -> Not_Supported and Leave_Master unless the check
// is switched off; Sync/Freeze without support treated like a reserved bit; Group_Select.
#include "dp_sm.hpp"

namespace dpc31 {

namespace cc = pdu::control_command;

void DpStateMachine::global_control(const fdl::Frame& req) {
  // Ignored for any of three reasons; the log names the first that holds.
  if (s_.state != DpState::Data_Exchange) {
    ++counters_.not_allowed;
    sig_.log(LogLevel::info, "Global_Control from {}: not in Data_Exchange: ignored", req.sa);
    return;
  }
  if (req.sa != s_.master_add) {
    ++counters_.not_allowed;
    sig_.log(LogLevel::info, "Global_Control from {}: not the locking master: ignored", req.sa);
    return;
  }
  if (req.du.size() != 2) {
    ++counters_.not_allowed;
    sig_.log(LogLevel::info, "Global_Control from {}: {} data bytes, not 2: ignored", req.sa,
             req.du.size());
    return;
  }
  const std::uint8_t groups = req.du[1];
  if (groups != 0 && (groups & s_.group_ident) == 0) return;  // addressed to other groups
  sig_.emit(BlockEvent::Kind::gc, req.du[0]);
  apply_global_control(req.du[0]);
}

// The block-level part: what an accepted Control_Command does to buffers and interrupts.
void DpStateMachine::apply_global_control(std::uint8_t command) {
  // The option bits: dpc31 Param_Reg, VPC3+ Mode_Reg2 (bit 0 interrupt mode, bit 1 no check).
  const std::uint16_t options = regs_.id() == Profile::dpc31      ? regs_.latch(RegId::Param_Reg)
                                : regs_.id() == Profile::vpc3plus ? regs_.latch(RegId::Mode_Reg2)
                                                                  : 0;
  static_assert(fields::Param_Reg::New_GC_Int_Mode == fields::Mode_Reg2::GC_Int_Mode &&
                fields::Param_Reg::Check_No_GC_Reserved == fields::Mode_Reg2::No_Check_GC_Reserved);
  const bool every_gc_interrupts = (options & fields::Mode_Reg2::GC_Int_Mode) != 0;
  const bool check_reserved = (options & fields::Mode_Reg2::No_Check_GC_Reserved) == 0;
  const bool bad =
      (check_reserved && (command & cc::Reserved) != 0) ||
      ((command & cc::Sync) != 0 && !regs_.mode0(fields::Mode_Reg0::Sync_Supported)) ||
      ((command & cc::Freeze) != 0 && !regs_.mode0(fields::Mode_Reg0::Freeze_Supported));
  if (bad) {
    sig_.log(LogLevel::info, "Global_Control {:02X}h: not supported: Not_Supported, Leave_Master",
             command);
    leave_master();
    s_.not_supported = true;
    return;
  }
  const std::uint8_t previous = regs_.cell(RegId::R_GC_Command);
  regs_.set_cell(RegId::R_GC_Command, command);
  if (every_gc_interrupts || command != previous) irq_.raise(irq::New_GC_Command);

  if ((command & cc::Clear_Data) != 0) {
    buffers_.failsafe_clear();
  }
  // Unsync wins over Sync; both hand the outputs received since the last hand-over (D) to the
  // user with DX_Out, unless Clear_Data already did. With nothing new in D, DX_Out comes all the
  // same (the manual's wording is unconditional) and no buffer changes hands.
  if ((command & (cc::Sync | cc::Unsync)) != 0) {
    s_.sync_mode = (command & cc::Unsync) == 0;
    if ((command & cc::Clear_Data) == 0) {
      if (buffers_.d_fresh()) {
        buffers_.dout_received();
      } else {
        irq_.raise(irq::DX_Out);
      }
    }
  }
  // "the interrupt 'DX_OUT' can directly be applied to the port PB3 if a global control message
  // is received with 'Sync', provided 'Enable DX_OUT_Port=1' was parameterized in the C31_Control
  // register beforehand" (seed 003, p.32). Sync with Unsync is an Unsync: no PB3.
  if ((command & (cc::Sync | cc::Unsync)) == cc::Sync && regs_.id() == Profile::dpc31 &&
      (regs_.latch(RegId::C31_Control) & fields::C31_Control::Enable_DX_Out_Port) != 0 &&
      (regs_.latch(RegId::Int_Req_Reg) & irq::DX_Out) != 0) {
    irq_.set_pb3(true);
  }
  if ((command & (cc::Freeze | cc::Unfreeze)) != 0) {
    s_.freeze_mode = (command & cc::Unfreeze) == 0;
    buffers_.din_fetch();  // the newest inputs (N) are taken into D, then frozen or not
  }
}

}  // namespace dpc31

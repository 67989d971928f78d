// DP state machine hooks: the user's verdict on Set_Prm and Chk_Cfg (User_Prm/Cfg_Data_(Not_)Okay)
// and SSA_Buffer_Free_Cmd. New_Prm_Data / New_Cfg_Data are cleared here, never through IAR.
#include <utility>

#include "core.hpp"

namespace dpc31 {

namespace {

constexpr std::uint16_t kEn_Change_Cfg_Buffer = 1u << 4;

enum class Verdict { ok, not_ok };

template <Handshake DpStateMachine::*Which>
std::uint16_t handshake_preview(const ChipCore& c) {
  return (c.dp.*Which).preview();
}

void prm_done(ChipCore& c, Verdict v) {
  c.latch[ChipCore::idx(RegId::Int_Req_Reg)] &= static_cast<std::uint16_t>(~irq::New_Prm_Data);
  c.dp.prm_fault = v == Verdict::not_ok;
  if (v == Verdict::not_ok) {
    c.leave_master();
  } else if (c.dp.state == DpState::Wait_Prm) {
    c.dp.state = DpState::Wait_Cfg;
  }
}

void cfg_done(ChipCore& c, Verdict v) {
  c.latch[ChipCore::idx(RegId::Int_Req_Reg)] &= static_cast<std::uint16_t>(~irq::New_Cfg_Data);
  c.dp.cfg_fault = v == Verdict::not_ok;
  if (v == Verdict::not_ok) {
    c.leave_master();
    return;
  }
  if ((c.latch[ChipCore::idx(RegId::Mode_Reg1)] & kEn_Change_Cfg_Buffer) != 0) {
    // Get_Cfg answers the new configuration from now on.
    const RegDesc* cfg = c.reg(RegId::R_Cfg_Buf_Ptr);
    const RegDesc* read_cfg = c.reg(RegId::R_Read_Cfg_Buf_Ptr);
    std::swap(c.mem[static_cast<std::uint32_t>(cfg->read_addr)],
              c.mem[static_cast<std::uint32_t>(read_cfg->read_addr)]);
  }
  if (c.dp.state == DpState::Wait_Cfg) {
    c.dp.state = DpState::Data_Exchange;
    c.raise(irq::Go_Leave_Data_Exchange);
  }
}

template <Handshake DpStateMachine::*Which, void (*Done)(ChipCore&, Verdict), Verdict V>
std::uint16_t handshake_command(ChipCore& c) {
  bool done = false;
  const std::uint8_t r = (c.dp.*Which).answer(done);
  if (done) Done(c, V);
  return r;
}

}  // namespace

void install_dp_sm_hooks(HookTable& h) {
  auto set = [&h](RegId id, auto read, auto command) {
    h[ChipCore::idx(id)].read = read;
    h[ChipCore::idx(id)].command = command;
  };
  set(RegId::User_Prm_Data_Okay, handshake_preview<&DpStateMachine::prm>,
      handshake_command<&DpStateMachine::prm, prm_done, Verdict::ok>);
  set(RegId::User_Prm_Data_Not_Okay, handshake_preview<&DpStateMachine::prm>,
      handshake_command<&DpStateMachine::prm, prm_done, Verdict::not_ok>);
  set(RegId::User_Cfg_Data_Okay, handshake_preview<&DpStateMachine::cfg>,
      handshake_command<&DpStateMachine::cfg, cfg_done, Verdict::ok>);
  set(RegId::User_Cfg_Data_Not_Okay, handshake_preview<&DpStateMachine::cfg>,
      handshake_command<&DpStateMachine::cfg, cfg_done, Verdict::not_ok>);
  set(
      RegId::SSA_Buffer_Free_Cmd, [](const ChipCore&) -> std::uint16_t { return 0; },
      [](ChipCore& c) -> std::uint16_t {
        c.dp.ssa_free = true;  // SAP55 accepts Set_Slave_Add again
        return 0;
      });
}

}  // namespace dpc31

// Mode registers and the chip's run state: Mode_Reg0 (written only while Offline), the
// Mode_Reg1 set/reset pair (Start_SPC3, EOI, Go_Offline, User_Leave_Master), VPC3+ Mode_Reg2,
// the Status register that reports the result, and the User_Timer_Clock.
#include "mode.hpp"

namespace dpc31 {

void ModeRegisters::install_hooks(HookTable& h) {
  auto at = [&h, this](RegId id) -> RegHooks& { return bind_hooks(h, id, *this); };
  // Mode_Reg0 and Mode_Reg2 configure the chip and may only change while it is Offline.
  const auto offline_only = [](void* b, std::uint16_t old, std::uint16_t next) {
    const ModeRegisters& m = self<ModeRegisters>(b);
    if (!m.dp_.started() || old == next) return next;
    m.sig_.log(LogLevel::warn,
               "mode register written while started (Passive_Idle): ignored, write it in Offline");
    return old;
  };
  at(RegId::Mode_Reg0).pre_write = offline_only;
  at(RegId::Mode_Reg2).pre_write = offline_only;
  at(RegId::Mode_Reg2).post_write = [](void* b, std::uint16_t, std::uint16_t now, std::uint16_t) {
    self<ModeRegisters>(b).regs_.follow_mode2(now);
  };
  // Only the bits the profile's Mode_Reg1_S takes act: on the DPC31 Start_SPC3, Go_Offline,
  // User_Leave_Master and Res_User_WD are requests (IGN here, docs/dpc31.md).
  at(RegId::Mode_Reg1_S).post_write = [](void* b, std::uint16_t, std::uint16_t,
                                         std::uint16_t written) {
    ModeRegisters& m = self<ModeRegisters>(b);
    m.command(written & m.regs_.reg(RegId::Mode_Reg1_S)->w1s);
  };
  at(RegId::Status_Reg).read = [](const void* b) { return self<ModeRegisters>(b).status(); };
}

// The actions follow the bits written as 1 (a command), not the stored value: Go_Offline stays
// set while Offline, yet a later Start alone must not take the chip Offline again.
void ModeRegisters::command(std::uint16_t written) {
  if ((written & fields::Mode_Reg1::Start_SPC3) != 0) start();
  if ((written & fields::Mode_Reg1::EOI) != 0) irq_.end_of_interrupt();
  if ((written & fields::Mode_Reg1::User_Leave_Master) != 0) dp_.leave_master();
  if ((written & fields::Mode_Reg1::Go_Offline) != 0) {
    // Written with Start_SPC3: Start first, then Go_Offline, which stays 1 as after its own
    // write (docs/timing.md), though the Start cleared it.
    regs_.latch(RegId::Mode_Reg1) |= fields::Mode_Reg1::Go_Offline;
    go_offline("Go_Offline");
  }
}

void ModeRegisters::start() {
  if (dp_.started()) return;
  dp_.start();
  regs_.clear_ram_access_violation();
  regs_.latch(RegId::Mode_Reg1) &= static_cast<std::uint16_t>(~fields::Mode_Reg1::Go_Offline);
  watchdog_.reset();
  clock_.arm(s_.user, user_timer_period());
  // R_GC_Command at every start of the DP slave: the DPC31 presets FFh "at initialization"
  // (seed 003; DPC31 p.26: MAC_Start is when "the DPS is powered up"), the SPC3 00h "during
  // initialization" (SPC3 p.36); the VPC3+ leaves the cell alone ("not initialized", VPC3+C p.50).
  // The preset is the cell's reset value of the register description.
  if (regs_.id() != Profile::vpc3plus) {
    regs_.set_cell(RegId::R_GC_Command,
                   static_cast<std::uint8_t>(regs_.reg(RegId::R_GC_Command)->reset));
  }
  mac_.start_search();
  sig_.log(LogLevel::info, "Start_SPC3: Offline -> Passive_Idle");
  // Power-on: the ASIC clears the output buffer and hands it to the user (DX_Out).
  buffers_.dout_clear();
}

// "go Offline after the current request" (SPC3 Mode_Reg1 bit 2; MAC_Reset "after finishing the
// current request"): with a request in progress the MAC calls offline() at its end.
void ModeRegisters::go_offline(std::string_view cause) {
  if (!dp_.started() || mac_.defer_offline(cause)) return;
  offline();
}

void ModeRegisters::offline() {
  if (!dp_.started()) return;
  regs_.latch(RegId::Mode_Reg1) &= static_cast<std::uint16_t>(~fields::Mode_Reg1::Start_SPC3);
  // The MAC reset puts the DP and watchdog state machines back into their reset states.
  watchdog_.reset();
  s_.user = Timer{};
  dp_.reset();
  mac_.stop();
  sig_.log(LogLevel::info, "Passive_Idle -> Offline (MAC_Reset)");
  irq_.raise(irq::MAC_Reset);
}

std::uint32_t ModeRegisters::user_timer_period() const {
  return static_cast<std::uint32_t>(
      clock_.cycles_for_us(regs_.mode0(fields::Mode_Reg0::User_Time_Base) ? 10000 : 1000));
}

// User_Timer_Clock: while the chip is started, every 1 ms (10 ms with Mode_Reg0.User_Time_Base).
void ModeRegisters::user_timer_tick() {
  clock_.arm(s_.user, user_timer_period());
  irq_.raise(irq::User_Timer_Clock);
}

// A User_Timer_Clock tick while its IRR bit is still set changes nothing anyone can see (the bit
// stays set, X/INT stays as it is) unless an acknowledge lands in its cycle, which needs a bus
// access, so not before `bound`. Such ticks before the next other deadline are counted, not
// visited: a silent bus with the user timer running costs one step per other deadline, not one
// per millisecond. The last skipped tick is noted as the event of its cycle, as visiting it would.
// `bound`: the earlier of the end of the step and the next other deadline.
void ModeRegisters::skip_quiet_user_ticks(std::uint64_t bound) {
  Timer& t = s_.user;
  if (t.at >= bound) return;
  if ((regs_.latch(RegId::Int_Req_Reg) & irq::User_Timer_Clock) == 0) return;
  const std::uint64_t p = user_timer_period();
  const std::uint64_t last = t.at + (bound - 1 - t.at) / p * p;
  irq_.note_events(irq::User_Timer_Clock, last);
  t.at = last + p;
}

std::uint16_t ModeRegisters::status() const {
  namespace f = fields::Status_Reg;
  return static_cast<std::uint16_t>(
      field_value(f::Offline_Passive_Idle, dp_.started() ? 1u : 0u) |
      field_value(f::Diag_Flag, buffers_.diag_flag() ? 1u : 0u) |
      field_value(f::RAM_Access_Violation, regs_.ram_access_violation() ? 1u : 0u) |
      field_value(f::DP_State, static_cast<unsigned>(dp_.state())) |
      field_value(f::WD_State, static_cast<unsigned>(watchdog_.state())) |
      field_value(f::Baudrate, watchdog_.baud_code()) | field_value(f::Release, release_));
}

}  // namespace dpc31

// Mode registers and the chip's run state: Mode_Reg0 (written only while Offline), the
// Mode_Reg1 set/reset pair (Start_SPC3, EOI, Go_Offline, User_Leave_Master), VPC3+ Mode_Reg2,
// and the Status register that reports the result.
#include "core.hpp"

namespace dpc31 {

namespace {

// Mode_Reg0 and Mode_Reg2 configure the chip and may only change while it is Offline.
std::uint16_t offline_only(ChipCore& c, std::uint16_t old, std::uint16_t next) {
  if (!c.started || old == next) return next;
  c.log(LogLevel::warn,
        "mode register written while started (Passive_Idle): ignored, write it in Offline");
  return old;
}

// The actions follow the bits written as 1 (a command), not the stored value: Go_Offline stays
// set while Offline, yet a later Start alone must not take the chip Offline again.
void mode_reg1_set(ChipCore& c, std::uint16_t /*old*/, std::uint16_t /*now*/) {
  const std::uint16_t written = c.written_bits;
  if ((written & fields::Mode_Reg1::Start_SPC3) != 0) c.start();
  if ((written & fields::Mode_Reg1::EOI) != 0) c.end_of_interrupt();
  if ((written & fields::Mode_Reg1::User_Leave_Master) != 0) c.leave_master();
  if ((written & fields::Mode_Reg1::Go_Offline) != 0) c.go_offline();
}

void mode_reg2_written(ChipCore& c, std::uint16_t /*old*/, std::uint16_t now) {
  c.large_ram = c.prof->ram_size_large != 0 && (now & fields::Mode_Reg2::_4kB_Mode) != 0;
}

std::uint16_t status_reg(const ChipCore& c) { return c.status(); }

}  // namespace

void install_mode_hooks(HookTable& h) {
  h[ChipCore::idx(RegId::Mode_Reg0)].pre_write = offline_only;
  h[ChipCore::idx(RegId::Mode_Reg2)].pre_write = offline_only;
  h[ChipCore::idx(RegId::Mode_Reg2)].post_write = mode_reg2_written;
  h[ChipCore::idx(RegId::Mode_Reg1_S)].post_write = mode_reg1_set;
  h[ChipCore::idx(RegId::Status_Reg)].read = status_reg;
}

void ChipCore::start() {
  if (started) return;
  started = true;
  ram_access_violation = false;
  latch[idx(RegId::Mode_Reg1)] &= static_cast<std::uint16_t>(~fields::Mode_Reg1::Go_Offline);
  timers.reset();
  arm(timers.user, user_timer_period());
  dp.reset();
  buffers.end_clear();
  dp.station = cell(RegId::R_TS_Adr);
  dp.no_add_change = cell(RegId::R_Real_No_Add_Change) == 0xFF;
  // R_GC_Command at every start of the DP slave: the DPC31 presets FFh "at initialization"
  // (seed 003; DPC31 p.26: MAC_Start is when "the DPS is powered up"), the SPC3 00h "during
  // initialization" (SPC3 p.36); the VPC3+ leaves the cell alone ("not initialized", VPC3+C p.50).
  // The preset is the cell's reset value of the register description.
  if (prof->id != Profile::vpc3plus) {
    set_cell(RegId::R_GC_Command, static_cast<std::uint8_t>(reg(RegId::R_GC_Command)->reset));
  }
  mac_start_search();
  log(LogLevel::info, "Start_SPC3: Offline -> Passive_Idle");
  // Power-on: the ASIC clears the output buffer and hands it to the user (DX_Out).
  dout_clear();
}

void ChipCore::go_offline() {
  if (!started) return;
  started = false;
  latch[idx(RegId::Mode_Reg1)] &= static_cast<std::uint16_t>(~fields::Mode_Reg1::Start_SPC3);
  // The MAC reset puts the DP and watchdog state machines back into their reset states.
  timers.reset();
  dp.reset();
  mac_stop();
  log(LogLevel::info, "Passive_Idle -> Offline (MAC_Reset)");
  raise(irq::MAC_Reset);
}

void ChipCore::leave_master() {
  if (!started) return;
  const DpState was = dp.state;
  dp.state = DpState::Wait_Prm;
  dp.prm = Handshake{};
  dp.cfg = Handshake{};
  dp.master_add = 0xFF;  // unlocked: any master may parameterise us again
  dp.sync_mode = false;
  dp.freeze_mode = false;
  dp.user_wd_armed = false;
  dp.fcb_valid = false;
  dp.dx_on_new_din = false;
  buffers.end_clear();
  log(LogLevel::info, "Leave_Master: DP state -> Wait_Prm");
  if (was == DpState::Data_Exchange) raise(irq::Go_Leave_Data_Exchange);
  dout_clear();
}

std::uint32_t ChipCore::user_timer_period() const {
  return cycles_for_us(mode0(fields::Mode_Reg0::User_Time_Base) ? 10000 : 1000);
}

// User_Timer_Clock: while the chip is started, every 1 ms (10 ms with Mode_Reg0.User_Time_Base).
void ChipCore::user_timer_tick() {
  arm(timers.user, user_timer_period());
  raise(irq::User_Timer_Clock);
}

std::uint16_t ChipCore::status() const {
  namespace f = fields::Status_Reg;
  return static_cast<std::uint16_t>(
      field_value(f::Offline_Passive_Idle, started ? 1u : 0u) |
      field_value(f::Diag_Flag, buffers.diag_flag ? 1u : 0u) |
      field_value(f::RAM_Access_Violation, ram_access_violation ? 1u : 0u) |
      field_value(f::DP_State, static_cast<unsigned>(dp.state)) |
      field_value(f::WD_State, static_cast<unsigned>(timers.wd)) |
      field_value(f::Baudrate, baud_code) | field_value(f::Release, release));
}

}  // namespace dpc31

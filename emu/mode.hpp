// Mode registers and the chip's run state: Mode_Reg0 (written only while Offline), the Mode_Reg1
// set/reset pair (Start_SPC3, EOI, Go_Offline, User_Leave_Master), VPC3+ Mode_Reg2, the Status
// register that reports the result, and the User_Timer_Clock time base (1 ms / 10 ms) that runs
// while the chip is started.
#pragma once

#include <cstdint>
#include <string_view>

#include "buffers.hpp"
#include "dp_sm.hpp"
#include "irq.hpp"
#include "mac.hpp"
#include "reg_hooks.hpp"
#include "regfile.hpp"
#include "signals.hpp"
#include "timer.hpp"
#include "watchdog.hpp"

namespace dpc31 {

class ModeRegisters {
 public:
  struct State {
    Timer user;  // the next User_Timer_Clock tick
  };

  ModeRegisters(Clock& clock, RegisterFile& regs, InterruptController& irq, BufferUnit& buffers,
                DpStateMachine& dp, Watchdog& watchdog, Mac& mac, const Signals& sig,
                std::uint8_t release)
      : clock_(clock),
        regs_(regs),
        irq_(irq),
        buffers_(buffers),
        dp_(dp),
        watchdog_(watchdog),
        mac_(mac),
        sig_(sig),
        release_(release) {
    mac_.offline_due = [this] { offline(); };
  }
  void reset() { s_ = State{}; }
  // Binds the hooks of the registers this block owns (reg_hooks.hpp).
  void install_hooks(HookTable& h);

  // Mode_Reg1_S written: the actions of the bits written as 1.
  void command(std::uint16_t written);
  void start();  // Start_SPC3: Offline -> Passive_Idle
  // Go_Offline (and a RAM access violation): the MAC reset after the current request; `cause`
  // names which in the log line.
  void go_offline(std::string_view cause);
  void offline();  // the MAC reset now (MAC_Stop; the end of the request go_offline waited for)
  [[nodiscard]] std::uint16_t status() const;  // Status_Reg

  void user_timer_tick();  // its timer is reached
  // Event engine: ticks that change nothing anyone sees are counted, not visited (engine.cpp).
  void skip_quiet_user_ticks(std::uint64_t bound);
  [[nodiscard]] std::uint64_t user_timer_at() const { return s_.user.at; }
  Timer& user_timer() { return s_.user; }  // the engine counts it

 private:
  friend struct BlockAccess;
  [[nodiscard]] std::uint32_t user_timer_period() const;
  Clock& clock_;
  RegisterFile& regs_;
  InterruptController& irq_;
  BufferUnit& buffers_;
  DpStateMachine& dp_;
  Watchdog& watchdog_;
  Mac& mac_;
  const Signals& sig_;
  std::uint8_t release_;  // Status_Reg bits 15..12: the profile's, or the VPC3+ variant's
  State s_;
};

}  // namespace dpc31

// The DPC31's request interface (DPC31 HW description p.22, §5.1.3, p.31; docs/dpc31.md): the user
// asks the chip for MAC_Start, MAC_Stop, MAC_New_TRDY, User_Leave_Master and DPS_User_Wd through
// the Instruction_Queue in RAM, and the chip answers through the Indication_Queue (MAC_Stop's
// confirmation, DPS_User_WD Expired). The DPS_User_Watchdog lives here because only requests
// drive it and it reports through an indication. Only the dpc31 profile has the queues' cells;
// on the SPC3 and the VPC3+ this block never acts.
#pragma once

#include <cstdint>

#include "dp_sm.hpp"
#include "dpc31/dp.hpp"
#include "irq.hpp"
#include "mode.hpp"
#include "reg_hooks.hpp"
#include "regfile.hpp"
#include "signals.hpp"
#include "timer.hpp"

namespace dpc31 {

class RequestInterface {
 public:
  struct State {
    Timer wd;                   // the DPS_User_Watchdog's next 10 ms decrement
    std::uint16_t wd_left = 0;  // its 16-bit count
    bool wd_locked = false;     // expired: only DPS_User_Wd Reset unlocks it
  };

  RequestInterface(Clock& clock, RegisterFile& regs, InterruptController& irq, DpStateMachine& dp,
                   ModeRegisters& mode, const Signals& sig)
      : clock_(clock), regs_(regs), irq_(irq), dp_(dp), mode_(mode), sig_(sig) {}
  void reset() { s_ = State{}; }
  // Binds the hooks of the registers this block owns (reg_hooks.hpp).
  void install_hooks(HookTable& h);

  // InstQ_Wr written: the MAC executes every request from InstQ_Rd up to it.
  void instq_written();
  void wd_tick();  // the DPS_User_Watchdog's timer is reached
  [[nodiscard]] std::uint64_t due() const { return clock_.due(s_.wd); }
  Timer& timer() { return s_.wd; }  // the engine counts it

 private:
  friend struct BlockAccess;
  void execute(std::uint8_t code, std::uint8_t param);
  void user_wd(std::uint8_t param);
  void indicate(std::uint8_t code, std::uint8_t event);
  Clock& clock_;
  RegisterFile& regs_;
  InterruptController& irq_;
  DpStateMachine& dp_;
  ModeRegisters& mode_;
  const Signals& sig_;
  State s_;
};

}  // namespace dpc31

// Watchdog state machine (seed 002): Baud_Search -> Baud_Control -> DP_Control. Baud_Control
// watches the baud rate (WD_Baud_Control_Val x 10 ms), DP_Control the master (TWD = 1 or 10 ms x
// WD_Fact_1 x WD_Fact_2). Its timer is an engine timer (timer.hpp).
#pragma once

#include <cstdint>

#include "dpc31/chip.hpp"
#include "irq.hpp"
#include "regfile.hpp"
#include "signals.hpp"
#include "timer.hpp"

namespace dpc31 {

class Watchdog {
 public:
  struct State {
    WdState wd = WdState::Baud_Search;
    Timer timer;                     // Baud_Control or DP_Control expiry
    bool dp_wd_on = false;           // Set_Prm WD_On: DP_Control monitors the master
    std::uint64_t dp_wd_cycles = 0;  // TWD in clocks
    std::uint8_t baud_code = 0;  // Status_Reg bits 11..8 (0 = 12 Mbaud, where Baud_Search starts)
  };
  // What an expiry asks of the chip: the DP state machine's Leave_Master (DP_Control), or a new
  // Baud_Search of the MAC (Baud_Control).
  enum class Expiry : std::uint8_t { none, dp_control, baud_control };

  Watchdog(Clock& clock, const RegisterFile& regs, InterruptController& irq, const Signals& sig)
      : clock_(clock), regs_(regs), irq_(irq), sig_(sig) {}
  void reset();     // the MAC reset: Baud_Search, nothing monitored (the baud code stays)
  void power_on();  // a hardware reset: also the baud code

  // Baud_Search heard a telegram at kBaudRates[code]: DP_Control (TWD from now) when parameters
  // with WD_On = 1 were accepted in Baud_Search, else Baud_Control.
  void baud_found(std::uint8_t code);
  // The parameters a Set_Prm brought take effect (User_Prm_Data_Okay); in Baud_Search they wait
  // for the rate found.
  void parameterise(bool wd_on, std::uint8_t f1, std::uint8_t f2, bool base_1ms);
  // An error-free telegram from `master` to our address: Baud_Control restarts for any station,
  // DP_Control only for the locking master (`master_add`).
  void retrigger(std::uint8_t master, std::uint8_t master_add);
  // Unlocked (Set_Prm Unlock_Req): no master to monitor, DP_Control -> Baud_Control.
  void release();
  void master_left();  // the DP state machine's Leave_Master
  Expiry expire();     // its timer is reached

  [[nodiscard]] WdState state() const { return s_.wd; }
  [[nodiscard]] bool dp_wd_on() const { return s_.dp_wd_on; }
  [[nodiscard]] std::uint8_t baud_code() const { return s_.baud_code; }
  [[nodiscard]] std::uint64_t due() const { return clock_.due(s_.timer); }
  Timer& timer() { return s_.timer; }  // the engine counts it

 private:
  friend struct BlockAccess;
  void enter_baud_control();
  void enter_monitoring();  // DP_Control or Baud_Control, as the accepted parameters ask
  Clock& clock_;
  const RegisterFile& regs_;
  InterruptController& irq_;
  const Signals& sig_;
  State s_;
};

}  // namespace dpc31

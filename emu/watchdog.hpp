// Timers: the User_Timer_Clock time base (1 ms / 10 ms) and the watchdog state machine.
// Both are engine timers (timer.hpp): the event engine skips idle time, deadline to deadline.
#pragma once

#include <cstdint>

#include "dpc31/chip.hpp"
#include "snapshot.hpp"
#include "timer.hpp"

namespace dpc31 {

struct Timers {
  Timer user;  // the next User_Timer_Clock tick
  WdState wd = WdState::Baud_Search;
  Timer watchdog;                  // Baud_Control or DP_Control expiry
  bool dp_wd_on = false;           // Set_Prm WD_On: DP_Control monitors the master
  std::uint64_t dp_wd_cycles = 0;  // TWD in clocks
  void reset() { *this = Timers{}; }
};

void save_state(snap::Writer& w, const Timers& s);
void load_state(snap::Reader& r, Timers& s);

}  // namespace dpc31

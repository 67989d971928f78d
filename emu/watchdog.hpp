// Timers: the User_Timer_Clock time base (1 ms / 10 ms) and the watchdog state machine.
// Every timer is a deadline in absolute cycles, so idle time is skipped, not stepped.
#pragma once

#include <cstdint>
#include <limits>

#include "dpc31/chip.hpp"
#include "snapshot.hpp"

namespace dpc31 {

inline constexpr std::uint64_t kNever = std::numeric_limits<std::uint64_t>::max();

struct Timers {
  std::uint64_t user_timer_next = kNever;  // next User_Timer_Clock event
  WdState wd = WdState::Baud_Search;
  std::uint64_t wd_deadline = kNever;  // Baud_Control or DP_Control expiry
  bool dp_wd_on = false;               // Set_Prm WD_On: DP_Control monitors the master
  std::uint64_t dp_wd_cycles = 0;      // TWD in clocks
  // Per-cycle engine: clocks to the next User_Timer_Clock / to the watchdog expiry (kNever: off).
  std::uint64_t user_left = kNever;
  std::uint64_t wd_left = kNever;
  void reset() { *this = Timers{}; }
};

void save_state(snap::Writer& w, const Timers& s);
void load_state(snap::Reader& r, Timers& s);

}  // namespace dpc31

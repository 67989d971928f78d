// Timers: the User_Timer_Clock time base (1 ms / 10 ms) and the watchdog state machine.
// Every timer is a deadline in absolute cycles, so idle time is skipped, not stepped.
#pragma once

#include <cstdint>
#include <limits>

#include "dpc31/chip.hpp"

namespace dpc31 {

inline constexpr std::uint64_t kNever = std::numeric_limits<std::uint64_t>::max();

struct Timers {
  std::uint64_t user_timer_next = kNever;  // next User_Timer_Clock event
  WdState wd = WdState::Baud_Search;
  void reset() { *this = Timers{}; }
};

}  // namespace dpc31

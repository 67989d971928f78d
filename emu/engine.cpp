// How time advances (docs/engine.md). Two engines share every action — what happens: a character
// reaches the MAC, an interrupt is raised, a watchdog expires — and differ only in deciding when:
// - event (the default): every timer is an absolute deadline, and advance() jumps from one
//   deadline to the next; the receiver is handed RxD edges and samples them when asked.
// - per_cycle: every clock is evaluated as RTL would: counters count down, the receiver looks at
//   RxD each clock, the transmitter shifts bit by bit. It never reads a deadline of the event
//   engine, so the two agreeing (tests: Engine.*) checks the event engine's arithmetic.
// The blocks never ask which engine runs: they arm their timers through the Clock (timer.hpp).
#include <algorithm>

#include "core.hpp"

namespace dpc31 {

bool ChipCore::advance_to(std::uint64_t end, Stop stop_at) {
  return clock.engine == Engine::per_cycle ? advance_clocks(end, stop_at)
                                           : advance_events(end, stop_at);
}

// The watchdog's expiry asks the chip for what its state machine does next.
void ChipCore::watchdog_expired() {
  switch (watchdog.expire()) {
    case Watchdog::Expiry::none:
      break;
    case Watchdog::Expiry::dp_control:  // WD_DP_Control_Timeout is latched already
      signals.emit(BlockEvent::Kind::wd_expired);
      dp.dp_control_expired();
      break;
    case Watchdog::Expiry::baud_control:
      mac.start_search();
      break;
  }
}

// ---- event engine ----

std::uint64_t ChipCore::next_event() const {
  if (clock.engine == Engine::per_cycle) return clock.now + 1;
  return std::min(mode.user_timer_at(), next_event_but_user_timer());
}

std::uint64_t ChipCore::line_event() const {
  if (clock.engine == Engine::per_cycle) return clock.now + 1;
  // A User_Timer_Clock tick while its IRR bit is set shows nothing (skip_quiet_user_ticks) until a
  // bus access acknowledges it: the chip takes it inside its next step.
  const bool quiet_tick = (regs.latch(RegId::Int_Req_Reg) & irq::User_Timer_Clock) != 0;
  return std::min(quiet_tick ? kNever : mode.user_timer_at(), next_event_but_user_timer(true));
}

std::uint64_t ChipCore::next_event_but_user_timer(bool for_line) const {
  // The end of the EOI inactive time is an event: X/INT may become active there.
  const std::uint64_t eoi_end = irq.inactive_until();
  return std::min({watchdog.due(), eoi_end > clock.now ? eoi_end : kNever,
                   for_line ? mac.line_deadline() : mac.deadline(), requests.due()});
}

// Everything due at `now`, in the order of docs/timing.md.
void ChipCore::process_events() { run_due<false>(); }

// The events of both engines; the MAC's step is `Mac::process` (the event engine: up to now) or
// `Mac::clock` (the per-cycle reference: this clock).
template <bool kPerCycle>
void ChipCore::run_due() {
  if (clock.reached(mode.user_timer())) mode.user_timer_tick();
  if constexpr (kPerCycle) {
    mac.clock();
  } else {
    mac.process();
  }
  if (mac.take_txd_wake()) stop = true;
  if (clock.reached(watchdog.timer())) watchdog_expired();
  if (clock.reached(requests.timer())) requests.wd_tick();
  // The events above only latched IRR: X/INT once, with all of them (docs/timing.md, step 6).
  irq.update_line();
  signals.state(clock.now);
}

bool ChipCore::advance_events(std::uint64_t end, Stop stop_at) {
  clock.quiet_until = 0;  // the events below may arm new deadlines
  for (;;) {
    const std::uint64_t other = next_event_but_user_timer();
    // Quiet ticks up to and including `end`: a tick that falls exactly on a step's end must not
    // become an event in one run and be skipped in another cut into other steps.
    mode.skip_quiet_user_ticks(end < other ? end + 1 : other);
    const std::uint64_t next = std::min(mode.user_timer_at(), other);
    if (next > end) {
      // Not past the last cycle: a block transfer's quiet run (bus.cpp) and a bus access end at
      // it, as a step does (Chip::cycle_after).
      clock.quiet_until = std::min(next, Chip::kLastCycle);
      break;
    }
    clock.now = std::max(clock.now, next);
    const bool was_active = irq.line();
    process_events();
    if (stop_at != Stop::never && irq.line() && !was_active) return true;
    if (stop_at == Stop::on_irq_or_request && stop) return false;
  }
  clock.now = end;
  return false;
}

// ---- per-cycle engine ----

// One clock of a running timer.
static void count_clock(Timer& t) {
  if (t.left != kNever && t.left != 0) --t.left;
}

bool ChipCore::advance_clocks(std::uint64_t end, Stop stop_at) {
  while (clock.now < end) {
    const bool was_active = irq.line();
    tick();
    if (stop_at != Stop::never && irq.line() && !was_active) return true;
    if (stop_at == Stop::on_irq_or_request && stop) return false;
  }
  return false;
}

void ChipCore::tick() {
  ++clock.now;
  count_clock(irq.eoi_timer());
  // The watchdog counts this clock before the MAC may retrigger it, and expires after.
  count_clock(watchdog.timer());
  count_clock(mode.user_timer());
  count_clock(requests.timer());
  run_due<true>();
}

}  // namespace dpc31

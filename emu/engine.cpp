// How time advances (docs/engine.md). Two engines share every action — what happens: a character
// reaches the MAC, an interrupt is raised, a watchdog expires — and differ only in deciding when:
// - event (the default): every timer is an absolute deadline, and advance() jumps from one
//   deadline to the next; the receiver is handed RxD edges and samples them when asked.
// - per_cycle: every clock is evaluated as RTL would: counters count down, the receiver looks at
//   RxD each clock, the transmitter shifts bit by bit. It never reads a deadline of the event
//   engine, so the two agreeing (tests: Engine.*) checks the event engine's arithmetic.
#include <algorithm>

#include "core.hpp"

namespace dpc31 {

std::uint64_t ChipCore::cycles_for_us(std::uint64_t us) const {
  // Round up: the manuals give minimum times ("at least 1 us").
  return (std::uint64_t{clock_hz} * us + 999'999u) / 1'000'000u;
}

bool ChipCore::advance_to(std::uint64_t end, Stop stop_at) {
  return engine == Engine::per_cycle ? advance_clocks(end, stop_at) : advance_events(end, stop_at);
}

void ChipCore::reset_time() {
  now = 0;
  quiet_until = 0;
}

// ---- the timers (timer.hpp; arm, reached, running, due: core.hpp, inline) ----

// Per-cycle engine: one clock of a running timer.
static void count_clock(Timer& t) {
  if (t.left != kNever && t.left != 0) --t.left;
}

void ChipCore::arm_search_window() {
  if (engine == Engine::event) {
    mac.search_deadline = now + std::uint64_t{kBaudSearchBits} * mac.rx.bit_time();
    note_deadline(mac.search_deadline);
  } else {
    mac.search.start(kBaudSearchBits);
  }
}

void ChipCore::stop_search_window() {
  mac.search_deadline = kNever;
  mac.search.on = false;
}

void ChipCore::drive_rxd(std::uint64_t cycle, bool level) {
  const std::uint64_t at = std::max(cycle, now);
  quiet_until = 0;
  if (engine == Engine::event) {
    // The receiver samples edges as they are given; the queue only serves a later reconfigure.
    while (!rxd_pending.empty() && rxd_pending.front().first <= now) rxd_pending.pop_front();
    mac.rx.edge(at, level);
    if (at > now) rxd_pending.emplace_back(at, level);
  } else if (at > now) {
    rxd_pending.emplace_back(at, level);
  } else {
    // This clock is already evaluated: the edge counts for it, its samples are taken.
    rxd_level = level;
    if (mac.sampler.late_edge(level, now)) mac.gap.on = false;
  }
  rxd_observer(at, level);
}

// ---- event engine ----

std::uint64_t ChipCore::next_event() const {
  if (engine == Engine::per_cycle) return now + 1;
  return std::min(timers.user.at, next_event_but_user_timer());
}

std::uint64_t ChipCore::next_event_but_user_timer() const {
  // The end of the EOI inactive time is an event: X/INT may become active there.
  const std::uint64_t eoi_end = irq.eoi.at > now ? irq.eoi.at : kNever;
  return std::min({timers.watchdog.at, eoi_end, mac_deadline()});
}

// A User_Timer_Clock tick while its IRR bit is still set changes nothing anyone can see (the bit
// stays set, X/INT stays as it is) unless an acknowledge lands in its cycle, which needs a bus
// access, so not before `end`. Such ticks before the next other deadline are counted, not
// visited: a silent bus with the user timer running costs one step per other deadline, not one
// per millisecond. The last skipped tick is noted as the event of its cycle, as visiting it would.
// `bound`: the earlier of the end of the step and the next other deadline.
void ChipCore::skip_quiet_user_ticks(std::uint64_t bound) {
  Timer& t = timers.user;
  if (t.at >= bound) return;
  if ((latch[idx(RegId::Int_Req_Reg)] & irq::User_Timer_Clock) == 0) return;
  const std::uint64_t p = user_timer_period();
  const std::uint64_t last = t.at + (bound - 1 - t.at) / p * p;
  irq.note_events(irq::User_Timer_Clock, last);
  t.at = last + p;
}

// Everything due at `now`, in the order of docs/timing.md.
void ChipCore::process_events() {
  if (reached(timers.user)) user_timer_tick();
  mac_process();
  if (reached(timers.watchdog)) watchdog_expired();
  update_irq_line();
  state_observer(now);
}

bool ChipCore::advance_events(std::uint64_t end, Stop stop_at) {
  quiet_until = 0;  // the events below may arm new deadlines
  for (;;) {
    const std::uint64_t other = next_event_but_user_timer();
    skip_quiet_user_ticks(std::min(end, other));
    const std::uint64_t next = std::min(timers.user.at, other);
    if (next > end) {
      quiet_until = next;
      break;
    }
    now = std::max(now, next);
    const bool was_active = irq_line;
    process_events();
    if (stop_at != Stop::never && irq_line && !was_active) return true;
    if (stop_at == Stop::on_irq_or_request && stop) return false;
  }
  now = end;
  return false;
}

// ---- per-cycle engine ----

bool ChipCore::advance_clocks(std::uint64_t end, Stop stop_at) {
  while (now < end) {
    const bool was_active = irq_line;
    clock();
    if (stop_at != Stop::never && irq_line && !was_active) return true;
    if (stop_at == Stop::on_irq_or_request && stop) return false;
  }
  return false;
}

void ChipCore::clock() {
  ++now;
  while (!rxd_pending.empty() && rxd_pending.front().first <= now) {
    rxd_level = rxd_pending.front().second;
    rxd_pending.pop_front();
  }
  count_clock(irq.eoi);
  // The watchdog counts this clock before the MAC may retrigger it, and expires after.
  count_clock(timers.watchdog);
  count_clock(timers.user);
  if (reached(timers.user)) user_timer_tick();
  mac_clock();
  if (reached(timers.watchdog)) watchdog_expired();
  update_irq_line();
  state_observer(now);
}

}  // namespace dpc31

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

// ---- timers armed by the actions ----

void ChipCore::arm_user_timer() {
  if (engine == Engine::event) {
    timers.user_timer_next = now + user_timer_period();
  } else {
    timers.user_left = user_timer_period();
  }
}

void ChipCore::arm_watchdog(std::uint64_t cycles) {
  if (engine == Engine::event) {
    timers.wd_deadline = cycles == kNever ? kNever : now + cycles;
  } else {
    timers.wd_left = cycles;
  }
}

std::uint64_t ChipCore::watchdog_due() const {
  if (engine == Engine::event) return timers.wd_deadline;
  return timers.wd_left == kNever ? kNever : now + timers.wd_left;
}

void ChipCore::arm_eoi() {
  if (engine == Engine::event) {
    irq.eoi_block_until = now + eoi_inactive_cycles();
  } else {
    irq.eoi_left = eoi_inactive_cycles();
  }
}

bool ChipCore::irq_active() const {
  const bool inactive_time =
      engine == Engine::event ? now < irq.eoi_block_until : irq.eoi_left != 0;
  return !inactive_time && (latch[idx(RegId::Int_Req_Reg)] & ~latch[idx(RegId::Int_Mask_Reg)]) != 0;
}

void ChipCore::arm_search_window() {
  if (engine == Engine::event) {
    mac.search_deadline = now + std::uint64_t{kBaudSearchBits} * mac.rx.bit_time();
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
  return std::min(timers.user_timer_next, next_event_but_user_timer());
}

std::uint64_t ChipCore::next_event_but_user_timer() const {
  const std::uint64_t eoi_end = irq.eoi_block_until > now ? irq.eoi_block_until : kNever;
  return std::min({timers.wd_deadline, eoi_end, mac_deadline()});
}

// A User_Timer_Clock tick while its IRR bit is still set changes nothing anyone can see (the bit
// stays set, X/INT stays as it is) unless an acknowledge lands in its cycle, which needs a bus
// access, so not before `end`. Such ticks before the next other deadline are counted, not
// visited: a silent bus with the user timer running costs one step per other deadline, not one
// per millisecond. The last skipped tick is noted as the event of its cycle, as visiting it would.
// `bound`: the earlier of the end of the step and the next other deadline.
void ChipCore::skip_quiet_user_ticks(std::uint64_t bound) {
  if (timers.user_timer_next >= bound) return;
  if ((latch[idx(RegId::Int_Req_Reg)] & irq::User_Timer_Clock) == 0) return;
  const std::uint64_t p = user_timer_period();
  const std::uint64_t last = timers.user_timer_next + (bound - 1 - timers.user_timer_next) / p * p;
  irq.note_events(irq::User_Timer_Clock, last);
  timers.user_timer_next = last + p;
}

// Everything due at `now`, in the order of docs/timing.md.
void ChipCore::process_events() {
  if (timers.user_timer_next <= now) {
    timers.user_timer_next = now + user_timer_period();
    raise(irq::User_Timer_Clock);
  }
  mac_process();
  if (timers.wd_deadline <= now) watchdog_expired();
  update_irq_line();
  state_observer(now);
}

bool ChipCore::advance_events(std::uint64_t end, Stop stop_at) {
  quiet_until = 0;  // the events below may arm new deadlines
  for (;;) {
    const std::uint64_t other = next_event_but_user_timer();
    skip_quiet_user_ticks(std::min(end, other));
    const std::uint64_t next = std::min(timers.user_timer_next, other);
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
  if (irq.eoi_left != 0) --irq.eoi_left;
  // The watchdog counts this clock before the MAC may retrigger it, and expires after.
  if (timers.wd_left != kNever && timers.wd_left != 0) --timers.wd_left;
  if (timers.user_left != kNever && --timers.user_left == 0) {
    timers.user_left = user_timer_period();
    raise(irq::User_Timer_Clock);
  }
  mac_clock();
  if (timers.wd_left == 0) watchdog_expired();
  update_irq_line();
  state_observer(now);
}

void ChipCore::mac_clock() {
  const std::uint32_t t = mac.rx.bit_time();
  UartChar ch;
  const UartSampler::Clock r = mac.sampler.clock(rxd_level, now, ch);
  if (r.ready) mac_char(ch);
  // Idle inside a telegram counts from the end of a stop bit; a start bit ends the gap, but one
  // on the very clock TSYN is reached comes too late (the gap is 33 bit times).
  if (mac.gap.tick(t) && mac.in_frame) mac_truncated();
  if (r.ended && mac.in_frame) mac.gap.start(kTsynBits);
  if (r.started) mac.gap.on = false;
  if (mac.search.tick(t)) mac_search_next();
  TxShifter& tx = mac.shifter;
  switch (tx.phase) {
    case TxShifter::Phase::idle:
      break;
    case TxShifter::Phase::wait_end:
      if (r.ended) {
        tx.phase = TxShifter::Phase::tsdr;
        tx.timer.start(tx.tsdr_bits);
      }
      break;
    case TxShifter::Phase::tsdr:
      if (tx.timer.tick(t)) {
        tx.phase = TxShifter::Phase::shifting;
        tx.index = 0;
        tx.bit = 0;
        tx.sub = 0;
        mac_txd(now, uart_bit(tx.bytes[0], 0));
      }
      break;
    case TxShifter::Phase::shifting:
      if (++tx.sub < t) break;
      tx.sub = 0;
      if (++tx.bit == kUartCharBits) {
        tx.bit = 0;
        ++tx.index;
      }
      if (tx.index < tx.bytes.size()) {
        mac_txd(now, uart_bit(tx.bytes[tx.index], tx.bit));
      } else {
        mac_txd(now, true);
        mac_tx_done();
      }
      break;
  }
}

}  // namespace dpc31

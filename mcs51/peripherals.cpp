// The 80C32's timers 0, 1 and 2, its serial port and its interrupt system, advanced machine cycle
// by machine cycle (Intel MCS-51 User's Manual, "Hardware Description of the 8051, 8052 and
// 80C51"; the sampling rules are written down in docs/cpu.md).
#include <algorithm>
#include <array>
#include <bit>

#include "mcs51/cpu.hpp"

namespace mcs51 {

namespace {
// TCON, SCON, T2CON, PCON bits.
constexpr std::uint8_t it0 = 0x01, ie0 = 0x02, it1 = 0x04, ie1 = 0x08, tr0 = 0x10, tf0 = 0x20,
                       tr1 = 0x40, tf1 = 0x80;
constexpr std::uint8_t ri = 0x01, ti = 0x02, rb8 = 0x04, sm2 = 0x20, ren = 0x10;
constexpr std::uint8_t cp_rl2 = 0x01, c_t2 = 0x02, tr2 = 0x04, exen2 = 0x08, tclk = 0x10,
                       rclk = 0x20, exf2 = 0x40, tf2 = 0x80;
constexpr std::uint8_t smod = 0x80, idl = 0x01;
// Pin sample bits: INT0, INT1, T0, T1, T2, T2EX.
constexpr std::uint8_t p_int0 = 1, p_int1 = 2, p_t0 = 4, p_t1 = 8, p_t2 = 16, p_t2ex = 32;

constexpr std::uint64_t max_horizon = 1u << 20;

// One count of a timer in mode 0 (13 bits: TL's low 5 bits under TH), 1 (16 bits) or 2 (TL
// reloaded from TH); true on overflow.
bool count(std::uint8_t& tl, std::uint8_t& th, unsigned mode) {
  switch (mode) {
    case 0: {
      auto low = static_cast<std::uint8_t>((tl + 1) & 0x1F);
      tl = static_cast<std::uint8_t>((tl & 0xE0) | low);
      return low == 0 && ++th == 0;
    }
    case 1:
      return ++tl == 0 && ++th == 0;
    default:
      if (++tl != 0) return false;
      tl = th;
      return true;
  }
}

}  // namespace

// An instruction, call or idle cycle that cannot be deferred: the peripherals tick every cycle.
StepResult Cpu::slow_step() {
  if (cycles_ < idle_until_) {  // idle and quiet (replan): the cycle is only counted
    ++cycles_;
    ++lag_;
    return {StepKind::idle, 1};
  }
  const std::uint8_t op = code_[pc_];
  const unsigned n = cycle_table[op];
  sync();
  if (powered_down()) {  // the oscillator is stopped: only time outside passes
    ++cycles_;
    return {StepKind::power_down, 1};
  }
  if (next_irq_ >= 0) {
    int source = next_irq_;
    next_irq_ = -1;  // the first instruction of the routine runs before any further call
    // An instruction that set IDL and was followed by an accepted call: the call ends idle ("the
    // activation of any enabled interrupt will cause PCON.0 to be cleared by hardware").
    sf(sfr::PCON) &= static_cast<std::uint8_t>(~idl);
    call_interrupt(source);
    irq_dirty_ = stale_ = true;
    replan();
    return {StepKind::interrupt, 2};
  }
  std::uint8_t before = requests();
  raised_ = 0;
  if (idle()) {  // the CPU stops, the peripherals run; an accepted interrupt ends idle
    tick(1);
    const std::uint8_t after = requests();
    next_irq_ = choose(before & after);
    if (next_irq_ >= 0) sf(sfr::PCON) &= static_cast<std::uint8_t>(~idl);
    // Clean when nothing was called and no request came: the next idle cycle polls the same.
    irq_dirty_ = next_irq_ >= 0 || after != before;
    replan();
    return {StepKind::idle, 1};
  }
  block_ = false;
  insn_start_ = cycles_;
  // The instruction acts at the end of its last machine cycle ("the new value arrives at the
  // latch during S6P2 of the final cycle"): the peripherals run all its cycles on the old
  // values. A request counts if it was sampled before that last cycle (the poll happens in the
  // cycle after the sample) and is still pending after the instruction (docs/cpu.md).
  tick(n - 1);
  const auto sampled = static_cast<std::uint8_t>(before | raised_);
  // A MOVX's bus access ends with RD / WR in S3/S4 of its second cycle, before that cycle's pin
  // sample at S5P2: what the access does to a pin (X/INT on INT0) is sampled in that cycle.
  const bool movx = is_movx(op);
  if (!movx) tick(1);
  ++pc_;
  dispatch_[op](*this);
  if (movx) {
    sync();
    tick(1);
  }
  set_parity();
  poll_after(sampled);
  replan();
  return {StepKind::instruction, n};
}

// The poll at the end of an instruction: a request sampled before its last cycle and still
// pending. The poll is clean (its answer, none, holds until an input changes) unless a call was
// chosen, the next call is held off, or a request is pending that this poll did not sample.
void Cpu::poll_after(std::uint8_t sampled) {
  const std::uint8_t req = requests();
  next_irq_ = block_ ? -1 : choose(sampled & req);
  irq_dirty_ = block_ || next_irq_ >= 0 || (req & ~sampled) != 0;
  last_req_ = req;
  block_ = false;  // set again only by an instruction, which makes the poll dirty
}

void Cpu::sync() {
  std::uint64_t left = lag_;
  lag_ = 0;
  cycles_ -= left;  // tick() counts them again
  while (left != 0) {
    const auto n = static_cast<unsigned>(std::min<std::uint64_t>(left, 1u << 30));
    left -= n;
    tick(n);
  }
}
bool Cpu::next_is_movx() const {
  return !powered_down() && !idle() && next_irq_ < 0 && is_movx(code_[pc_]);
}

std::uint8_t Cpu::requests() const {
  std::uint8_t tcon = sfr_latch(sfr::TCON);
  return static_cast<std::uint8_t>(((tcon & ie0) ? 1 : 0) | ((tcon & tf0) ? 2 : 0) |
                                   ((tcon & ie1) ? 4 : 0) | ((tcon & tf1) ? 8 : 0) |
                                   ((sfr_latch(sfr::SCON) & (ri | ti)) ? 16 : 0) |
                                   ((sfr_latch(sfr::T2CON) & (tf2 | exf2)) ? 32 : 0));
}

// The source called next: enabled, of the higher level first, then in polling order; none while
// a routine of the same or a higher level is in service.
int Cpu::choose(std::uint8_t requested) const {
  std::uint8_t ie = sfr_latch(sfr::IE);
  if ((ie & 0x80) == 0) return -1;
  auto enabled = static_cast<std::uint8_t>(requested & ie & 0x3F);
  auto high = static_cast<std::uint8_t>(enabled & sfr_latch(sfr::IP));
  if (high != 0 && (in_service_ & 2) == 0) return std::countr_zero(high);
  auto low = static_cast<std::uint8_t>(enabled & ~sfr_latch(sfr::IP));
  if (low != 0 && in_service_ == 0) return std::countr_zero(low);
  return -1;
}

// The hardware LCALL: 2 machine cycles; the timer flags and an edge-triggered external flag are
// cleared, the serial and timer 2 flags are left to the routine.
void Cpu::call_interrupt(int source) {
  insn_start_ = cycles_;
  push(static_cast<std::uint8_t>(pc_));
  push(static_cast<std::uint8_t>(pc_ >> 8));
  pc_ = static_cast<std::uint16_t>(3 + 8 * source);
  bool high = ((sfr_latch(sfr::IP) >> source) & 1) != 0;
  in_service_ |= high ? 2 : 1;
  std::uint8_t& tcon = sf(sfr::TCON);
  switch (source) {
    case 0:
      if (tcon & it0) tcon &= static_cast<std::uint8_t>(~ie0);
      break;
    case 1:
      tcon &= static_cast<std::uint8_t>(~tf0);
      break;
    case 2:
      if (tcon & it1) tcon &= static_cast<std::uint8_t>(~ie1);
      break;
    case 3:
      tcon &= static_cast<std::uint8_t>(~tf1);
      break;
    default:
      break;
  }
  raised_ = 0;
  tick(2);
}

void Cpu::raise(std::uint8_t addr, std::uint8_t mask, int source) {
  if ((sf(addr) & mask) == 0) irq_dirty_ = true;
  sf(addr) |= mask;
  raised_ |= static_cast<std::uint8_t>(1u << source);
}

void Cpu::set_port_input(unsigned port, std::uint8_t value) {
  if (port_in_[port & 3] == value) return;  // the same pins: nothing to sample again
  sync();                                   // the cycles so far ran with the old pins
  port_in_[port & 3] = value;
  pins_dirty_ = true;
  unplan();
}

void Cpu::set_pin(unsigned port, unsigned bit, bool high) {
  std::uint8_t m = static_cast<std::uint8_t>(1u << bit);
  set_port_input(port, static_cast<std::uint8_t>(high ? port_in_[port] | m : port_in_[port] & ~m));
}

void Cpu::schedule_int0(std::uint64_t at, bool high) {
  sync();
  int0_change_ = {at, high, true};
  unplan();
}

void Cpu::unplan() {
  stale_ = true;
  horizon_ = idle_until_ = 0;
}

// The machine cycle up to which the peripherals may lag: while each level-triggered input's flag
// already follows its pin (set while it is low, clear while high), timer 2 stops, the serial port
// is quiet (serial_quiet), no character is on its way and timers 0 and 1 are not in mode 3, a
// running timer's next overflow is the only new request it can raise; one that would only raise a
// flag already set (mode 2) sets no bound. In
// idle the same bound holds for the idle cycles, whose poll cannot change before it
// (`idle_until_`; instructions are not run then).
void Cpu::replan() {
  stale_ = false;
  horizon_ = cycles_;
  idle_until_ = 0;
  if (irq_dirty_ || next_irq_ >= 0 || pins_dirty_ || int0_change_.pending) return;
  const std::uint8_t tcon = sfr_latch(sfr::TCON), tmod = sfr_latch(sfr::TMOD);
  const std::uint8_t pins = last_pins_;
  if (powered_down()) return;  // the oscillator stopped: one cycle per step
  if (!(tcon & it0) && ((pins & p_int0) == 0) != ((tcon & ie0) != 0)) return;
  if (!(tcon & it1) && ((pins & p_int1) == 0) != ((tcon & ie1) != 0)) return;
  if ((sfr_latch(sfr::T2CON) & (tr2 | exen2)) != 0) return;
  if (!serial_quiet() || tx_bits_ != -2 || rx_ticks_ >= 0) return;
  if ((tmod & 3) == 3 || (tmod & 0x30) == 0x30) return;
  std::uint64_t h = max_horizon;
  for (unsigned t = 0; t < 2; ++t) {
    const unsigned ctl = (tmod >> (4 * t)) & 0x0F;
    const bool run = (tcon & (t ? tr1 : tr0)) && (!(ctl & 0x08) || (pins & (t ? p_int1 : p_int0)));
    if (!run || (ctl & 0x04)) continue;  // stopped, or counting edges of a pin that holds still
    const unsigned tl = sfr_latch(t ? sfr::TL1 : sfr::TL0), th = sfr_latch(t ? sfr::TH1 : sfr::TH0);
    const bool flag = (tcon & (t ? tf1 : tf0)) != 0;
    switch (ctl & 3) {
      case 0:
        h = std::min<std::uint64_t>(h, 0x2000u - (th << 5 | (tl & 0x1Fu)) - 1);
        break;
      case 1:
        h = std::min<std::uint64_t>(h, 0x10000u - (th << 8 | tl) - 1);
        break;
      default:
        if (!flag) h = std::min<std::uint64_t>(h, 0x100u - tl - 1);
        break;
    }
  }
  horizon_ = cycles_ - lag_ + h;
  if (idle()) {
    idle_until_ = horizon_;
    horizon_ = cycles_;
  }
}

// Nothing in the serial port changes by itself: modes 1 and 3 move only with timer 1's or timer
// 2's overflows; mode 0 with nothing to shift out and no reception to start (REN clear or RI
// set). Mode 2's divider counts every machine cycle.
bool Cpu::serial_quiet() const {
  const std::uint8_t scon = sfr_latch(sfr::SCON);
  switch (scon >> 6) {
    case 0:
      return tx_bits_ == -2 && rx_ticks_ < 0 && ((scon & ren) == 0 || (scon & ri) != 0);
    case 2:
      return false;
    default:
      return true;
  }
}

bool Cpu::pin(unsigned port, unsigned bit) const { return (port_pins(port) >> bit & 1) != 0; }

void Cpu::serial_receive(std::uint8_t data, bool bit8) {
  sync();
  unplan();
  std::uint8_t scon = sfr_latch(sfr::SCON);
  if ((scon & ren) == 0 || (scon >> 6) == 0) return;  // receiver off, or mode 0 (no start bit)
  // The stop bit is sampled at 9.5 bit times (mode 1), the ninth data bit's stop at 10.5.
  rx_ticks_ = (scon >> 6) == 1 ? 152 : 168;
  rx_data_ = data;
  rx_bit8_ = bit8;
}

// The pins change only between steps (from outside, or by a port write): sampled once per call,
// an edge falls in the call's first cycle. Only the running blocks are advanced cycle by cycle.
void Cpu::tick(unsigned cycles) {
  if (cycles == 0) return;
  if (int0_change_.pending && int0_change_.at < cycles_ + cycles) {  // split at the change
    const auto first =
        static_cast<unsigned>(int0_change_.at > cycles_ ? int0_change_.at - cycles_ : 0);
    int0_change_.pending = false;
    tick(first);
    set_int0(int0_change_.high);
    tick(cycles - first);
    return;
  }
  std::uint8_t pins = last_pins_;
  if (pins_dirty_) {
    pins_dirty_ = false;
    pins = static_cast<std::uint8_t>((pin(3, 2) ? p_int0 : 0) | (pin(3, 3) ? p_int1 : 0) |
                                     (pin(3, 4) ? p_t0 : 0) | (pin(3, 5) ? p_t1 : 0) |
                                     (pin(1, 0) ? p_t2 : 0) | (pin(1, 1) ? p_t2ex : 0));
  }
  auto fall = static_cast<std::uint8_t>(last_pins_ & ~pins);
  last_pins_ = pins;

  // External interrupts: edge-triggered flags latch a high-to-low transition between two
  // samples; level-triggered flags follow the pin.
  std::uint8_t& tcon = sf(sfr::TCON);
  if (tcon & it0) {
    if (fall & p_int0) raise(sfr::TCON, ie0, 0);
  } else if ((pins & p_int0) == 0) {
    raise(sfr::TCON, ie0, 0);
  } else if (tcon & ie0) {
    tcon &= static_cast<std::uint8_t>(~ie0);
    irq_dirty_ = true;
  }
  if (tcon & it1) {
    if (fall & p_int1) raise(sfr::TCON, ie1, 2);
  } else if ((pins & p_int1) == 0) {
    raise(sfr::TCON, ie1, 2);
  } else if (tcon & ie1) {
    tcon &= static_cast<std::uint8_t>(~ie1);
    irq_dirty_ = true;
  }
  const bool t01 = (tcon & (tr0 | tr1)) != 0 || (sfr_latch(sfr::TMOD) & 3) == 3;
  const bool t2 = (sfr_latch(sfr::T2CON) & (tr2 | exen2)) != 0;
  const unsigned mode = sfr_latch(sfr::SCON) >> 6;
  if (!t2 && serial_quiet() && (!t01 || timers01_bulk(cycles, fall, pins))) {
    cycles_ += cycles;
    return;
  }
  for (unsigned i = 0; i < cycles; ++i) {
    ++cycles_;
    if (t01) timers01(fall, pins);
    if (t2) timer2(fall);
    if (mode == 0) {
      serial_mode0();
    } else if (mode == 2) {
      unsigned t = (sfr_latch(sfr::PCON) & smod) ? 6 : 3;  // osc/32 or osc/64 per bit
      serial(t, t);
    }
    fall = 0;
  }
}

// Timers 0 and 1 over `cycles` at once: a count that wraps modes 0 and 1 or any count in mode 3
// goes cycle by cycle (false, nothing changed); mode 2's reloads are counted in bulk, each
// overflow raising the flag and (timer 1) clocking the serial port as one cycle at a time would.
bool Cpu::timers01_bulk(unsigned cycles, std::uint8_t fall, std::uint8_t pins) {
  const std::uint8_t tmod = sfr_latch(sfr::TMOD);
  const std::uint8_t tcon = sfr_latch(sfr::TCON);
  if ((tmod & 3) == 3 || (tmod & 0x30) == 0x30) return false;
  unsigned counts[2] = {};
  for (unsigned t = 0; t < 2; ++t) {
    const unsigned ctl = (tmod >> (4 * t)) & 0x0F;
    const bool run = (tcon & (t ? tr1 : tr0)) && (!(ctl & 0x08) || (pins & (t ? p_int1 : p_int0)));
    if (!run) continue;
    counts[t] = (ctl & 0x04) ? ((fall & (t ? p_t1 : p_t0)) ? 1 : 0) : cycles;
    const unsigned tl = sfr_latch(t ? sfr::TL1 : sfr::TL0), th = sfr_latch(t ? sfr::TH1 : sfr::TH0);
    if ((ctl & 3) == 0 && counts[t] >= 0x2000 - (th << 5 | (tl & 0x1F))) return false;
    if ((ctl & 3) == 1 && counts[t] >= 0x10000 - (th << 8 | tl)) return false;
  }
  for (unsigned t = 0; t < 2; ++t) {
    if (counts[t] == 0) continue;
    std::uint8_t& tl = sf(t ? sfr::TL1 : sfr::TL0);
    std::uint8_t& th = sf(t ? sfr::TH1 : sfr::TH0);
    const unsigned m = (tmod >> (4 * t)) & 3;
    if (m == 0) {
      const unsigned v = (th << 5 | (tl & 0x1Fu)) + counts[t];
      tl = static_cast<std::uint8_t>((tl & 0xE0) | (v & 0x1F));
      th = static_cast<std::uint8_t>(v >> 5);
      continue;
    }
    if (m == 1) {
      const unsigned v = (th << 8 | tl) + counts[t];
      tl = static_cast<std::uint8_t>(v);
      th = static_cast<std::uint8_t>(v >> 8);
      continue;
    }
    const unsigned left = 0x100u - tl;
    if (counts[t] < left) {
      tl = static_cast<std::uint8_t>(tl + counts[t]);
      continue;
    }
    const unsigned period = 0x100u - th, past = counts[t] - left;
    const unsigned overflows = 1 + past / period;
    tl = static_cast<std::uint8_t>(th + past % period);
    raise(sfr::TCON, t ? tf1 : tf0, t ? 3 : 1);
    if (t == 1) timer1_clocks_serial(overflows);
  }
  return true;
}

// Timer 1's overflows clock the serial port in modes 1 and 3 (halved unless SMOD).
void Cpu::timer1_clocks_serial(unsigned overflows) {
  if (((sfr_latch(sfr::SCON) >> 6) & 1) == 0) return;
  unsigned ticks = overflows;
  if ((sfr_latch(sfr::PCON) & smod) == 0) {
    ticks = (t1_half_ + overflows) / 2;
    t1_half_ = static_cast<std::uint8_t>((t1_half_ + overflows) & 1);
  }
  if (ticks == 0) return;
  const std::uint8_t t2con = sfr_latch(sfr::T2CON);
  serial((t2con & tclk) ? 0 : ticks, (t2con & rclk) ? 0 : ticks);
}

void Cpu::timers01(std::uint8_t fall, std::uint8_t pins) {
  const std::uint8_t tmod = sfr_latch(sfr::TMOD);
  const std::uint8_t tcon = sfr_latch(sfr::TCON);
  const unsigned m0 = tmod & 3, m1 = (tmod >> 4) & 3;
  // Timer 0: runs with TR0 and (no GATE or INT0 high); counts cycles or T0's falling edges.
  bool run0 = (tcon & tr0) && (!(tmod & 0x08) || (pins & p_int0));
  bool in0 = (tmod & 0x04) ? (fall & p_t0) != 0 : true;
  if (run0 && in0) {
    if (m0 == 3) {  // TL0 an 8-bit timer of its own
      if (++sf(sfr::TL0) == 0) raise(sfr::TCON, tf0, 1);
    } else if (count(sf(sfr::TL0), sf(sfr::TH0), m0)) {
      raise(sfr::TCON, tf0, 1);
    }
  }
  if (m0 == 3 && (tcon & tr1)) {  // TH0 counts cycles under TR1 and owns TF1
    if (++sf(sfr::TH0) == 0) raise(sfr::TCON, tf1, 3);
  }
  // Timer 1: in mode 3 it holds; with timer 0 in mode 3 it runs whenever not in mode 3 (TR1 is
  // TH0's) and only clocks the serial port.
  if (m1 == 3) return;
  bool run1 = m0 == 3 || ((tcon & tr1) && (!(tmod & 0x80) || (pins & p_int1)));
  bool in1 = (tmod & 0x40) ? (fall & p_t1) != 0 : true;
  if (!(run1 && in1) || !count(sf(sfr::TL1), sf(sfr::TH1), m1)) return;
  if (m0 != 3) raise(sfr::TCON, tf1, 3);
  timer1_clocks_serial(1);
}

void Cpu::timer2(std::uint8_t fall) {
  std::uint8_t& t2con = sf(sfr::T2CON);
  const bool baud = (t2con & (tclk | rclk)) != 0;
  auto reload = [&] {
    sf(sfr::TL2) = sfr_latch(sfr::RCAP2L);
    sf(sfr::TH2) = sfr_latch(sfr::RCAP2H);
  };
  if (t2con & tr2) {
    // As a baud rate generator the timer counts at osc/2: 6 counts per machine cycle.
    unsigned n = (t2con & c_t2) ? ((fall & p_t2) ? 1 : 0) : (baud ? 6 : 1);
    for (unsigned i = 0; i < n; ++i) {
      if (++sf(sfr::TL2) != 0 || ++sf(sfr::TH2) != 0) continue;
      if (baud) {
        reload();
        if ((sfr_latch(sfr::SCON) >> 6) & 1) serial((t2con & tclk) ? 1 : 0, (t2con & rclk) ? 1 : 0);
      } else {
        if ((t2con & cp_rl2) == 0) reload();
        raise(sfr::T2CON, tf2, 5);
      }
    }
  }
  if ((t2con & exen2) && (fall & p_t2ex)) {  // T2EX: capture, reload, or only EXF2
    if (!baud) {
      if (t2con & cp_rl2) {
        sf(sfr::RCAP2L) = sfr_latch(sfr::TL2);
        sf(sfr::RCAP2H) = sfr_latch(sfr::TH2);
      } else {
        reload();
      }
    }
    raise(sfr::T2CON, exf2, 5);
  }
}

// The divide-by-16 counters of modes 1, 2 and 3: the transmitter starts a character at the next
// bit boundary after the write to SBUF and sets TI as its stop bit begins; the receiver sets RI
// when it samples the stop bit.
void Cpu::serial(unsigned tx_ticks, unsigned rx_ticks) {
  std::uint8_t& scon = sf(sfr::SCON);
  const unsigned mode = scon >> 6;
  if (tx_bits_ == -2) {  // no character to send: only the free-running divider moves
    tx_div_ = static_cast<std::uint8_t>((tx_div_ + tx_ticks) & 15);
    tx_ticks = 0;
  }
  for (unsigned i = 0; i < tx_ticks; ++i) {  // the divider runs free; bits start at its wrap
    tx_div_ = (tx_div_ + 1) & 15;
    if (tx_div_ != 0 || tx_bits_ == -2) continue;
    const int data_bits = mode == 1 ? 9 : 10;  // start bit, 8 data bits (, TB8)
    if (++tx_bits_ == data_bits) {
      raise(sfr::SCON, ti, 4);
      if (on_serial_tx) on_serial_tx(tx_data_, tx_bit8_, cycles_);
    } else if (tx_bits_ > data_bits) {
      tx_bits_ = -2;  // the stop bit is out
    }
  }
  if (rx_ticks_ < 0) return;
  rx_ticks_ -= static_cast<int>(rx_ticks);
  if (rx_ticks_ > 0) return;
  rx_ticks_ = -1;
  if ((scon & ri) == 0 && ((scon & sm2) == 0 || rx_bit8_)) {
    sf(sfr::SBUF) = rx_data_;
    scon = static_cast<std::uint8_t>(rx_bit8_ ? scon | rb8 : scon & ~rb8);
    raise(sfr::SCON, ri, 4);
  }
}

// Mode 0: a shift register clocked at osc/12; a character is 8 machine cycles. Transmission
// starts with the write to SBUF, reception when REN is set with RI clear; data on RXD (P3.0).
void Cpu::serial_mode0() {
  std::uint8_t& scon = sf(sfr::SCON);
  if (tx_bits_ != -2 && ++tx_bits_ == 8) {
    tx_bits_ = -2;
    raise(sfr::SCON, ti, 4);
    if (on_serial_tx) on_serial_tx(tx_data_, false, cycles_);
  }
  if (rx_ticks_ < 0 && (scon & ren) && !(scon & ri)) {
    rx_ticks_ = 8;
    rx_data_ = 0;
  }
  if (rx_ticks_ < 0) return;
  rx_data_ = static_cast<std::uint8_t>((rx_data_ >> 1) | (pin(3, 0) ? 0x80 : 0));
  if (--rx_ticks_ == 0) {
    rx_ticks_ = -1;
    sf(sfr::SBUF) = rx_data_;
    raise(sfr::SCON, ri, 4);
  }
}

}  // namespace mcs51

// Watchdog state machine (seed 002): Baud_Search -> Baud_Control -> DP_Control. Baud_Control
// watches the baud rate (WD_Baud_Control_Val x 10 ms), DP_Control the master (TWD = 1 or 10 ms x
// WD_Fact_1 x WD_Fact_2). An error-free telegram to our address retriggers Baud_Control; only
// the locking master's retriggers DP_Control.
#include "core.hpp"

namespace dpc31 {

namespace {}  // namespace

// Baud_Control monitoring time; the VPC3+S manual states a factor 2 that the SPC3 text lacks.
// WD_Baud_Control_Val = 0 switches the monitoring off (modelled).
static std::uint64_t baud_control_cycles(const ChipCore& c) {
  const std::uint64_t val = c.latch[ChipCore::idx(RegId::WD_Baud_Control_Val)];
  if (val == 0) return kNever;
  const std::uint64_t factor = c.prof->id == Profile::vpc3plus ? 2 : 1;
  return c.cycles_for_us(val * factor * 10'000);
}

static void enter_baud_control(ChipCore& c) {
  c.timers.wd = WdState::Baud_Control;
  c.arm(c.timers.watchdog, baud_control_cycles(c));
}

void ChipCore::baud_found(std::uint8_t code) {
  baud_code = code;
  log(LogLevel::info, "baud rate found: {} baud (code {})", kBaudRates[code], code);
  enter_baud_control(*this);
  emit(BlockEvent::Kind::irq, irq::Baudrate_Detect);
  raise(irq::Baudrate_Detect);
}

void ChipCore::watchdog_parameterise(bool wd_on, std::uint8_t f1, std::uint8_t f2, bool base_1ms) {
  timers.dp_wd_on = wd_on;
  timers.dp_wd_cycles = cycles_for_us(std::uint64_t{base_1ms ? 1000u : 10'000u} * f1 * f2);
  if (timers.wd == WdState::Baud_Search) return;
  if (wd_on && mode0(fields::Mode_Reg0::DP_Mode)) {
    timers.wd = WdState::DP_Control;
    arm(timers.watchdog, timers.dp_wd_cycles);
  } else {
    enter_baud_control(*this);  // WD_On = 0: stays in Baud_Control, the DP state is never reset
  }
}

void ChipCore::watchdog_retrigger(std::uint8_t master) {
  if (timers.wd == WdState::DP_Control) {
    // "The 'DP_Control' state serves response time monitoring of the DP master (Master_Add)"
    // (SPC3 p.25): another master's telegrams, answered or refused, do not keep it alive.
    if (master == dp.master_add) arm(timers.watchdog, timers.dp_wd_cycles);
  } else if (timers.wd == WdState::Baud_Control) {
    enter_baud_control(*this);
  }
}

void ChipCore::watchdog_release() {
  timers.dp_wd_on = false;
  if (timers.wd == WdState::DP_Control) enter_baud_control(*this);
}

void ChipCore::watchdog_expired() {
  arm(timers.watchdog, kNever);
  if (timers.wd == WdState::DP_Control) {
    log(LogLevel::info, "DP watchdog expired: WD_DP_Control_Timeout, DP state machine reset");
    enter_baud_control(*this);
    emit(BlockEvent::Kind::irq, irq::WD_DP_Control_Timeout);
    raise(irq::WD_DP_Control_Timeout);
    emit(BlockEvent::Kind::leave_master);
    leave_master();
    timers.dp_wd_on = false;
  } else if (timers.wd == WdState::Baud_Control) {
    log(LogLevel::info, "Baud_Control expired: Baud_Search");
    timers.wd = WdState::Baud_Search;
    mac_start_search();
  }
}

}  // namespace dpc31

namespace dpc31 {

namespace {

template <typename Ar, typename S>
void members(Ar& ar, S& s) {
  static_assert(snap::member_count<Timers>() == 5, "a new member: add it here");
  static_assert(snap::member_count<Timer>() == 2, "a new member: add it here and in IRQC");
  // The order of format version 2 (docs/snapshots.md): both timers' deadlines first, their
  // per-cycle counts last.
  ar(s.user.at);
  ar.bounded(s.wd, WdState::DP_Control);
  ar(s.watchdog.at);
  ar(s.dp_wd_on);
  ar(s.dp_wd_cycles);
  ar(s.user.left);
  ar(s.watchdog.left);
}

}  // namespace

void save_state(snap::Writer& w, const Timers& s) {
  w.section("TIMR");
  members(w, s);
}

void load_state(snap::Reader& r, Timers& s) {
  r.section("TIMR");
  members(r, s);
}

}  // namespace dpc31

// Watchdog state machine (seed 002): Baud_Search -> Baud_Control -> DP_Control. An error-free
// telegram to our address retriggers Baud_Control; only the locking master's retriggers
// DP_Control.
#include "watchdog.hpp"

#include "dpc31/uart.hpp"

namespace dpc31 {

void Watchdog::reset() {
  const std::uint8_t code = s_.baud_code;
  s_ = State{};
  s_.baud_code = code;
}

void Watchdog::power_on() { s_ = State{}; }

// Baud_Control monitoring time; the VPC3+S manual states a factor 2 that the SPC3 text lacks.
// WD_Baud_Control_Val = 0 switches the monitoring off (modelled).
void Watchdog::enter_baud_control() {
  s_.wd = WdState::Baud_Control;
  const std::uint64_t val = regs_.latch(RegId::WD_Baud_Control_Val);
  const std::uint64_t factor = regs_.id() == Profile::vpc3plus ? 2 : 1;
  clock_.arm(s_.timer, val == 0 ? kNever : clock_.cycles_for_us(val * factor * 10'000));
}

void Watchdog::baud_found(std::uint8_t code) {
  s_.baud_code = code;
  sig_.log(LogLevel::info, "baud rate found: {} baud (code {})", kBaudRates[code], code);
  enter_monitoring();
  sig_.emit(BlockEvent::Kind::irq, irq::Baudrate_Detect);
  irq_.raise(irq::Baudrate_Detect);
}

void Watchdog::parameterise(bool wd_on, std::uint8_t f1, std::uint8_t f2, bool base_1ms) {
  s_.dp_wd_on = wd_on;
  s_.dp_wd_cycles = clock_.cycles_for_us(std::uint64_t{base_1ms ? 1000u : 10'000u} * f1 * f2);
  // In Baud_Search the rate found enters the state these parameters ask for (baud_found).
  if (s_.wd != WdState::Baud_Search) enter_monitoring();
}

// Seed 002: "the watchdog is used for the 'DP_Control' state, after a 'Set_Param telegram' was
// received with ... WD_On = 1" (and DP_Mode = 1); otherwise Baud_Control, where the DP state is
// never reset.
void Watchdog::enter_monitoring() {
  if (s_.dp_wd_on && regs_.mode0(fields::Mode_Reg0::DP_Mode)) {
    s_.wd = WdState::DP_Control;
    clock_.arm(s_.timer, s_.dp_wd_cycles);
  } else {
    enter_baud_control();
  }
}

// Parameters accepted in Baud_Search wait for the rate; a Leave_Master before it leaves no master
// for DP_Control to monitor.
void Watchdog::master_left() {
  if (s_.wd == WdState::Baud_Search) s_.dp_wd_on = false;
}

void Watchdog::retrigger(std::uint8_t master, std::uint8_t master_add) {
  if (s_.wd == WdState::DP_Control) {
    // "The 'DP_Control' state serves response time monitoring of the DP master (Master_Add)"
    // (SPC3 p.25): another master's telegrams, answered or refused, do not keep it alive.
    if (master == master_add) clock_.arm(s_.timer, s_.dp_wd_cycles);
  } else if (s_.wd == WdState::Baud_Control) {
    enter_baud_control();
  }
}

void Watchdog::release() {
  s_.dp_wd_on = false;
  if (s_.wd == WdState::DP_Control) enter_baud_control();
}

Watchdog::Expiry Watchdog::expire() {
  clock_.arm(s_.timer, kNever);
  if (s_.wd == WdState::DP_Control) {
    sig_.log(LogLevel::info, "DP watchdog expired: WD_DP_Control_Timeout, DP state machine reset");
    enter_baud_control();
    irq_.raise(irq::WD_DP_Control_Timeout);
    s_.dp_wd_on = false;
    return Expiry::dp_control;
  }
  if (s_.wd == WdState::Baud_Control) {
    sig_.log(LogLevel::info, "Baud_Control expired: Baud_Search");
    s_.wd = WdState::Baud_Search;
    return Expiry::baud_control;
  }
  return Expiry::none;
}

}  // namespace dpc31

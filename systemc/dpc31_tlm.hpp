// The chip as a SystemC TLM-2.0 model for virtual platforms (docs/systemc.md): one dpc31::Chip
// behind a target socket for its parallel bus, X/INT, the interrupt, PB3 and TxD as signals, its
// clock on the SystemC time base. Installed as <dpc31/systemc/dpc31_tlm.hpp>, target
// dpc31emu::systemc (find_package(dpc31emu COMPONENTS systemc)).
#pragma once

#include <tlm_utils/simple_target_socket.h>

#include <cstdint>
#include <deque>
#include <limits>
#include <systemc>
#include <tlm>
#include <utility>

#include "dpc31/bus_port.hpp"
#include "dpc31/chip.hpp"

namespace dpc31::board {
class Hooks;
}

namespace dpc31::systemc {

// The C HAL's selected chip (dpc31_select, a FirmwareHost's call into its firmware) and the board
// hooks are per OS thread, and SystemC's threads share one: an initiator that waits inside a call
// into its firmware sets its own aside for the wait, so another initiator's firmware calls made
// meanwhile neither take nor clear it (docs/systemc.md, "Several chips"). b_transport does so
// around its own waits; a platform's wait inside a firmware call (a quantum keeper's sync()) is
// made while one of these lives.
class KeepSelection {
 public:
  KeepSelection();
  ~KeepSelection();
  KeepSelection(const KeepSelection&) = delete;
  KeepSelection& operator=(const KeepSelection&) = delete;

 private:
  hal::Selection hal_;
  board::Hooks* hooks_;
};

class Dpc31Tlm : public sc_core::sc_module {
 public:
  // The parallel bus: one byte per address, as the chip's bus is 8 bits wide. A transaction of
  // n bytes is n accesses of bus_access_cycles() clocks each, back to back (byte enables and the
  // streaming width honoured); b_transport annotates the exact time to its end. No DMI: every
  // access may be a register or a command cell. Debug transport: peek / poke, no time.
  tlm_utils::simple_target_socket<Dpc31Tlm> bus;
  sc_core::sc_out<bool> x_int;  // the X/INT pin (its polarity: Mode_Reg0.INT_Pol)
  sc_core::sc_out<bool> irq;    // the interrupt is active (independent of the polarity)
  sc_core::sc_out<bool> pb3;    // dpc31 port PB3 (low on the other profiles)
  sc_core::sc_out<bool> txd;    // the serial output, each edge at its cycle's time
  // The serial input for a UART model (optional): its value at time 0 and each change drive RxD at
  // the first clock at or after their time (a low start is warned of: PROFIBUS idles high), or at
  // the chip's cycle where a bus access took it past that time (docs/systemc.md: not exact beside
  // bus traffic; drive_rxd_chars ahead of time is).
  // Unbound: drive it through chip().drive_rxd / drive_rxd_chars.
  sc_core::sc_port<sc_core::sc_signal_in_if<bool>, 1, sc_core::SC_ZERO_OR_MORE_BOUND> rxd;

  SC_HAS_PROCESS(Dpc31Tlm);
  // A time resolution coarser than one clock of the chip is std::invalid_argument: two cycles
  // would share a time, and the chip's timing would move.
  Dpc31Tlm(const sc_core::sc_module_name& name, const ChipOptions& options);

  // The chip: its serial input (drive_rxd, drive_rxd_chars) and what a testbench looks at. Use
  // it from SystemC processes only; time moves through the model, not through Chip::step. The
  // model watches its Chip::on_cycle (one watcher): a platform does not set another.
  Chip& chip() { return chip_; }
  // The time base: cycle c is at ceil(c / clock_hz) seconds on the SystemC time line (the time
  // resolution decides the rounding); cycle_at is its inverse. The time line ends at
  // sc_max_time(): a cycle after last_cycle() has no time (time_of: std::out_of_range).
  [[nodiscard]] sc_core::sc_time time_of(std::uint64_t cycle) const;
  [[nodiscard]] std::uint64_t cycle_at(const sc_core::sc_time& t) const;
  // The last cycle with a time: Chip::kLastCycle, or cycle_at(sc_max_time()) where that is sooner
  // (885 443 715 538 058 at 48 MHz and 1 ps, about 213 days).
  [[nodiscard]] std::uint64_t last_cycle() const;
  // Notified when the irq signal rises, at that cycle's time (the delta after the signal's
  // update: a waiter reads it true); an activation and an end applied at one time notify nothing.
  [[nodiscard]] const sc_core::sc_event& irq_rise() const { return irq_rise_; }
  // For a process that moves time through the chip's serial side (the built-in DP master's
  // DpMaster::scheduler): waits until the chip reached `cycle` or one of its steps stopped
  // (Chip::request_stop, wake_on_txd); a cycle after last_cycle() waits until last_cycle(), where
  // the time line ends (a "no limit" wait returns there). Accesses that would start at or after
  // `cycle` wait until this process has acted, as the host CPU of the native run gives the bus side
  // its turn; so does an access while a step stopped it, and none waits for a stop with no
  // process here.
  void run_until(std::uint64_t cycle);
  // RxD edges were driven ahead of time: the chip's next event may be sooner.
  void rxd_driven() { changed_.notify(sc_core::SC_ZERO_TIME); }

  // Accesses through the socket, and how many of them had to wait for the rest of the platform
  // (temporal decoupling: the others ran ahead of SystemC time).
  [[nodiscard]] std::uint64_t accesses() const { return accesses_; }
  [[nodiscard]] std::uint64_t syncs() const { return syncs_; }

 private:
  void b_transport(tlm::tlm_generic_payload& tr, sc_core::sc_time& delay);
  unsigned int transport_dbg(tlm::tlm_generic_payload& tr);
  bool get_direct_mem_ptr(tlm::tlm_generic_payload& tr, tlm::tlm_dmi& dmi);
  void run();          // SC_THREAD: the chip's own events at their times
  void watch_rxd();    // SC_THREAD: the rxd port\'s changes onto the chip\'s RxD
  void apply_edges();  // SC_METHOD: scheduled pin changes onto the ports
  // X/INT follows the interrupt and Mode_Reg0.INT_Pol: a polarity write, a reset or a load_state
  // flips the pin without a change of the interrupt (no on_irq_change), so the pin is compared
  // wherever the chip may have moved (Chip::on_cycle) and after a debug write.
  void follow_x_int(std::uint64_t cycle);
  // A reset or load_state took the chip back to `cycle`: the pins' changes queued after now are
  // dropped and the pins follow the chip's; a warning where an initiator had run ahead past now.
  void went_back(std::uint64_t cycle);
  void step_to(std::uint64_t cycle);  // never past `cycle`, never backwards
  void schedule(std::uint64_t cycle, int pin, bool level);

  Chip chip_;
  std::uint64_t ticks_per_second_;
  // The pins' changes as the chip reports them, applied at their times (a bus access may take the
  // chip ahead of SystemC time: its effects wait for their time).
  struct Edge {
    sc_core::sc_time at;
    int pin;
    bool level;
  };
  std::deque<Edge> edges_;
  bool x_int_level_;        // the X/INT level last scheduled
  std::uint64_t seen_ = 0;  // the chip's cycle after its last move (Chip::on_cycle)
  sc_core::sc_event edge_due_;
  sc_core::sc_event irq_rise_;
  sc_core::sc_event changed_;  // an access or RxD moved the chip's next event
  sc_core::sc_event stopped_;  // a step stopped (a waiting run_until may go on)
  sc_core::sc_event scheduler_moved_;
  // The cycle the process in run_until waits for (max: none waits).
  std::uint64_t horizon_ = std::numeric_limits<std::uint64_t>::max();
  std::uint64_t accesses_ = 0;
  std::uint64_t syncs_ = 0;
};

}  // namespace dpc31::systemc

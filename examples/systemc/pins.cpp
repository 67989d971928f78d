// The model's pin signals against the chip's pins (docs/systemc.md, "X/INT, the interrupt, PB3,
// TxD"), in three runs: `dpc31_sc_pins polarity` (CTest SystemC.pins), `dpc31_sc_pins reset`
// (CTest SystemC.reset) and `dpc31_sc_pins polarity_jump` (CTest SystemC.polarity_jump); and
// another process acting on the chip while an initiator uses the bus ("Time and temporal
// decoupling"), `dpc31_sc_pins stop` (CTest SystemC.stop_without_waiter) and `dpc31_sc_pins
// reset_ahead` (CTest SystemC.reset_ahead), each ended by a limit of 10 ms so that a hang is a
// failure. Exit 0 when every check holds; each one that does not is a line on stderr. The first
// two use an SPC3 whose initiator unmasks User_Timer_Clock alone and starts the chip.
//
// Expected cycles (docs/timing.md, "Bus accesses": an access starting at t completes at t + 4;
// "Interrupt line": polarity INT_Pol = 0 low-active, 1 high-active, and a hardware reset clears
// Int_Req_Reg; "Timers": the first User_Timer_Clock at s + 48 000 after Start_SPC3 completes at
// s):
// - polarity: X/INT made high-active (Mode_Reg0.INT_Pol = 1, written while Offline). Int_Mask_Reg
//   lo, hi 4, 8; Mode_Reg0 lo (INT_Pol = 1) 12: X/INT, inactive, goes from high to low;
//   Start_SPC3 16; User_Timer_Clock 48 016: the interrupt and X/INT go high; its acknowledge
//   (Int_Ack_Reg lo) starts there and completes at 48 020: both go low. A process woken by
//   irq_rise() reads the irq signal true (it read false until the next delta).
// - reset (docs/systemc.md, "A reset"): Int_Mask_Reg lo, hi 4, 8; Start_SPC3 12; User_Timer_Clock
//   48 012: irq high, X/INT (low-active) low; chip().reset() there: irq low, X/INT high at
//   48 012. The same three writes again start at 48 012 (the reset chip brought to SystemC time,
//   its clock counting on): 48 016, 48 020, Start_SPC3 48 024, User_Timer_Clock 96 024.
// - polarity_jump: no interrupt at all, only INT_Pol moves X/INT. Mode_Reg0 lo (INT_Pol = 1)
//   completes at 4: X/INT (inactive) goes low; a snapshot there; chip().reset() at 1000 takes
//   Mode_Reg0 back to 0 (low-active): high at 1000; load_state of the snapshot at 2000 (INT_Pol 1
//   again, its cycle 4 in the past: written at once): low at 2000.
// - stop (CTest SystemC.stop_without_waiter): another process calls chip().request_stop() at 1 us
//   while no process waits in run_until. The initiator's write at 0 completes at 4 (docs/timing.md,
//   "Bus accesses": an access starting at t completes at t + 4), time_of(4) = 83 334 ps; it waits
//   2 us more, to 2 083 334 ps: its next write starts at the first clock at or after that time,
//   cycle 100 (time_of(100) = ceil(100 / 48 MHz) = 2 083 334 ps), and completes at 104, at
//   time_of(104) = 2 166 667 ps. The stop stays requested (nobody's to clear).
// - reset_ahead (CTest SystemC.reset_ahead): the initiator runs 10 us ahead (a quantum keeper's
//   local time): Int_Mask_Reg lo, hi (every interrupt unmasked) and Start_SPC3 start at cycle 480
//   (10 us x 48 MHz) and complete at 484, 488, 492, the interrupt active at 492 and its edge
//   queued for time_of(492) = 10.25 us; another process resets the chip at 1 us. The reset takes
//   those accesses back (the chip is not started at 10.25 us; a write there completes at 496, the
//   chip's cycle SystemC time in clocks, docs/systemc.md "A reset"), the model warns once
//   (/dpc31/Dpc31Tlm/reset), and the irq signal never rises: irq_rise() is never notified (it was,
//   at 10.25 us, with irq reading 0).
#include <tlm_utils/simple_initiator_socket.h>

#include <cstdint>
#include <cstdio>
#include <string>
#include <systemc>
#include <tlm>
#include <utility>
#include <vector>

#include "dpc31/dpc31_regs.h"
#include "dpc31_tlm.hpp"

namespace {

dpc31::ChipOptions spc3() {
  dpc31::ChipOptions o;
  o.profile = dpc31::Profile::spc3;
  return o;
}

using Edges = std::vector<std::pair<std::uint64_t, bool>>;  // (cycle, level)

std::string text(const Edges& edges) {
  std::string s;
  for (const auto& [cycle, level] : edges) {
    s.append(" ").append(std::to_string(cycle)).append(level ? ":1" : ":0");
  }
  return s.empty() ? " none" : s;
}

struct Bench : sc_core::sc_module {
  tlm_utils::simple_initiator_socket<sc_core::sc_module> cpu{"cpu"};
  dpc31::systemc::Dpc31Tlm chip{"spc3", spc3()};
  sc_core::sc_signal<bool> x_int{"x_int"}, irq{"irq"}, pb3{"pb3"}, txd{"txd"};
  Edges x_int_edges, irq_edges;
  int failures = 0;
  int rises = 0;
  bool done = false;
  const std::string run;

  SC_HAS_PROCESS(Bench);
  Bench(const sc_core::sc_module_name& n, std::string which) : sc_module(n), run(std::move(which)) {
    cpu.bind(chip.bus);
    chip.x_int(x_int);
    chip.irq(irq);
    chip.pb3(pb3);
    chip.txd(txd);
    SC_THREAD(initiator);
    SC_THREAD(other);
    SC_THREAD(watch_rise);
    SC_METHOD(watch_x_int);
    sensitive << x_int;
    dont_initialize();
    SC_METHOD(watch_irq);
    sensitive << irq;
    dont_initialize();
  }

  // The initial values are written at time 0: the edges that follow are the ones looked at.
  void note(Edges& edges, bool level) {
    if (sc_core::sc_time_stamp() == sc_core::SC_ZERO_TIME) return;
    edges.emplace_back(chip.cycle_at(sc_core::sc_time_stamp()), level);
  }
  void watch_x_int() { note(x_int_edges, x_int.read()); }
  void watch_irq() { note(irq_edges, irq.read()); }
  void watch_rise() {
    for (;;) {
      wait(chip.irq_rise());
      ++rises;
    }
  }

  void expect(bool ok, const std::string& what) {
    if (ok) return;
    std::fprintf(stderr, "pins: %s\n", what.c_str());
    ++failures;
  }

  // A write of one byte, running ahead of SystemC time (the delay annotated to its end).
  void write(std::uint32_t addr, unsigned char value, sc_core::sc_time& delay) {
    tlm::tlm_generic_payload tr;
    tr.set_command(tlm::TLM_WRITE_COMMAND);
    tr.set_address(addr);
    tr.set_data_ptr(&value);
    tr.set_data_length(1);
    tr.set_streaming_width(1);
    tr.set_response_status(tlm::TLM_INCOMPLETE_RESPONSE);
    cpu->b_transport(tr, delay);
    expect(tr.is_response_ok(), "a write is refused");
  }

  void initiator() {
    if (run == "reset") {
      run_reset();
    } else if (run == "polarity_jump") {
      run_polarity_jump();
    } else if (run == "stop") {
      run_stop();
    } else if (run == "reset_ahead") {
      run_reset_ahead();
    } else {
      run_polarity();
    }
    done = true;
    sc_core::sc_stop();
  }

  // Another process: a stop request or a reset at 1 us.
  void other() {
    if (run != "stop" && run != "reset_ahead") return;
    wait(1, sc_core::SC_US);
    if (run == "stop") {
      chip.chip().request_stop();
    } else {
      chip.chip().reset();
    }
  }

  // User_Timer_Clock alone unmasked, Start_SPC3, each write waited for: the chip's cycle when
  // the Start completed.
  std::uint64_t start() {
    sc_core::sc_time delay = sc_core::SC_ZERO_TIME;
    for (const auto& [addr, value] :
         {std::pair<std::uint32_t, unsigned>{SPC3_Int_Mask_Reg_LO_INTEL,
                                             ~SPC3_Int_Req_Reg_User_Timer_Clock_Msk & 0xFFu},
          {SPC3_Int_Mask_Reg_HI_INTEL, 0xFFu},
          {SPC3_Mode_Reg1_S, SPC3_Mode_Reg1_S_Start_SPC3_Msk}}) {
      write(addr, static_cast<unsigned char>(value), delay);
      wait(delay);
      delay = sc_core::SC_ZERO_TIME;
    }
    return chip.chip().cycle();
  }

  void run_reset() {
    expect(start() == 12, "the first Start_SPC3 completes at " +
                              std::to_string(chip.chip().cycle()) + ", expected 12");
    wait(chip.irq_rise());
    expect(sc_core::sc_time_stamp() == chip.time_of(48012),
           "the first User_Timer_Clock at " + sc_core::sc_time_stamp().to_string() +
               ", expected time_of(48012)");
    chip.chip().reset();
    wait(sc_core::SC_ZERO_TIME);
    wait(sc_core::SC_ZERO_TIME);
    expect(!irq.read() && x_int.read(), "after the reset irq reads " + std::to_string(irq.read()) +
                                            " and x_int " + std::to_string(x_int.read()) +
                                            ", expected 0 and 1");
    const std::uint64_t s = start();
    expect(s == 48024, "the Start after the reset completes at chip cycle " + std::to_string(s) +
                           ", expected 48024 (SystemC time in clocks)");
    wait(chip.irq_rise());
    expect(sc_core::sc_time_stamp() == chip.time_of(96024) && chip.chip().cycle() == 96024,
           "the User_Timer_Clock after the reset at " + sc_core::sc_time_stamp().to_string() +
               ", chip cycle " + std::to_string(chip.chip().cycle()) +
               ", expected time_of(96024), cycle 96024");
    const Edges irq_want{{48012, true}, {48012, false}, {96024, true}};
    expect(irq_edges == irq_want,
           "irq edges (cycle:level)" + text(irq_edges) + ", expected" + text(irq_want));
    const Edges x_int_want{{48012, false}, {48012, true}, {96024, false}};
    expect(x_int_edges == x_int_want,
           "x_int edges (cycle:level)" + text(x_int_edges) + ", expected" + text(x_int_want));
  }

  void run_polarity_jump() {
    sc_core::sc_time delay = sc_core::SC_ZERO_TIME;
    write(SPC3_Mode_Reg0_LO_INTEL, SPC3_Mode_Reg0_INT_Pol_Msk, delay);
    wait(delay);
    const std::vector<std::uint8_t> snapshot = chip.chip().save_state();
    wait(chip.time_of(1000) - sc_core::sc_time_stamp());
    chip.chip().reset();
    wait(chip.time_of(2000) - sc_core::sc_time_stamp());
    chip.chip().load_state(snapshot);
    wait(sc_core::SC_ZERO_TIME);
    wait(sc_core::SC_ZERO_TIME);
    expect(irq_edges.empty(), "irq edges (cycle:level)" + text(irq_edges) + ", expected none");
    const Edges want{{4, false}, {1000, true}, {2000, false}};
    expect(x_int_edges == want,
           "x_int edges (cycle:level)" + text(x_int_edges) + ", expected" + text(want));
    expect(x_int.read() == chip.chip().x_int_pin(), "x_int differs from the chip's X/INT pin");
  }

  void run_stop() {
    const std::uint32_t ram = chip.chip().profile().user_base;
    sc_core::sc_time delay = sc_core::SC_ZERO_TIME;
    write(ram, 0x11, delay);
    wait(delay);
    expect(sc_core::sc_time_stamp() == sc_core::sc_time::from_value(83'334),
           "the first write ends at " + sc_core::sc_time_stamp().to_string());
    wait(2, sc_core::SC_US);
    delay = sc_core::SC_ZERO_TIME;
    write(ram, 0x22, delay);
    wait(delay);
    expect(chip.chip().cycle() == 104 &&
               sc_core::sc_time_stamp() == sc_core::sc_time::from_value(2'166'667),
           "the write after the stop request ends at chip cycle " +
               std::to_string(chip.chip().cycle()) + ", " + sc_core::sc_time_stamp().to_string() +
               ", expected 104, 2166667 ps");
    expect(chip.chip().stop_requested(), "the stop request was cleared");
  }

  void run_reset_ahead() {
    sc_core::sc_time delay(10, sc_core::SC_US);
    write(SPC3_Int_Mask_Reg_LO_INTEL, 0x00, delay);
    write(SPC3_Int_Mask_Reg_HI_INTEL, 0x00, delay);
    write(SPC3_Mode_Reg1_S, SPC3_Mode_Reg1_S_Start_SPC3_Msk, delay);
    expect(chip.chip().cycle() == 492 && chip.chip().irq_active(),
           "ahead: chip cycle " + std::to_string(chip.chip().cycle()) + ", interrupt " +
               std::to_string(chip.chip().irq_active()) + ", expected 492 and active");
    wait(delay);
    wait(sc_core::SC_ZERO_TIME);
    wait(sc_core::SC_ZERO_TIME);
    expect(sc_core::sc_time_stamp() == chip.time_of(492),
           "synchronised at " + sc_core::sc_time_stamp().to_string() + ", expected time_of(492)");
    expect(!chip.chip().started() && !chip.chip().irq_active(),
           "after the reset: started " + std::to_string(chip.chip().started()) + ", interrupt " +
               std::to_string(chip.chip().irq_active()) + ", expected 0, 0");
    // The reset chip counts on from SystemC time: a write now starts at 492, completes at 496.
    delay = sc_core::SC_ZERO_TIME;
    write(chip.chip().profile().user_base, 0x11, delay);
    expect(chip.chip().cycle() == 496, "a write after the reset completes at chip cycle " +
                                           std::to_string(chip.chip().cycle()) + ", expected 496");
    expect(rises == 0 && irq_edges.empty() && !irq.read(),
           "irq_rise notified " + std::to_string(rises) + " times, the irq signal changed " +
               std::to_string(irq_edges.size()) + " times, expected none");
    const auto warned = sc_core::sc_report_handler::get_count("/dpc31/Dpc31Tlm/reset");
    expect(warned == 1, "the reset warned " + std::to_string(warned) + " times, expected once");
  }
  void run_polarity() {
    wait(sc_core::SC_ZERO_TIME);
    expect(x_int.read(), "X/INT is not high at reset (low-active, inactive)");
    sc_core::sc_time delay = sc_core::SC_ZERO_TIME;
    write(SPC3_Int_Mask_Reg_LO_INTEL,
          static_cast<unsigned char>(~SPC3_Int_Req_Reg_User_Timer_Clock_Msk), delay);
    write(SPC3_Int_Mask_Reg_HI_INTEL, 0xFF, delay);
    write(SPC3_Mode_Reg0_LO_INTEL, SPC3_Mode_Reg0_INT_Pol_Msk, delay);
    write(SPC3_Mode_Reg1_S, SPC3_Mode_Reg1_S_Start_SPC3_Msk, delay);
    wait(delay);
    delay = sc_core::SC_ZERO_TIME;
    wait(chip.irq_rise());
    expect(irq.read(), "irq reads false right after irq_rise()");
    write(SPC3_Int_Ack_Reg_LO_INTEL, SPC3_Int_Req_Reg_User_Timer_Clock_Msk, delay);
    wait(delay);
    wait(sc_core::SC_ZERO_TIME);
    const Edges want{{12, false}, {48016, true}, {48020, false}};
    expect(x_int_edges == want,
           "x_int edges (cycle:level)" + text(x_int_edges) + ", expected" + text(want));
    expect(x_int.read() == chip.chip().x_int_pin(), "x_int differs from the chip's X/INT pin");
  }
};

}  // namespace

int sc_main(int argc, char* argv[]) {
  const std::string run = argc == 2 ? argv[1] : "";
  if (run != "polarity" && run != "reset" && run != "polarity_jump" && run != "stop" &&
      run != "reset_ahead") {
    std::fprintf(stderr, "pins: usage: pins polarity|reset|polarity_jump|stop|reset_ahead\n");
    return 2;
  }
  sc_core::sc_report_handler::set_actions("/OSCI/SystemC", sc_core::SC_INFO,
                                          sc_core::SC_DO_NOTHING);
  Bench bench{"bench", run};
  sc_core::sc_start(sc_core::sc_time(10, sc_core::SC_MS));  // a hang ends here
  if (!bench.done) {
    std::fprintf(stderr, "pins: %s: the initiator did not finish within 10 ms\n", run.c_str());
    return 1;
  }
  return bench.failures == 0 ? 0 : 1;
}

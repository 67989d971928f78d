// Other processes acting on the chip while an initiator uses the bus (docs/systemc.md, "Time and
// temporal decoupling", "A reset"), in two runs on an SPC3, each ended by its own limit so that a
// hang is a failure, not a wait: exit 0 when every check holds, each one that does not a line on
// stderr.
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

#include "dpc31/dpc31_regs.h"
#include "dpc31_tlm.hpp"

namespace {

dpc31::ChipOptions spc3() {
  dpc31::ChipOptions o;
  o.profile = dpc31::Profile::spc3;
  return o;
}

struct Bench : sc_core::sc_module {
  tlm_utils::simple_initiator_socket<sc_core::sc_module> cpu{"cpu"};
  dpc31::systemc::Dpc31Tlm chip{"spc3", spc3()};
  sc_core::sc_signal<bool> x_int{"x_int"}, irq{"irq"}, pb3{"pb3"}, txd{"txd"};
  const std::string run;
  int failures = 0;
  bool done = false;
  int rises = 0;
  int irq_changes = 0;

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
    SC_METHOD(watch_irq);
    sensitive << irq;
    dont_initialize();
  }

  void expect(bool ok, const std::string& what) {
    if (ok) return;
    std::fprintf(stderr, "decoupling: %s\n", what.c_str());
    ++failures;
  }

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
    if (run == "stop") {
      run_stop();
    } else {
      run_reset_ahead();
    }
    done = true;
    sc_core::sc_stop();
  }

  // The other process: a stop request or a reset at 1 us.
  void other() {
    wait(1, sc_core::SC_US);
    if (run == "stop") {
      chip.chip().request_stop();
    } else {
      chip.chip().reset();
    }
  }

  void watch_rise() {
    for (;;) {
      wait(chip.irq_rise());
      ++rises;
    }
  }
  void watch_irq() { ++irq_changes; }

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
    expect(rises == 0 && irq_changes == 0 && !irq.read(),
           "irq_rise notified " + std::to_string(rises) + " times, the irq signal changed " +
               std::to_string(irq_changes) + " times, expected none");
    const auto warned = sc_core::sc_report_handler::get_count("/dpc31/Dpc31Tlm/reset");
    expect(warned == 1, "the reset warned " + std::to_string(warned) + " times, expected once");
  }
};

}  // namespace

int sc_main(int argc, char* argv[]) {
  const std::string run = argc == 2 ? argv[1] : "";
  if (run != "stop" && run != "reset_ahead") {
    std::fprintf(stderr, "decoupling: usage: decoupling stop|reset_ahead\n");
    return 2;
  }
  sc_core::sc_report_handler::set_actions("/OSCI/SystemC", sc_core::SC_INFO,
                                          sc_core::SC_DO_NOTHING);
  Bench bench{"bench", run};
  sc_core::sc_start(sc_core::sc_time(1, sc_core::SC_MS));  // a hang ends here
  if (!bench.done) {
    std::fprintf(stderr, "decoupling: %s: the initiator did not finish within 1 ms\n", run.c_str());
    return 1;
  }
  return bench.failures == 0 ? 0 : 1;
}

// A hardware reset in a platform (docs/systemc.md, "A reset"): an SPC3 with User_Timer_Clock
// alone unmasked, started; when its interrupt becomes active an SC_THREAD calls chip().reset().
// The reset is an event at that time: the irq and x_int signals show its end of the interrupt
// there, and the chip's clock counts on (its cycle is SystemC time in clocks, not clocks since
// the reset). Exit 0 when every check holds; each one that does not is a line on stderr.
//
// Expected cycles (docs/timing.md, "Bus accesses": an access starting at t completes at t + 4;
// "Timers": the first User_Timer_Clock at s + 48 000 after Start_SPC3 completes at s; "Interrupt
// line": low-active by default, and a hardware reset clears Int_Req_Reg):
//   Int_Mask_Reg lo, hi 4, 8; Start_SPC3 12; User_Timer_Clock 48 012: irq high, x_int low; the
//   reset there: irq low, x_int high at 48 012. The same three writes again start at 48 012 (the
//   reset chip brought to SystemC time): 48 016, 48 020, Start_SPC3 48 024, User_Timer_Clock
//   96 024.
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
    s += " " + std::to_string(cycle) + ":" + (level ? "1" : "0");
  }
  return s.empty() ? " none" : s;
}

struct Bench : sc_core::sc_module {
  tlm_utils::simple_initiator_socket<sc_core::sc_module> cpu{"cpu"};
  dpc31::systemc::Dpc31Tlm chip{"spc3", spc3()};
  sc_core::sc_signal<bool> x_int{"x_int"}, irq{"irq"}, pb3{"pb3"}, txd{"txd"};
  Edges x_int_edges, irq_edges;
  int failures = 0;

  SC_HAS_PROCESS(Bench);
  explicit Bench(const sc_core::sc_module_name& n) : sc_module(n) {
    cpu.bind(chip.bus);
    chip.x_int(x_int);
    chip.irq(irq);
    chip.pb3(pb3);
    chip.txd(txd);
    SC_THREAD(initiator);
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

  void expect(bool ok, const std::string& what) {
    if (ok) return;
    std::fprintf(stderr, "reset: %s\n", what.c_str());
    ++failures;
  }

  // A write of one byte, then SystemC time to its end.
  void write(std::uint32_t addr, unsigned char value) {
    tlm::tlm_generic_payload tr;
    tr.set_command(tlm::TLM_WRITE_COMMAND);
    tr.set_address(addr);
    tr.set_data_ptr(&value);
    tr.set_data_length(1);
    tr.set_streaming_width(1);
    tr.set_response_status(tlm::TLM_INCOMPLETE_RESPONSE);
    sc_core::sc_time delay = sc_core::SC_ZERO_TIME;
    cpu->b_transport(tr, delay);
    expect(tr.is_response_ok(), "a write is refused");
    wait(delay);
  }

  // User_Timer_Clock alone unmasked, Start_SPC3: the chip's cycle when the Start completed.
  std::uint64_t start() {
    write(SPC3_Int_Mask_Reg_LO_INTEL,
          static_cast<unsigned char>(~SPC3_Int_Req_Reg_User_Timer_Clock_Msk));
    write(SPC3_Int_Mask_Reg_HI_INTEL, 0xFF);
    write(SPC3_Mode_Reg1_S, SPC3_Mode_Reg1_S_Start_SPC3_Msk);
    return chip.chip().cycle();
  }

  void initiator() {
    expect(start() == 12, "the first Start_SPC3 completes at " +
                              std::to_string(chip.chip().cycle()) + ", expected 12");
    wait(chip.irq_rise());
    expect(sc_core::sc_time_stamp() == chip.time_of(48012),
           "the first User_Timer_Clock at " + sc_core::sc_time_stamp().to_string() +
               ", expected time_of(48012)");
    chip.chip().reset();
    wait(sc_core::SC_ZERO_TIME);
    wait(sc_core::SC_ZERO_TIME);
    expect(!irq.read() && x_int.read(), "after the reset irq reads " +
                                            std::to_string(irq.read()) + " and x_int " +
                                            std::to_string(x_int.read()) + ", expected 0 and 1");
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
    sc_core::sc_stop();
  }
};

}  // namespace

int sc_main(int, char*[]) {
  sc_core::sc_report_handler::set_actions("/OSCI/SystemC", sc_core::SC_INFO,
                                          sc_core::SC_DO_NOTHING);
  Bench bench{"bench"};
  sc_core::sc_start();
  return bench.failures == 0 ? 0 : 1;
}

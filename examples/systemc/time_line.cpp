// Where the model meets the edges of SystemC's time line (docs/systemc.md, "the clock"):
//   far     SystemC's 64-bit time ends at sc_max_time(), 2^64 - 1 ticks of 1 ps: the last cycle
//           at 48 MHz is floor((2^64 - 1) * 48e6 / 1e12) = 885 443 715 538 058. A cycle after it
//           has no time (time_of: std::out_of_range, it wrapped round), and the built-in master's
//           "no limit" idle returns there (it waited for a wrapped time for ever).
//   coarse  a time resolution of 100 ns is coarser than a 48 MHz clock (20.83 ns): refused when
//           the model is built (three writes ended at cycle 14, not 12).
//   rxd_low an rxd signal declared without a value starts low: the chip's RxD follows it at
//           cycle 0 with one warning (the first start bit was lost without a word).
// Exit 0 when every check holds; each one that does not is a line on stderr.
#include <tlm_utils/simple_initiator_socket.h>

#include <cstdint>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <systemc>
#include <utility>
#include <vector>

#include "dp_master.hpp"
#include "dpc31_tlm.hpp"

namespace {

int failures = 0;

void expect(bool ok, const std::string& what) {
  if (ok) return;
  std::fprintf(stderr, "time_line: %s\n", what.c_str());
  ++failures;
}

// `f()` throws an E with exactly `message`.
template <typename E, typename F>
void expect_throw(const std::string& what, F f, const std::string& message) {
  try {
    f();
    expect(false, what + ": nothing thrown");
  } catch (const E& e) {
    expect(e.what() == message, what + ": " + e.what());
  }
}

constexpr std::uint64_t kLast = 885'443'715'538'058;  // floor((2^64 - 1) * 48e6 / 1e12)

// The model with its socket and pins bound (rxd is left to the bench).
struct Platform : sc_core::sc_module {
  tlm_utils::simple_initiator_socket<sc_core::sc_module> cpu{"cpu"};
  dpc31::systemc::Dpc31Tlm chip{"dpc31", dpc31::ChipOptions{}};
  sc_core::sc_signal<bool> x_int{"x_int"}, irq{"irq"}, pb3{"pb3"}, txd{"txd"};

  explicit Platform(const sc_core::sc_module_name& n) : sc_module(n) {
    cpu.bind(chip.bus);
    chip.x_int(x_int);
    chip.irq(irq);
    chip.pb3(pb3);
    chip.txd(txd);
  }
};

struct Far : Platform {
  SC_HAS_PROCESS(Far);
  explicit Far(const sc_core::sc_module_name& n) : Platform(n) { SC_THREAD(master); }

  void master() {
    expect(chip.last_cycle() == kLast, "last_cycle " + std::to_string(chip.last_cycle()));
    // ceil(kLast * 1e12 / 48e6) ps = 18 446 744 073 709 541 667 ps: on the line.
    expect(chip.time_of(kLast).value() == 18'446'744'073'709'541'667ULL, "time_of(last)");
    expect_throw<std::out_of_range>(
        "time_of(last + 1)", [this] { (void)chip.time_of(kLast + 1); },
        "Dpc31Tlm::time_of: cycle 885443715538059 is beyond SystemC's time line (its last cycle "
        "is 885443715538058)");
    dpc31::SlaveConfig slave;
    slave.address = 5;
    dpc31::DpMaster m(chip.chip(), {}, slave);
    m.scheduler = [this](std::uint64_t c) { chip.run_until(c); };
    m.idle(std::numeric_limits<std::uint64_t>::max());
    expect(chip.chip().cycle() == kLast, "idle ended at " + std::to_string(chip.chip().cycle()));
    expect(sc_core::sc_time_stamp() == chip.time_of(kLast), "idle ended at another time");
    sc_core::sc_stop();
  }
};

void coarse() {
  sc_core::sc_set_time_resolution(100, sc_core::SC_NS);
  expect_throw<std::invalid_argument>(
      "a resolution of 100 ns",
      [] {
        dpc31::systemc::Dpc31Tlm{"dpc31", dpc31::ChipOptions{}};
      },
      "Dpc31Tlm: the time resolution 100 ns is coarser than one clock of the chip at 48000000 Hz: "
      "set sc_set_time_resolution to one clock or finer");
}

std::vector<std::string> warnings;

// The model's warnings kept; SystemC's own (its banner's kind) go on as they would.
void keep_warning(const sc_core::sc_report& r, const sc_core::sc_actions& actions) {
  if (std::string(r.get_msg_type()).rfind("/dpc31/", 0) != 0) {
    sc_core::sc_report_handler::default_handler(r, actions);
    return;
  }
  warnings.push_back(std::string(r.get_msg_type()) + ": " + r.get_msg());
}

struct RxdLow : Platform {
  sc_core::sc_signal<bool> rxd{"rxd"};  // as docs/systemc.md's snippet had it: no value, low
  std::vector<std::pair<std::uint64_t, bool>> edges;

  explicit RxdLow(const sc_core::sc_module_name& n) : Platform(n) {
    chip.rxd(rxd);
    chip.chip().on_rxd([this](std::uint64_t c, bool level) { edges.emplace_back(c, level); });
  }
};

void rxd_low() {
  sc_core::sc_report_handler::set_handler(keep_warning);
  RxdLow b("bench");
  sc_core::sc_start(sc_core::sc_time(1, sc_core::SC_US));
  expect(warnings == std::vector<std::string>{"/dpc31/Dpc31Tlm/rxd: rxd is low at time 0: the "
                                              "chip's RxD is held low until it rises (a PROFIBUS "
                                              "line idles high: initialise the signal to true)"},
         std::to_string(warnings.size()) + " warnings" +
             (warnings.empty() ? std::string() : ", the first: " + warnings.front()));
  expect(b.edges == std::vector<std::pair<std::uint64_t, bool>>{{0, false}},
         std::to_string(b.edges.size()) + " RxD edges");
}

}  // namespace

int sc_main(int argc, char* argv[]) {
  const std::string mode = argc == 2 ? argv[1] : "";
  // SystemC's "Simulation stopped by user." after sc_stop: not a result.
  sc_core::sc_report_handler::set_actions("/OSCI/SystemC", sc_core::SC_INFO,
                                          sc_core::SC_DO_NOTHING);
  if (mode == "far") {
    Far f("far");
    sc_core::sc_start();
  } else if (mode == "coarse") {
    coarse();
  } else if (mode == "rxd_low") {
    rxd_low();
  } else {
    std::fprintf(stderr, "time_line: usage: time_line far|coarse|rxd_low\n");
    return 2;
  }
  return failures == 0 ? 0 : 1;
}

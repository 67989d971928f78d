// The model's serial pins as signals (docs/systemc.md): a UART thread puts an FDL_Status request
// on the rxd signal, edge by edge at 12 Mbaud, to a started SPC3; the chip's answer appears on
// the txd signal. Expected (docs/timing.md, "Telegrams"): the answer's first start bit at the end
// of the request's last stop bit + 11 bit times, T = 4 clocks at 12 Mbaud and 48 MHz, the first
// rate of the baud search. Exit 0 when it is there, at that time.
#include <tlm_utils/simple_initiator_socket.h>

#include <cstdio>
#include <systemc>
#include <tlm>
#include <vector>

#include "dpc31/fdl.hpp"
#include "dpc31/uart.hpp"
#include "dpc31_tlm.hpp"

namespace {

constexpr std::uint32_t kT = 4;  // clocks per bit at 12 Mbaud

struct Bench : sc_core::sc_module {
  tlm_utils::simple_initiator_socket<sc_core::sc_module> cpu{"cpu"};
  dpc31::systemc::Dpc31Tlm chip{"spc3", dpc31::ChipOptions{dpc31::Profile::spc3}};
  sc_core::sc_signal<bool> x_int{"x_int"}, irq{"irq"}, pb3{"pb3"}, txd{"txd"};
  sc_core::sc_signal<bool> rxd{"rxd", true};
  std::uint64_t request_end = 0;
  std::uint64_t answer_start = 0;

  SC_HAS_PROCESS(Bench);
  explicit Bench(const sc_core::sc_module_name& n) : sc_module(n) {
    cpu.bind(chip.bus);
    chip.x_int(x_int);
    chip.irq(irq);
    chip.pb3(pb3);
    chip.txd(txd);
    chip.rxd(rxd);
    SC_THREAD(uart);
    SC_THREAD(listen);
  }

  void uart() {
    // Start_SPC3 through the socket (Mode_Reg1_S, 08h): completes at cycle 4.
    std::uint8_t start = 0x01;
    tlm::tlm_generic_payload tr;
    tr.set_command(tlm::TLM_WRITE_COMMAND);
    tr.set_address(0x08);
    tr.set_data_ptr(&start);
    tr.set_data_length(1);
    tr.set_streaming_width(1);
    sc_core::sc_time delay = sc_core::SC_ZERO_TIME;
    cpu->b_transport(tr, delay);
    wait(delay);
    // FDL_Status to the chip's station address after TSYN (33 bit times) of idle line.
    const std::vector<std::uint8_t> bytes = dpc31::fdl::encode(dpc31::fdl::make_frame(
        chip.chip().station_address(), 2,
        dpc31::fdl::make_request_fc(dpc31::fdl::Function::FDL_Status, false, false)));
    const std::uint64_t first = chip.chip().cycle() + 33 * kT;
    std::vector<std::pair<std::uint64_t, bool>> edges;
    dpc31::uart_encode(bytes, first, kT, edges);
    for (const auto& [cycle, level] : edges) {
      wait(chip.time_of(cycle) - sc_core::sc_time_stamp());
      rxd.write(level);
    }
    request_end = first + bytes.size() * 11 * kT;
  }

  void listen() {
    wait(txd.negedge_event());  // the answer's first start bit
    answer_start = chip.cycle_at(sc_core::sc_time_stamp());
    wait(sc_core::sc_time(100, sc_core::SC_US));
    sc_core::sc_stop();
  }
};

}  // namespace

int sc_main(int, char*[]) {
  Bench b("bench");
  sc_core::sc_start(sc_core::sc_time(1, sc_core::SC_MS));
  const std::uint64_t expected = b.request_end + 11 * kT;
  std::printf("request end %llu, answer start %llu, expected %llu\n",
              static_cast<unsigned long long>(b.request_end),
              static_cast<unsigned long long>(b.answer_start),
              static_cast<unsigned long long>(expected));
  return b.request_end != 0 && b.answer_start == expected ? 0 : 1;
}

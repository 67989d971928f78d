// The edges of the model's socket (docs/systemc.md, "the bus", "debug transport"): a transaction
// that does not fit below the top of the address range is refused whole, also where its address
// plus its length passes 2^64 (it wrapped round to 1FFFh and 0 and was carried out), and a debug
// transaction with TLM_IGNORE_COMMAND transfers nothing (it was taken as a write). Exit 0 when
// every check holds; each one that does not is a line on stderr.
#include <tlm_utils/simple_initiator_socket.h>

#include <cstdint>
#include <cstdio>
#include <string>
#include <systemc>
#include <tlm>
#include <utility>

#include "dpc31_tlm.hpp"

namespace {

constexpr std::uint64_t kTop = ~std::uint64_t{0};  // the last address a payload can name

std::string hex(std::uint64_t v) {
  char text[24];
  std::snprintf(text, sizeof text, "%llXh", static_cast<unsigned long long>(v));
  return text;
}

struct Bench : sc_core::sc_module {
  tlm_utils::simple_initiator_socket<sc_core::sc_module> cpu{"cpu"};
  dpc31::systemc::Dpc31Tlm chip{"dpc31", dpc31::ChipOptions{}};
  sc_core::sc_signal<bool> x_int{"x_int"}, irq{"irq"}, pb3{"pb3"}, txd{"txd"};
  int failures = 0;

  SC_HAS_PROCESS(Bench);
  explicit Bench(const sc_core::sc_module_name& n) : sc_module(n) {
    cpu.bind(chip.bus);
    chip.x_int(x_int);
    chip.irq(irq);
    chip.pb3(pb3);
    chip.txd(txd);
    SC_THREAD(initiator);
  }

  void expect(bool ok, const std::string& what) {
    if (ok) return;
    std::fprintf(stderr, "transport_edges: %s\n", what.c_str());
    ++failures;
  }

  static void set(tlm::tlm_generic_payload& tr, tlm::tlm_command cmd, std::uint64_t addr,
                  unsigned char* data, unsigned len) {
    tr.set_command(cmd);
    tr.set_address(addr);
    tr.set_data_ptr(data);
    tr.set_data_length(len);
    tr.set_streaming_width(len);
    tr.set_response_status(tlm::TLM_INCOMPLETE_RESPONSE);
  }

  // b_transport of `len` bytes at `addr`: its response, and whether the chip saw no access.
  tlm::tlm_response_status access(tlm::tlm_command cmd, std::uint64_t addr, unsigned len,
                                  bool& untouched) {
    unsigned char data[2] = {0x55, 0x66};
    tlm::tlm_generic_payload tr;
    set(tr, cmd, addr, data, len);
    const std::uint64_t accesses = chip.accesses();
    const std::uint64_t cycle = chip.chip().cycle();
    sc_core::sc_time delay = sc_core::SC_ZERO_TIME;
    cpu->b_transport(tr, delay);
    wait(delay);
    untouched = chip.accesses() == accesses && chip.chip().cycle() == cycle;
    return tr.get_response_status();
  }

  void initiator() {
    const std::uint64_t top = (std::uint64_t{1} << chip.chip().profile().address_bits) - 1;
    bool untouched = false;
    expect(access(tlm::TLM_READ_COMMAND, top, 1, untouched) == tlm::TLM_OK_RESPONSE && !untouched,
           "the last address is read");
    for (const tlm::tlm_command cmd : {tlm::TLM_READ_COMMAND, tlm::TLM_WRITE_COMMAND}) {
      const std::string name = cmd == tlm::TLM_READ_COMMAND ? "a read" : "a write";
      for (const std::uint64_t addr : {top, top + 1, kTop - 1, kTop}) {
        const tlm::tlm_response_status st = access(cmd, addr, 2, untouched);
        expect(st == tlm::TLM_ADDRESS_ERROR_RESPONSE && untouched,
               name + " of 2 bytes at " + hex(addr) + ": response " + std::to_string(st) +
                   (untouched ? "" : ", carried out"));
      }
    }

    // Debug transport: a cell of RAM written, then an ignored command with another value.
    unsigned char v = 0xA5;
    tlm::tlm_generic_payload w;
    set(w, tlm::TLM_WRITE_COMMAND, 0x1000, &v, 1);
    expect(cpu->transport_dbg(w) == 1, "a debug write of 1 byte");
    unsigned char zero = 0x00;
    tlm::tlm_generic_payload ignore;
    set(ignore, tlm::TLM_IGNORE_COMMAND, 0x1000, &zero, 1);
    const unsigned n = cpu->transport_dbg(ignore);
    expect(n == 0, "an ignored debug command transferred " + std::to_string(n) + " bytes");
    expect(chip.chip().peek(0x1000) == 0xA5, "an ignored debug command wrote the cell");
    unsigned char two[2] = {};
    tlm::tlm_generic_payload r;
    set(r, tlm::TLM_READ_COMMAND, kTop, two, 2);
    expect(cpu->transport_dbg(r) == 0, "a debug read at the top of the 64-bit range");
    // A debug write keeps Chip::poke's run-state rule: EOI at Mode_Reg1's read-back (15h) is not
    // stored and ends the transfer; En_Change_Cfg_Buffer is the latch's own.
    for (const auto& [byte, taken] : {std::pair{0x02, 0u}, std::pair{0x10, 1u}}) {
      unsigned char m1 = static_cast<unsigned char>(byte);
      tlm::tlm_generic_payload p;
      set(p, tlm::TLM_WRITE_COMMAND, 0x15, &m1, 1);
      const unsigned done = cpu->transport_dbg(p);
      expect(done == taken && chip.chip().peek(0x15) == (taken != 0 ? byte : 0),
             "a debug write of " + hex(static_cast<std::uint64_t>(byte)) + " at 15h transferred " +
                 std::to_string(done) + " bytes");
    }
    sc_core::sc_stop();
  }
};

}  // namespace

int sc_main(int, char*[]) {
  Bench b("bench");
  sc_core::sc_start();
  return b.failures == 0 ? 0 : 1;
}

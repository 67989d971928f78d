// An example virtual platform (docs/systemc.md): a CPU thread runs the DO4 firmware through the
// model's TLM-2.0 socket with a quantum keeper (temporal decoupling), the built-in DP master is on
// the chip's serial line. It reaches Data_Exchange, exchanges data, and must have exactly the
// cycles of the native run (the same firmware on the host CPU model, session/cpu.cpp): every
// telegram, every answer and every DO4 output write, compared one by one. Exit 0 when equal.
//   vp_do4 [--bench N]   N: also time N b_transport accesses (register reads) per second
//   vp_do4 --two         two such platforms in one simulation (a dpc31 at 5, a vpc3plus at 6),
//                        each compared with its own native run
#include <tlm_utils/simple_initiator_socket.h>
#include <tlm_utils/tlm_quantumkeeper.h>

#include <cerrno>
#include <charconv>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <systemc>
#include <tlm>
#include <vector>

#include "dp_master.hpp"
#include "dpc31/bus_port.hpp"
#include "dpc31_tlm.hpp"
#include "firmware_host.hpp"

namespace {

using dpc31::systemc::Dpc31Tlm;
using dpc31::systemc::KeepSelection;

// A platform's chip and its DO4's station address.
struct Station {
  dpc31::Profile profile;
  std::uint8_t address;
};
constexpr Station kAlone{dpc31::Profile::dpc31, 5};
constexpr Station kSecond{dpc31::Profile::vpc3plus, 6};

dpc31::SlaveConfig slave_of(const dpc31_firmware& d, const Station& st) {
  dpc31::SlaveConfig s = dpc31::with_gsd_defaults(d);
  s.address = st.address;
  return s;
}

// What one run gave: the telegrams with their cycles, DO4's output writes, the end.
struct Run {
  std::vector<std::uint64_t> telegrams;  // request start/end, answer start/end of each exchange
  std::vector<std::uint64_t> outputs;    // cycle and value of each port write
  std::uint64_t cycle = 0;
  bool data_exchange = false;
};

const std::vector<std::vector<std::uint8_t>> kOutputs = {{0x05, 0x01}, {0x0A, 0x01}, {0x0F, 0x01}};

void master_session(dpc31::DpMaster& m, dpc31::FirmwareHost& fw, Run& r) {
  r.data_exchange = m.startup();
  for (const auto& out : kOutputs) m.data_exchange(out);
  for (const dpc31::Exchange& ex : m.history()) {
    r.telegrams.insert(r.telegrams.end(),
                       {ex.request_start, ex.request_end, ex.answer_start, ex.answer_end});
  }
  for (const auto& w : fw.port_writes()) r.outputs.insert(r.outputs.end(), {w.cycle, w.value});
}

Run native(const Station& st) {
  const dpc31_firmware& d = dpc31::find_firmware("DO4");
  dpc31::Chip chip({st.profile});
  dpc31::FirmwareHost fw(d);
  dpc31::DirectBus bus(chip);
  fw.init(bus, st.address);
  dpc31::DpMaster m(chip, {}, slave_of(d, st));
  m.set_firmware(fw.program());
  Run r;
  master_session(m, fw, r);
  r.cycle = chip.cycle();
  return r;
}

// The firmware's bus over the socket: each access a b_transport with the quantum keeper's local
// time, which the model annotates with the access's exact time.
class SocketBus final : public dpc31::BusPort {
 public:
  SocketBus(tlm_utils::simple_initiator_socket<sc_core::sc_module>& s, Dpc31Tlm& model)
      : socket_(s), model_(model) {
    qk_.reset();
  }
  std::uint8_t read(std::uint32_t addr) override {
    std::uint8_t v = 0;
    access(tlm::TLM_READ_COMMAND, addr, &v);
    return v;
  }
  void write(std::uint32_t addr, std::uint8_t value) override {
    access(tlm::TLM_WRITE_COMMAND, addr, &value);
  }
  void write_block(std::uint32_t addr, std::span<const std::uint8_t> bytes) override {
    for (std::uint8_t b : bytes) write(addr++, b);
  }
  void read_block(std::uint32_t addr, std::span<std::uint8_t> out) override {
    for (std::uint8_t& b : out) b = read(addr++);
  }
  void fill(std::uint32_t addr, std::uint8_t value, std::size_t len) override {
    for (std::size_t i = 0; i < len; ++i) write(addr++, value);
  }
  bool equal(std::uint32_t a, std::uint32_t b, std::size_t len) override {
    for (std::size_t i = 0; i < len; ++i) {
      const std::uint8_t first = read(a++);  // a + i, then b + i: the drivers' order
      if (first != read(b++)) return false;
    }
    return true;
  }
  void idle(std::uint64_t cycles) override {
    const sc_core::sc_time now = sc_core::sc_time_stamp();
    const std::uint64_t at = model_.cycle_at(now + qk_.get_local_time());
    qk_.set(model_.time_of(at + cycles) - now);
    if (qk_.need_sync()) sync();
  }
  [[nodiscard]] const dpc31::Chip& chip() const override { return model_.chip(); }
  // A wait inside the firmware's call: another platform's firmware runs meanwhile.
  void sync() {
    const KeepSelection keep;
    qk_.sync();
  }

 private:
  void access(tlm::tlm_command cmd, std::uint32_t addr, std::uint8_t* data) {
    tlm::tlm_generic_payload tr;
    tr.set_command(cmd);
    tr.set_address(addr);
    tr.set_data_ptr(data);
    tr.set_data_length(1);
    tr.set_streaming_width(1);
    sc_core::sc_time delay = qk_.get_local_time();
    socket_->b_transport(tr, delay);
    if (tr.is_response_error()) SC_REPORT_FATAL("vp_do4", tr.get_response_string().c_str());
    qk_.set(delay);
    if (qk_.need_sync()) sync();
  }
  tlm_utils::simple_initiator_socket<sc_core::sc_module>& socket_;
  Dpc31Tlm& model_;
  tlm_utils::tlm_quantumkeeper qk_;
};

struct Platform : sc_core::sc_module {
  tlm_utils::simple_initiator_socket<sc_core::sc_module> cpu_socket{"cpu_socket"};
  Station station;
  Dpc31Tlm chip;
  sc_core::sc_signal<bool> x_int{"x_int"}, irq{"irq"}, pb3{"pb3"}, txd{"txd"};
  const dpc31_firmware& d = dpc31::find_firmware("DO4");
  dpc31::FirmwareHost fw{d};
  sc_core::sc_event init_done;
  Run result;
  std::uint64_t bench_accesses = 0;
  double bench_seconds = 0;
  int& running;  // the platforms whose master has not ended: the last one stops the simulation

  SC_HAS_PROCESS(Platform);
  Platform(const sc_core::sc_module_name& n, const Station& st, std::uint64_t bench, int& run)
      : sc_module(n), station(st), chip("dpc31", dpc31::ChipOptions{st.profile}), running(run) {
    ++running;
    cpu_socket.bind(chip.bus);
    chip.x_int(x_int);
    chip.irq(irq);
    chip.pb3(pb3);
    chip.txd(txd);
    bench_accesses = bench;
    SC_THREAD(cpu);
    SC_THREAD(master);
  }

  // The host CPU: main()'s set-up, then the ISR whenever the interrupt is active (DO4 is
  // interrupt-driven), level-triggered as the native CPU model.
  void cpu() {
    SocketBus bus(cpu_socket, chip);
    fw.init(bus, station.address);
    bus.sync();
    init_done.notify();
    wait(sc_core::SC_ZERO_TIME);  // the master is set up at the end of main()'s set-up, as natively
    for (;;) {
      if (fw.interrupts_enabled() && chip.chip().irq_active()) {
        fw.isr(bus);
        continue;
      }
      bus.sync();
      if (!(fw.interrupts_enabled() && chip.chip().irq_active())) wait(chip.irq_rise());
    }
  }

  void master() {
    wait(init_done);
    dpc31::DpMaster m(chip.chip(), {}, slave_of(d, station));
    m.scheduler = [this](std::uint64_t cycle) { chip.run_until(cycle); };
    master_session(m, fw, result);
    result.cycle = chip.chip().cycle();
    if (bench_accesses != 0) bench();
    if (--running == 0) sc_core::sc_stop();
  }

  // b_transport's rate: reads of one RAM byte of the user area through the socket, one payload
  // each, the initiator running ahead as far as the model lets it.
  void bench() {
    const std::uint32_t addr = chip.chip().profile().user_base;
    tlm::tlm_generic_payload tr;
    std::uint8_t v = 0;
    tr.set_command(tlm::TLM_READ_COMMAND);
    tr.set_data_ptr(&v);
    tr.set_data_length(1);
    tr.set_streaming_width(1);
    const auto t0 = std::chrono::steady_clock::now();
    sc_core::sc_time delay = sc_core::SC_ZERO_TIME;
    for (std::uint64_t i = 0; i < bench_accesses; ++i) {
      tr.set_address(addr);
      cpu_socket->b_transport(tr, delay);
    }
    bench_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
};

bool same(const char* what, const std::vector<std::uint64_t>& a,
          const std::vector<std::uint64_t>& b) {
  if (a == b) {
    std::printf("%s: %zu values, equal\n", what, a.size());
    return true;
  }
  std::printf("%s differ: native %zu values, SystemC %zu\n", what, a.size(), b.size());
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
    if (a[i] != b[i]) {
      std::printf("  first at %zu: native %llu, SystemC %llu\n", i,
                  static_cast<unsigned long long>(a[i]), static_cast<unsigned long long>(b[i]));
      break;
    }
  }
  return false;
}

// `--bench N`: N from 1 to 10^9 accesses, decimal or 0x hex as every number of the dpc31 command
// line (docs/security.md, "Numbers on the command line"); `--two`: two platforms; anything else
// is a usage error (exit 2).
bool parse_args(int argc, char* argv[], std::uint64_t& bench, bool& two) {
  if (argc == 1) return true;
  if (argc == 2 && std::strcmp(argv[1], "--two") == 0) return two = true;
  if (argc != 3 || std::strcmp(argv[1], "--bench") != 0) return false;
  std::string_view n(argv[2]);
  const bool hex = n.size() > 2 && n[0] == '0' && (n[1] == 'x' || n[1] == 'X');
  if (hex) n.remove_prefix(2);
  const auto [end, ec] = std::from_chars(n.data(), n.data() + n.size(), bench, hex ? 16 : 10);
  return ec == std::errc() && end == n.data() + n.size() && bench >= 1 && bench <= 1'000'000'000;
}

// One platform's run against its native run: true when every value is equal.
bool report(const Platform& vp, const Run& ref) {
  const Run& got = vp.result;
  bool ok = got.data_exchange && ref.data_exchange;
  std::printf("Data_Exchange: native %s, SystemC %s\n", ref.data_exchange ? "yes" : "no",
              got.data_exchange ? "yes" : "no");
  ok = same("telegram cycles", ref.telegrams, got.telegrams) && ok;
  ok = same("DO4 output writes", ref.outputs, got.outputs) && ok;
  ok = same("final cycle", {ref.cycle}, {got.cycle}) && ok;
  std::printf("b_transport: %llu accesses, %llu synchronised\n",
              static_cast<unsigned long long>(vp.chip.accesses()),
              static_cast<unsigned long long>(vp.chip.syncs()));
  return ok;
}

}  // namespace

int sc_main(int argc, char* argv[]) {
  std::uint64_t bench = 0;
  bool two = false;
  if (!parse_args(argc, argv, bench, two)) {
    std::fprintf(stderr,
                 "dpc31_vp_do4: usage: dpc31_vp_do4 [--bench N] [--two] (N accesses, 1 to 10^9; "
                 "--two alone)\n");
    return 2;
  }
  const Run ref = native(kAlone);
  const Run ref2 = two ? native(kSecond) : Run{};
  tlm_utils::tlm_quantumkeeper::set_global_quantum(sc_core::sc_time(1, sc_core::SC_US));
  int running = 0;
  Platform vp("vp", kAlone, bench, running);
  std::unique_ptr<Platform> second;
  if (two) second = std::make_unique<Platform>("vp2", kSecond, 0, running);
  // The platform stops itself: SystemC's "Info: /OSCI/SystemC: Simulation stopped by user." and
  // its blank line would go to stdout before the report, which is the report alone.
  sc_core::sc_report_handler::set_actions("/OSCI/SystemC", sc_core::SC_INFO,
                                          sc_core::SC_DO_NOTHING);
  sc_core::sc_start();
  bool ok = report(vp, ref);
  if (second) {
    std::printf("second platform, a vpc3plus at %u:\n", unsigned{kSecond.address});
    ok = report(*second, ref2) && ok;
  }
  if (bench != 0) {
    std::printf("bench: %.3g b_transport accesses per second\n",
                static_cast<double>(bench) / vp.bench_seconds);
  }
  // The report is the result: one lost on the way out (a full disk) is exit 2 with one line, as
  // for the CLI's outputs, never an exit 0 nobody can see.
  errno = 0;
  if (std::fflush(stdout) != 0 || std::ferror(stdout) != 0) {
    std::fprintf(stderr, "dpc31_vp_do4: cannot write the standard output%s%s\n",
                 errno != 0 ? ": " : "", errno != 0 ? std::strerror(errno) : "");
    return 2;
  }
  return ok ? 0 : 1;
}

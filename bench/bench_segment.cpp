// Issue 30: one DP cycle over a segment of N slaves (8 + 8 bytes each, the built-in user side on
// each chip's host CPU), at 1.5 and 12 Mbaud; chip time over wall time (docs/performance.md,
// docs/segment.md). Start-up is not timed.
#include <benchmark/benchmark.h>

#include <memory>
#include <vector>

#include "dp_master.hpp"
#include "dpc31/bus_port.hpp"
#include "responder.hpp"
#include "segment.hpp"

namespace {

void BM_SegmentDpCycle(benchmark::State& st) {
  const auto baud = static_cast<std::uint32_t>(st.range(0));
  const auto n = static_cast<std::size_t>(st.range(1));
  dpc31::Segment seg(baud);
  std::vector<std::unique_ptr<dpc31::Responder>> users;
  std::vector<dpc31::SlaveConfig> slaves;
  for (std::size_t i = 0; i < n; ++i) {
    dpc31::SlaveConfig sc;
    sc.address = static_cast<std::uint8_t>(3 + i);
    sc.cfg = {0x17, 0x27};  // 8 bytes in, 8 bytes out
    sc.in_len = 8;
    sc.out_len = 8;
    slaves.push_back(sc);
    dpc31::ResponderConfig rc;
    rc.slave = sc;
    // The user watchdog served on every DX_Out, as a firmware does: the SPC3 leaves
    // Data_Exchange at the Data_Exchange that counts R_User_WD_Value down to 0 (docs/timing.md),
    // 512 DP cycles into the run without it.
    rc.user_watchdog = true;
    users.push_back(std::make_unique<dpc31::Responder>(rc));
    users.back()->set_inputs(std::vector<std::uint8_t>(8, static_cast<std::uint8_t>(i)));
    const std::size_t k = seg.add_chip("slave", dpc31::ChipOptions{dpc31::Profile::spc3});
    dpc31::DirectBus bus(seg.chip(k));
    users.back()->init(bus);
    dpc31::Responder* r = users.back().get();
    // What the responder records is forgotten at once, as a long run's driver does: the
    // benchmark's memory stays flat (docs/decisions.md, "branch i30y-outputs").
    seg.set_firmware(k, [r](dpc31::BusPort& b) {
      r->isr(b);
      r->keep_last_output();
      r->interrupts.clear();
    });
  }
  const std::size_t m = seg.add_sender("master");
  dpc31::DpMaster master(seg, m, dpc31::MasterConfig{2, baud}, slaves);
  if (!master.startup_all()) {
    st.SkipWithError("a slave did not reach Data_Exchange");
    return;
  }
  // The chips take what the start-up left in the telegram log, and one DP cycle grows the
  // master's and the line's buffers, untimed: the first timed DP cycle is a steady one
  // (docs/performance.md).
  seg.align();
  const std::vector<std::vector<std::uint8_t>> outputs(n, std::vector<std::uint8_t>(8, 0x55));
  // One vector of exchanges, filled by every cycle: its buffers are reused, as a long run's are.
  std::vector<dpc31::Exchange> cycle;
  master.dp_cycle(outputs, cycle);
  const std::uint64_t c0 = seg.cycle();
  for (auto _ : st) {
    // Every timed exchange a Data_Exchange: its answer carries the slave's 8 input bytes (a
    // slave out of Data_Exchange would answer otherwise, at another cost).
    master.dp_cycle(outputs, cycle);
    for (const dpc31::Exchange& ex : cycle) {
      if (!ex.answer || ex.answer->du.size() != 8) {
        st.SkipWithError("a Data_Exchange was not answered with the slave's inputs");
        return;
      }
    }
    master.clear_history();  // as a long run does (dpc31 soak): the memory stays flat
  }
  const double chip_s = static_cast<double>(seg.cycle() - c0) / seg.clock_hz();
  st.counters["x_realtime"] = benchmark::Counter(chip_s, benchmark::Counter::kIsRate);
  st.counters["chip_us_per_cycle"] =
      benchmark::Counter(chip_s * 1e6 / static_cast<double>(st.iterations()));
}
BENCHMARK(BM_SegmentDpCycle)
    ->ArgNames({"baud", "slaves"})
    ->ArgsProduct({{1500000, 12000000}, {1, 2, 4, 8, 16, 32}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace

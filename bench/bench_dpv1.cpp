// DPV1 (issue 28): MSAC_C1 Reads of a 240-byte record at 12 Mbaud on a VPC3+, the built-in
// master (session/dpv1_master) polling the built-in user side (session/responder_dpv1), every
// telegram bit-level on RxD / TxD with exact timing: how many seconds of chip time one second of
// wall time buys ("x_realtime"), 1 000 Reads per iteration.
#include <benchmark/benchmark.h>

#include <vector>

#include "dp_master.hpp"
#include "dpv1_master.hpp"
#include "responder.hpp"

namespace {

constexpr int kReads = 1000;
constexpr std::uint8_t kRecord = 240;

dpc31::ResponderConfig config() {
  dpc31::ResponderConfig rc;
  rc.slave.user_prm = {0xC0, 0x00, 0x00};  // DPV1_Enable, Fail_Safe
  rc.dpv1.records = {{0, 1, std::vector<std::uint8_t>(kRecord, 0xA5)}};
  return rc;
}

void BM_Dpv1Read(benchmark::State& st) {
  const dpc31::ResponderConfig rc = config();
  dpc31::Chip chip({dpc31::Profile::vpc3plus, dpc31::BusMode::intel, 0});
  chip.set_log_sink(nullptr);
  dpc31::Responder user(rc);
  dpc31::DirectBus bus(chip);
  user.init(bus);
  dpc31::DpMaster master(chip, dpc31::MasterConfig{2, 12'000'000, 100, 33}, rc.slave);
  master.set_firmware([&user](dpc31::BusPort& b) { user.isr(b); });
  dpc31::Dpv1Master dpv1(chip, master);
  if (!master.startup(5000)) {
    st.SkipWithError("the master did not bring the slave to Data_Exchange");
    return;
  }
  const std::uint64_t c0 = chip.cycle();
  for (auto _ : st) {
    for (int i = 0; i < kReads; ++i) {
      const dpc31::Dpv1Answer a = dpv1.read(0, 1, kRecord);
      if (a.outcome != dpc31::Dpv1Answer::Outcome::positive || a.du.size() != 4u + kRecord) {
        st.SkipWithError("a Read was not answered with the record");
        return;
      }
      // Kept for tests; here they would only grow.
      master.clear_history();
      user.interrupts.clear();
    }
  }
  const double chip_seconds = static_cast<double>(chip.cycle() - c0) / chip.clock_hz();
  st.counters["x_realtime"] = benchmark::Counter(chip_seconds, benchmark::Counter::kIsRate);
  st.counters["chip_us_per_read"] =
      benchmark::Counter(chip_seconds * 1e6 / (static_cast<double>(st.iterations()) * kReads));
}
BENCHMARK(BM_Dpv1Read)->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace

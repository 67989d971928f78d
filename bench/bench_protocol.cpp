// Cyclic Data_Exchange through the whole chip (bit-level RxD/TxD, firmware on its thread):
// how many seconds of chip time one second of wall time buys ("x_realtime").
#include <benchmark/benchmark.h>

#include "../emu/dp_master.hpp"
#include "../emu/responder.hpp"

namespace {

void BM_DataExchange(benchmark::State& st) {
  const auto baud = static_cast<std::uint32_t>(st.range(0));
  const auto len = static_cast<std::uint8_t>(st.range(1));
  dpc31::Chip chip({dpc31::Profile::dpc31, dpc31::BusMode::intel, 0});
  chip.set_log_sink(nullptr);
  dpc31::ResponderConfig rc;
  rc.slave.in_len = len;
  rc.slave.out_len = len;
  dpc31::Responder user(rc);
  user.inputs.assign(len, 0x5A);
  dpc31::DirectBus bus(chip);
  user.init(bus);
  dpc31::DpMaster master(chip, dpc31::MasterConfig{2, baud, 100, 33}, rc.slave);
  master.set_firmware([&](dpc31::BusPort& b) { user.isr(b); });
  if (!master.startup(5000)) st.SkipWithError("no start-up");
  const std::vector<std::uint8_t> out(len, 0x11);
  const std::uint64_t c0 = chip.cycle();
  for (auto _ : st) master.data_exchange(out);
  const double chip_seconds = static_cast<double>(chip.cycle() - c0) / chip.clock_hz();
  st.counters["x_realtime"] = benchmark::Counter(chip_seconds, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_DataExchange)
    ->Args({12'000'000, 4})
    ->Args({12'000'000, 244})
    ->Args({1'500'000, 244})
    ->Args({9600, 4})
    ->UseRealTime();

// A DP watchdog at its longest, TWD = 10 ms x 255 x 255 = 650.25 s, running out on a silent bus:
// the event engine jumps from deadline to deadline (the user timer's every 1 ms, the watchdog's).
// Target: < 10 ms wall per expiry.
void BM_WatchdogExpiry650s(benchmark::State& st) {
  dpc31::Chip chip({dpc31::Profile::dpc31, dpc31::BusMode::intel, 0});
  chip.set_log_sink(nullptr);
  dpc31::ResponderConfig rc;
  rc.slave.wd_fact1 = 255;
  rc.slave.wd_fact2 = 255;
  dpc31::Responder user(rc);
  dpc31::DirectBus bus(chip);
  user.init(bus);
  dpc31::DpMaster master(chip, dpc31::MasterConfig{2, 12'000'000, 100, 33}, rc.slave);
  master.set_firmware([&](dpc31::BusPort& b) { user.isr(b); });
  if (!master.startup(5000)) st.SkipWithError("no start-up");
  const std::uint64_t twd = 650'250ull * (chip.clock_hz() / 1000);
  const std::vector<std::uint8_t> armed = chip.save_state();
  for (auto _ : st) {
    st.PauseTiming();
    chip.load_state(armed);
    st.ResumeTiming();
    chip.step(twd);
    if (chip.wd_state() != dpc31::WdState::Baud_Control) st.SkipWithError("no expiry");
  }
}
BENCHMARK(BM_WatchdogExpiry650s)->Unit(benchmark::kMicrosecond)->UseRealTime();

}  // namespace

// The whole chip on the bus (bit-level RxD/TxD, exact timing, firmware on its thread) driven by
// the built-in DP master: how many seconds of chip time one second of wall time buys
// ("x_realtime"). Issue 7 items b (12 Mbaud, 244 + 244 bytes), c (start-up and data exchange at
// 9.6 kbaud), d (a 650 s DP watchdog expiring), and the scaling families: Data_Exchange against
// baud rate and telegram length, a traced run against the number of traced signals.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <chrono>
#include <ctime>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "bench_options.hpp"
#include "bytewise_bus.hpp"
#include "cleanup.hpp"
#include "dp_master.hpp"
#include "responder.hpp"
#include "waveform.hpp"

namespace {

using Clock = std::chrono::steady_clock;

// A chip at power-on with the responder firmware (`len` bytes each way) behind the built-in
// master; `wd_fact` != 0 sets both DP watchdog factors (10 ms base, TWD = 10 ms x wd_fact^2).
// `blocks`: the firmware copies its buffers as block transfers (CopyToVpc3 & co.), else one
// access per byte (the same bus accesses, docs/timing.md "Block transfers").
// Not movable: the firmware callback refers to the members.
class DpSession {
 public:
  DpSession(std::uint32_t baud, std::uint8_t len, std::uint8_t wd_fact = 0, bool blocks = true)
      : config_(responder_config(len, wd_fact)),
        chip_({dpc31::Profile::dpc31, dpc31::BusMode::intel, 0}),
        user_(config_),
        bus_(chip_),
        master_(chip_, dpc31::MasterConfig{2, baud, 100, 33}, config_.slave),
        outputs_(len, 0x11) {
    chip_.set_log_sink(nullptr);
    user_.set_inputs(std::vector<std::uint8_t>(len, 0x5A));
    user_.init(bus_);
    master_.set_firmware([this, blocks](dpc31::BusPort& b) {
      if (blocks) {
        user_.isr(b);
      } else {
        dpc31::BytewiseBus bytewise(b);
        user_.isr(bytewise);
      }
    });
  }
  DpSession(const DpSession&) = delete;
  DpSession& operator=(const DpSession&) = delete;

  dpc31::Chip& chip() { return chip_; }
  dpc31::DpMaster& master() { return master_; }
  // Start-up to Data_Exchange; false (benchmark skipped with an error) if it fails.
  bool startup(benchmark::State& st) {
    if (master_.startup(5000) && chip_.dp_state() == dpc31::DpState::Data_Exchange) return true;
    st.SkipWithError("the master did not bring the slave to Data_Exchange");
    return false;
  }
  // `n` Data_Exchanges; false (benchmark skipped with an error) if one is not answered with the
  // slave's inputs (a slave out of Data_Exchange answers otherwise, at another cost).
  bool exchange(benchmark::State& st, int n) {
    for (int i = 0; i < n; ++i) {
      const dpc31::Exchange ex = master_.data_exchange(outputs_);
      if (!ex.answer || ex.answer->du.size() != config_.slave.in_len) {
        st.SkipWithError("a Data_Exchange was not answered with the slave's inputs");
        return false;
      }
      // The responder records every ISR entry and output for tests, the master every exchange;
      // here that would only grow.
      user_.interrupts.clear();
      user_.outputs.clear();
      master_.clear_history();
    }
    return true;
  }
  [[nodiscard]] double chip_seconds() const {
    return static_cast<double>(chip_.cycle()) / chip_.clock_hz();
  }

 private:
  static dpc31::ResponderConfig responder_config(std::uint8_t len, std::uint8_t wd_fact) {
    dpc31::ResponderConfig rc;
    // The DPC31's DPS_User_Watchdog runs only once a firmware enables it (docs/dpc31.md); it
    // counts time, not telegrams, so row d's 650 s of silence would end in its Leave_Master.
    rc.user_watchdog = false;
    rc.slave.in_len = len;
    rc.slave.out_len = len;
    if (wd_fact != 0) {
      rc.slave.wd_on = true;
      rc.slave.wd_fact1 = wd_fact;
      rc.slave.wd_fact2 = wd_fact;
      rc.slave.wd_base_1ms = false;
    }
    return rc;
  }

  dpc31::ResponderConfig config_;
  dpc31::Chip chip_;
  dpc31::Responder user_;
  dpc31::DirectBus bus_;
  dpc31::DpMaster master_;
  std::vector<std::uint8_t> outputs_;
};

void set_realtime_factor(benchmark::State& st, double chip_seconds) {
  st.counters["x_realtime"] = benchmark::Counter(chip_seconds, benchmark::Counter::kIsRate);
}

// One Data_Exchange per iteration, after start-up (not timed); block:0 copies byte by byte.
void BM_DataExchange(benchmark::State& st) {
  DpSession s(static_cast<std::uint32_t>(st.range(0)), static_cast<std::uint8_t>(st.range(1)), 0,
              st.range(2) != 0);
  if (!s.startup(st)) return;
  const double t0 = s.chip_seconds();
  for (auto _ : st) {
    if (!s.exchange(st, 1)) return;
  }
  set_realtime_factor(st, s.chip_seconds() - t0);
  st.counters["chip_us_per_dx"] =
      benchmark::Counter((s.chip_seconds() - t0) * 1e6 / static_cast<double>(st.iterations()));
}
// Items b and b' (block copies, and byte by byte; the same at 1.5 Mbaud), then the scaling
// families: baud rate at 32 bytes, telegram length at 1.5 and 12 Mbaud, with block copies.
void data_exchange_args(benchmark::internal::Benchmark* b) {
  b->Args({12000000, 244, 0});
  b->Args({1500000, 244, 0});
  for (const int baud : {9600, 19200, 93750, 187500, 500000, 1500000, 3000000, 6000000, 12000000}) {
    b->Args({baud, 32, 1});
  }
  for (const int baud : {1500000, 12000000}) {
    for (const int len : {4, 128, 244}) b->Args({baud, len, 1});
  }
}
BENCHMARK(BM_DataExchange)
    ->ArgNames({"baud", "len", "block"})
    ->Apply(data_exchange_args)
    ->UseRealTime();

// Item c: power-on (chip construction), the master's start-up including the baud search, and
// `range(1)` Data_Exchanges of 4 + 4 bytes, all timed.
void BM_StartupAndDataExchange(benchmark::State& st) {
  double chip_seconds = 0;
  for (auto _ : st) {
    DpSession s(static_cast<std::uint32_t>(st.range(0)), 4);
    if (!s.startup(st) || !s.exchange(st, static_cast<int>(st.range(1)))) return;
    chip_seconds += s.chip_seconds();
  }
  set_realtime_factor(st, chip_seconds);
}
BENCHMARK(BM_StartupAndDataExchange)
    ->ArgNames({"baud", "dx"})
    ->Args({9600, 100})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

// Item d: WD_Fact_1 = WD_Fact_2 = 255 on the 10 ms base: TWD = 650.25 s. After start-up and one
// Data_Exchange the bus falls silent; timed: TWD - 1 ms (still Data_Exchange), then 2 ms more
// (the watchdog has expired: Wait_Prm, Baud_Control).
void BM_WatchdogExpiry650s(benchmark::State& st) {
  for (auto _ : st) {
    DpSession s(1'500'000, 4, 255);
    if (!s.startup(st) || !s.exchange(st, 1)) return;
    const std::uint64_t ms = s.chip().clock_hz() / 1000;
    const std::uint64_t twd = 650'250 * ms;
    const auto t0 = Clock::now();
    s.master().idle(twd - ms);
    const bool before = s.chip().dp_state() == dpc31::DpState::Data_Exchange;
    s.master().idle(2 * ms);
    const auto t1 = Clock::now();
    st.SetIterationTime(std::chrono::duration<double>(t1 - t0).count());
    if (!before || s.chip().dp_state() != dpc31::DpState::Wait_Prm ||
        s.chip().wd_state() != dpc31::WdState::Baud_Control) {
      st.SkipWithError("the DP watchdog did not expire at TWD = 650.25 s");
      return;
    }
  }
}
// A fixed count: only the silence is timed (microseconds), so --benchmark_min_time would ask for
// hundreds of thousands of iterations, each with an untimed start-up (minutes per repetition).
BENCHMARK(BM_WatchdogExpiry650s)->UseManualTime()->Iterations(100)->Unit(benchmark::kMillisecond);

// The documented signals (docs/waveforms.md) the session's chip has: pins.c31_int0 is the C31
// controller's only, and the session's dpc31 has the external one.
std::vector<std::string> session_signals() {
  std::vector<std::string> out;
  for (const dpc31::wave::SignalDef& d : dpc31::wave::signal_list()) {
    if (std::string_view(d.name) != "pins.c31_int0") out.emplace_back(d.name);
  }
  return out;
}

// Scaling: power-on, start-up and 50 Data_Exchanges of 32 + 32 bytes at 1.5 Mbaud, with a VCD
// of the first `range(0)` of session_signals(); 0 = no recorder.
dpc31::wave::Options trace_options(std::size_t signals) {
  const std::vector<std::string> all = session_signals();
  dpc31::wave::Options o;
  o.path = (std::filesystem::temp_directory_path() /
            ("dpc31-bench-trace-" + std::to_string(::getpid()) + ".vcd"))
               .string();
  o.signals.assign(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(signals));
  return o;
}
// One such run; false (benchmark skipped with an error) if it fails. Adds its chip time.
bool traced_run(benchmark::State& st, const dpc31::wave::Options& o, double& chip_seconds) {
  DpSession s(1'500'000, 32);
  dpc31::wave::Recorder rec(o);
  std::string error;
  if (!o.signals.empty() && !rec.attach(s.chip(), error)) {
    st.SkipWithError(error.c_str());
    return false;
  }
  if (!s.startup(st) || !s.exchange(st, 50)) return false;
  if (!o.signals.empty() && !rec.finish(s.chip().cycle(), error)) {
    st.SkipWithError(error.c_str());
    return false;
  }
  chip_seconds += s.chip_seconds();
  return true;
}
void BM_TracedRun(benchmark::State& st) {
  const dpc31::wave::Options o = trace_options(static_cast<std::size_t>(st.range(0)));
  const dpc31::cleanup::Entry gone = dpc31::cleanup::Entry::path(o.path);  // also on a signal
  double chip_seconds = 0;
  std::uintmax_t bytes = 0;
  for (auto _ : st) {
    if (!traced_run(st, o, chip_seconds)) return;
    if (!o.signals.empty()) bytes = std::filesystem::file_size(o.path);
  }
  std::error_code ec;
  std::filesystem::remove(o.path, ec);
  set_realtime_factor(st, chip_seconds);
  st.counters["vcd_bytes"] = static_cast<double>(bytes);
}
void traced_run_args(benchmark::internal::Benchmark* b) {
  const auto n = static_cast<std::int64_t>(session_signals().size());
  for (const std::int64_t k :
       {std::int64_t{0}, std::int64_t{1}, std::int64_t{2}, std::int64_t{4}, std::int64_t{8}, n}) {
    b->Arg(k);
  }
}
BENCHMARK(BM_TracedRun)
    ->ArgName("signals")
    ->Apply(traced_run_args)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

// Item i (issue 19 item 7): the run above traced with every signal against the same run
// untraced, side by side in every iteration (so that a change in the machine's load falls on
// both). traced_over_untraced: the ratio of their wall times; _cpu: of their CPU times.
void BM_TracedOverUntraced(benchmark::State& st) {
  const dpc31::wave::Options none = trace_options(0);
  const dpc31::wave::Options all = trace_options(session_signals().size());
  const dpc31::cleanup::Entry gone = dpc31::cleanup::Entry::path(all.path);  // also on a signal
  double chip_seconds = 0;
  double wall[2] = {0, 0};
  double cpu[2] = {0, 0};
  const auto cpu_now = [] {
    timespec ts{};
    ::clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
  };
  for (auto _ : st) {
    for (int traced = 0; traced < 2; ++traced) {
      const auto t0 = Clock::now();
      const double c0 = cpu_now();
      if (!traced_run(st, traced != 0 ? all : none, chip_seconds)) return;
      wall[traced] += std::chrono::duration<double>(Clock::now() - t0).count();
      cpu[traced] += cpu_now() - c0;
    }
  }
  dpc31::bench::files_made();
  std::error_code ec;
  std::filesystem::remove(all.path, ec);
  st.counters["traced_over_untraced"] = wall[1] / wall[0];
  st.counters["traced_over_untraced_cpu"] = cpu[1] / cpu[0];
  st.counters["untraced_ms"] = wall[0] * 1e3 / static_cast<double>(st.iterations());
  st.counters["traced_ms"] = wall[1] * 1e3 / static_cast<double>(st.iterations());
}
BENCHMARK(BM_TracedOverUntraced)->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace

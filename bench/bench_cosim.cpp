// Cycles per second of the C++ blocks alone, the Verilated RTL alone, and the lockstep pair, on
// the same random stimulus (issue 7 item e: C++ >= 20x the RTL, lockstep >= 5 M cycles/s).
#include <benchmark/benchmark.h>

#include <chrono>

#include "lockstep.hpp"

namespace {

using namespace dpc31;
using namespace dpc31::cosim;
using MakeDut = std::unique_ptr<Dut> (*)(const DutOptions&);

const Stimulus& stimulus() {
  static const Stimulus s = random_stimulus({Profile::dpc31, 7, 200'000});
  return s;
}

std::unique_ptr<Dut> make_rtl(const DutOptions& o) { return make_rtl_dut(o); }

// A fresh Dut stepped through the whole stimulus.
void run_dut(MakeDut make, const Stimulus& s) {
  std::unique_ptr<Dut> d = make({Profile::dpc31, BusMode::intel});
  for (const Inputs& in : s) d->step(in);
  benchmark::DoNotOptimize(d->outputs());
}

void set_cycle_rate(benchmark::State& st, std::size_t cycles_per_iteration) {
  st.counters["cycles_per_s"] = benchmark::Counter(
      static_cast<double>(cycles_per_iteration) * static_cast<double>(st.iterations()),
      benchmark::Counter::kIsRate);
}

void run_alone(benchmark::State& st, MakeDut make) {
  const Stimulus& s = stimulus();
  for (auto _ : st) run_dut(make, s);
  set_cycle_rate(st, s.size());
}

void BM_CppBlocks(benchmark::State& st) { run_alone(st, make_cpp_dut); }
void BM_RtlBlocks(benchmark::State& st) { run_alone(st, make_rtl); }
void BM_Lockstep(benchmark::State& st) {
  const Stimulus& s = stimulus();
  for (auto _ : st) {
    benchmark::DoNotOptimize(run_lockstep(s, {Profile::dpc31, BusMode::intel}).divergence);
  }
  set_cycle_rate(st, s.size());
}

// Both alone in every iteration, interleaved so that both see the same machine load; the counter
// is how many times faster the C++ blocks are than the RTL.
void BM_CppOverRtl(benchmark::State& st) {
  using Clock = std::chrono::steady_clock;
  const Stimulus& s = stimulus();
  Clock::duration cpp{};
  Clock::duration rtl{};
  for (auto _ : st) {
    const auto t0 = Clock::now();
    run_dut(make_cpp_dut, s);
    const auto t1 = Clock::now();
    run_dut(make_rtl, s);
    rtl += Clock::now() - t1;
    cpp += t1 - t0;
  }
  st.counters["cpp_over_rtl"] =
      std::chrono::duration<double>(rtl).count() / std::chrono::duration<double>(cpp).count();
}

BENCHMARK(BM_CppBlocks)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RtlBlocks)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Lockstep)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CppOverRtl)->Unit(benchmark::kMillisecond);

}  // namespace

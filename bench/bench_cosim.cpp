// Cycles per second of the C++ blocks alone, the Verilated RTL alone, and the lockstep pair, on
// the same random stimulus (issue: C++ >= 20x the RTL, lockstep >= 5 M cycles/s).
#include <benchmark/benchmark.h>

#include "lockstep.hpp"

namespace {

using namespace dpc31;
using namespace dpc31::cosim;

const Stimulus& stimulus() {
  static const Stimulus s = random_stimulus({Profile::dpc31, 7, 200'000});
  return s;
}

void run_alone(benchmark::State& st, std::unique_ptr<Dut> (*make)(const DutOptions&)) {
  const Stimulus& s = stimulus();
  std::uint64_t cycles = 0;
  for (auto _ : st) {
    std::unique_ptr<Dut> d = make({Profile::dpc31, BusMode::intel});
    for (const Inputs& in : s) d->step(in);
    benchmark::DoNotOptimize(d->outputs());
    cycles += s.size();
  }
  st.counters["cycles_per_s"] =
      benchmark::Counter(static_cast<double>(cycles), benchmark::Counter::kIsRate);
}

void BM_CppBlocks(benchmark::State& st) { run_alone(st, make_cpp_dut); }
void BM_RtlBlocks(benchmark::State& st) {
  run_alone(st, [](const DutOptions& o) { return make_rtl_dut(o); });
}
void BM_Lockstep(benchmark::State& st) {
  const Stimulus& s = stimulus();
  std::uint64_t cycles = 0;
  for (auto _ : st) {
    benchmark::DoNotOptimize(run_lockstep(s, {Profile::dpc31, BusMode::intel}).divergence);
    cycles += s.size();
  }
  st.counters["cycles_per_s"] =
      benchmark::Counter(static_cast<double>(cycles), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_CppBlocks)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RtlBlocks)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Lockstep)->Unit(benchmark::kMillisecond);

}  // namespace

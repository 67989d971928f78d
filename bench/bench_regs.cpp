// Register access cost through the C++ API (issue: performance target <= 5 ns per access).
#include <benchmark/benchmark.h>

#include "dpc31/chip.hpp"
#include "dpc31/dpc31_hal.h"

namespace {

void BM_ReadRegister(benchmark::State& st) {
  dpc31::Chip c({dpc31::Profile::dpc31, dpc31::BusMode::intel, 0});
  for (auto _ : st) benchmark::DoNotOptimize(c.read(0x00));
}
BENCHMARK(BM_ReadRegister);

void BM_WriteRegister(benchmark::State& st) {
  dpc31::Chip c({dpc31::Profile::dpc31, dpc31::BusMode::intel, 0});
  std::uint8_t v = 0;
  // Int_Mask_Reg bits 7..0; bits 7..5 are reserved and stay 1, so nothing is logged.
  for (auto _ : st) c.write(0x04, static_cast<std::uint8_t>(v++ | 0xE0));
  benchmark::DoNotOptimize(c.cycle());
}
BENCHMARK(BM_WriteRegister);

void BM_ReadRam(benchmark::State& st) {
  dpc31::Chip c({dpc31::Profile::dpc31, dpc31::BusMode::intel, 0});
  for (auto _ : st) benchmark::DoNotOptimize(c.read(0x0900));
}
BENCHMARK(BM_ReadRam);

void BM_StepUserTimer(benchmark::State& st) {
  dpc31::Chip c({dpc31::Profile::dpc31, dpc31::BusMode::intel, 0});
  c.write(0x08, 0x01);  // started: the user timer ticks every 48000 cycles
  for (auto _ : st) c.step(48000);
}
BENCHMARK(BM_StepUserTimer);

// The same accesses through the C HAL: a firmware's Vpc3Read / Vpc3Write on the selected chip.
void BM_HalReadRegister(benchmark::State& st) {
  dpc31_chip* c = dpc31_create("dpc31", 0);
  dpc31_select(c);
  for (auto _ : st) benchmark::DoNotOptimize(Vpc3Read(0x00));
  dpc31_destroy(c);
}
BENCHMARK(BM_HalReadRegister);

void BM_HalWriteRegister(benchmark::State& st) {
  dpc31_chip* c = dpc31_create("dpc31", 0);
  dpc31_select(c);
  std::uint8_t v = 0;
  for (auto _ : st) Vpc3Write(0x04, static_cast<std::uint8_t>(v++ | 0xE0));
  dpc31_destroy(c);
}
BENCHMARK(BM_HalWriteRegister);

}  // namespace

BENCHMARK_MAIN();

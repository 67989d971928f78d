// Register access cost through the C++ API and through the C HAL (include/dpc31/dpc31_hal.h):
// issue 7 item a, target <= 5 ns per access. Int_Req_Reg is read, Int_Mask_Reg written (its
// reserved bits 7..5 stay 1, so nothing is logged).
#include <benchmark/benchmark.h>

#include "dpc31/chip.hpp"
#include "dpc31/dpc31_hal.h"

namespace {

constexpr std::uint16_t kIntReq = 0x00;
constexpr std::uint16_t kIntMask = 0x04;
constexpr std::uint16_t kUserRam = 0x0900;

std::uint8_t mask_value(std::uint8_t& v) { return static_cast<std::uint8_t>(v++ | 0xE0); }

void BM_ReadRegister(benchmark::State& st) {
  dpc31::Chip c({dpc31::Profile::dpc31, dpc31::BusMode::intel, 0});
  for (auto _ : st) benchmark::DoNotOptimize(c.read(kIntReq));
}
BENCHMARK(BM_ReadRegister);

void BM_WriteRegister(benchmark::State& st) {
  dpc31::Chip c({dpc31::Profile::dpc31, dpc31::BusMode::intel, 0});
  std::uint8_t v = 0;
  for (auto _ : st) c.write(kIntMask, mask_value(v));
  benchmark::DoNotOptimize(c.cycle());
}
BENCHMARK(BM_WriteRegister);

void BM_ReadRam(benchmark::State& st) {
  dpc31::Chip c({dpc31::Profile::dpc31, dpc31::BusMode::intel, 0});
  for (auto _ : st) benchmark::DoNotOptimize(c.read(kUserRam));
}
BENCHMARK(BM_ReadRam);

// The C HAL on a handle of its own; `selected` also makes it the chip of Vpc3Read/Vpc3Write.
class HalChip {
 public:
  explicit HalChip(bool selected) : c_(dpc31_create("dpc31", 0)) {
    if (selected) dpc31_select(c_);
  }
  ~HalChip() { dpc31_destroy(c_); }  // also deselects it
  HalChip(const HalChip&) = delete;
  HalChip& operator=(const HalChip&) = delete;
  [[nodiscard]] dpc31_chip* get() const { return c_; }

 private:
  dpc31_chip* c_;
};

void BM_HalRead(benchmark::State& st) {
  const HalChip c(false);
  for (auto _ : st) benchmark::DoNotOptimize(dpc31_read(c.get(), kIntReq));
}
BENCHMARK(BM_HalRead);

void BM_HalWrite(benchmark::State& st) {
  const HalChip c(false);
  std::uint8_t v = 0;
  for (auto _ : st) dpc31_write(c.get(), kIntMask, mask_value(v));
  benchmark::DoNotOptimize(dpc31_cycle(c.get()));
}
BENCHMARK(BM_HalWrite);

void BM_Vpc3Read(benchmark::State& st) {
  const HalChip c(true);
  for (auto _ : st) benchmark::DoNotOptimize(Vpc3Read(kIntReq));
}
BENCHMARK(BM_Vpc3Read);

void BM_Vpc3Write(benchmark::State& st) {
  const HalChip c(true);
  std::uint8_t v = 0;
  for (auto _ : st) Vpc3Write(kIntMask, mask_value(v));
  benchmark::DoNotOptimize(dpc31_cycle(c.get()));
}
BENCHMARK(BM_Vpc3Write);

void BM_StepUserTimer(benchmark::State& st) {
  dpc31::Chip c({dpc31::Profile::dpc31, dpc31::BusMode::intel, 0});
  c.write(0x08, 0x01);  // started: the user timer ticks every 48000 cycles
  for (auto _ : st) c.step(48000);
}
BENCHMARK(BM_StepUserTimer);

}  // namespace

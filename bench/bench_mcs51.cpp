// Issue 34 item 6: the 80C32 core alone (docs/cpu.md), in real time at 24 MHz.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <vector>

#include "mcs51/cpu.hpp"

namespace {

// Timers 0 and 1 running (timer 1 as the UART's baud generator), then a loop of ALU, MOVX to the
// core's own XDATA and MUL: per pass 9 instructions, 16 machine cycles.
const std::vector<std::uint8_t> kLoop = {
    0x75, 0x89, 0x21,  // MOV TMOD,#21h
    0x75, 0x8D, 0xFD,  // MOV TH1,#FDh
    0x75, 0x98, 0x50,  // MOV SCON,#50h
    0xD2, 0x8E,        // SETB TR1
    0xD2, 0x8C,        // SETB TR0
    0xE8,              // loop: MOV A,R0
    0x24, 0x03,        // ADD A,#3
    0xF8,              // MOV R0,A
    0x90, 0x01, 0x00,  // MOV DPTR,#0100h
    0xF0,              // MOVX @DPTR,A
    0x09,              // INC R1
    0xA4,              // MUL AB
    0xB9, 0x00, 0xF3,  // CJNE R1,#0,loop
    0x80, 0xF1,        // SJMP loop
};

void BM_Mcs51Core(benchmark::State& st) {
  mcs51::Cpu cpu;
  cpu.load_code(0, kLoop);
  constexpr std::uint64_t chunk = 200'000;  // machine cycles per iteration: 0.1 s at 24 MHz
  std::uint64_t cycles = 0;
  for (auto _ : st) cycles += cpu.run(chunk);
  // 24 MHz: 2 M machine cycles per second.
  st.counters["x_realtime"] =
      benchmark::Counter(static_cast<double>(cycles) / 2e6, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Mcs51Core)->UseRealTime();

}  // namespace

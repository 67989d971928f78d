// Issue 34 item 6: the 80C32 core alone (docs/cpu.md), in real time at 24 MHz; a whole DO4
// session on it beside the chip.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <string>
#include <vector>

#include "mcs51/cpu.hpp"
#include "scenario.hpp"

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

// A whole DO4 session on the 80C32 at 24 MHz (SDCC's image, firmware/mcs51/) beside an SPC3 at
// 1.5 Mbaud, timed from power-on: the baud search and start-up, 2 000 Data_Exchanges back to
// back (the ISR busy all the time), a pulled cable until the OSP value: x real time in chip time.
void BM_Do4Cpu51Session(benchmark::State& st) {
  const std::string text =
      "profile spc3\nbaud 1500000\n"
      "cpu 80c32 clock=24000000 firmware " DPC31_DO4_IHX
      " ports=outputs,modul_ok\n"
      "slave address=7 ident=0x0D04 cfg=21,10 in=1 out=2 wd=2,5 user_prm=00,01,05,00\n"
      "startup\nexpect dp_state Data_Exchange\nexchange outputs=0A,01\nexchange 2000\n"
      "silence 150ms\nexpect port outputs 5\n";
  dpc31::Scenario s;
  dpc31::ScenarioError error;
  if (!dpc31::parse_scenario(text, "bench.scn", s, error)) {
    st.SkipWithError(error.text().c_str());
    return;
  }
  double chip_seconds = 0;
  for (auto _ : st) {
    const dpc31::ScenarioOutcome o = dpc31::run_scenario(s, {}, {});
    if (!o.ok() || o.failed != 0) {
      const std::string why = o.failures.empty() ? "an expect failed" : o.failures.front();
      st.SkipWithError(("the DO4 session on the 80C32: " + why).c_str());
      return;
    }
    chip_seconds += static_cast<double>(o.final_cycle) / 48e6;
  }
  st.counters["x_realtime"] = benchmark::Counter(chip_seconds, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Do4Cpu51Session)->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace

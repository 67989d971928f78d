// The 80C32 beside the chip (session/cpu51_board.*, docs/cpu.md): every MOVX lands in the chip
// at the chip cycle the bus timing gives, X/INT reaches INT0. Expected cycles by hand from
// docs/cpu.md ("MOVX timing": RD/WR rises 18 oscillator clocks after the MOVX starts; the chip
// cycle is ceil(clock * 48 MHz / f_cpu)) and docs/timing.md (an access completes 4 clocks after
// it starts; X/INT follows the request in the same cycle).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "board_image.hpp"
#include "cpu51_board.hpp"

namespace dpc31 {
namespace {

struct Seen {
  std::uint64_t cycle;
  bool write;
  std::uint16_t addr;
  std::uint8_t data;
  bool operator==(const Seen&) const = default;
};

struct Observed {
  std::vector<Seen> accesses;
  std::vector<std::pair<std::uint64_t, bool>> irq;
};

Observed run_xint_ack(std::uint32_t cpu_hz) {
  const mcs51::HexImage img = board_image("xint_ack");
  Chip chip({Profile::spc3, BusMode::intel});
  Observed run;
  chip.on_bus_access([&](std::uint64_t c, const BusAccess& a) {
    run.accesses.push_back({c, a.write, a.addr, a.data});
  });
  chip.on_irq_change([&](std::uint64_t c, bool active) { run.irq.emplace_back(c, active); });
  Cpu51Board board(chip, cpu_hz, 0x8000);
  board.cpu().load_code(0, img.bytes);
  board.run_until(2000);
  EXPECT_EQ(board.cpu().in_service(), 0);
  return run;
}

TEST(Cpu51Board, MovxLandsAtTheStrobesEndAt24MHz) {
  // 24 MHz: one oscillator clock is 2 chip clocks. MOVX in machine cycles [5,7), [12,14) and,
  // in the routine after the INT0 call, [22,24) (board/xint_ack.asm): strobe ends at clocks
  // 60 + 18 = 78, 144 + 18 = 162, 264 + 18 = 282. X/INT goes active at the second one's strobe,
  // INT0 is sampled low in the same cycle (13, S5P2 after the strobe), polled in 14 (the NOP),
  // the call is [15,17).
  Observed run = run_xint_ack(24'000'000);
  std::vector<Seen> want = {
      {156, true, 0x004, 0xEF}, {324, true, 0x000, 0x10}, {564, true, 0x002, 0x10}};
  EXPECT_EQ(run.accesses, want);
  std::vector<std::pair<std::uint64_t, bool>> irq = {{324, true}, {564, false}};
  EXPECT_EQ(run.irq, irq);
}

TEST(Cpu51Board, MovxLandsAtTheStrobesEndAt11_0592MHz) {
  // 48 MHz / 11.0592 MHz = 625/144: clocks 78, 162, 282 → ceil(338.54) = 339,
  // ceil(703.125) = 704, ceil(1223.96) = 1224.
  Observed run = run_xint_ack(11'059'200);
  std::vector<Seen> want = {
      {339, true, 0x004, 0xEF}, {704, true, 0x000, 0x10}, {1224, true, 0x002, 0x10}};
  EXPECT_EQ(run.accesses, want);
  std::vector<std::pair<std::uint64_t, bool>> irq = {{704, true}, {1224, false}};
  EXPECT_EQ(run.irq, irq);
}

// The X/INT changes (chip cycle, active) of `code` on an 80C32 at 24 MHz beside an SPC3 at XDATA
// 8000h, run to each of `ends` in turn.
std::vector<std::pair<std::uint64_t, bool>> irq_changes(const std::vector<std::uint8_t>& code,
                                                        const std::vector<std::uint64_t>& ends) {
  Chip chip({Profile::spc3, BusMode::intel});
  std::vector<std::pair<std::uint64_t, bool>> irq;
  chip.on_irq_change([&](std::uint64_t c, bool active) { irq.emplace_back(c, active); });
  Cpu51Board board(chip, 24'000'000, 0x8000);
  board.cpu().load_code(0, code);
  for (const std::uint64_t end : ends) board.run_until(end);
  EXPECT_EQ(chip.cycle(), ends.back());
  return irq;
}

TEST(Cpu51Board, AnX_IntChangeIsSampledInTheCycleWhoseS5p2SeesIt) {
  // 24 MHz (chip cycle = 2 x clock). Start_SPC3 completes at s = 2 x (144 + 18) = 324; the first
  // User_Timer_Clock at s + 48 000 = 48 324 (docs/timing.md, Timers) drives X/INT active. CPU
  // cycle j samples INT0 at clock 12j + 10, chip cycle 24j + 20 >= 48 324 first for j = 2013:
  // the second cycle of the MUL [2012, 2016) (2012 = 14 + 6 x 333). Sampled before the MUL's
  // last cycle, it is called after it: [2016, 2018); LJMP [2018, 2020), MOV DPTR, MOV A, the
  // acknowledge MOVX [2023, 2025): strobe at clock 24 276 + 18 = 24 294, chip cycle 48 588.
  const mcs51::HexImage img = board_image("user_timer");
  ASSERT_GT(img.size, 0u);
  const std::vector<std::pair<std::uint64_t, bool>> want = {{48'324, true}, {48'588, false}};
  EXPECT_EQ(irq_changes(img.bytes, {50'000}), want);
}

// The refusal's one sentence (std::invalid_argument), or "" when it was made.
template <typename F>
std::string refusal(F&& make) {
  try {
    make();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(Cpu51Board, TheTimeBaseIsExact) {
  Chip chip({Profile::spc3, BusMode::intel});
  Cpu51Board b40(chip, 40'000'000, 0);
  EXPECT_EQ(b40.chip_cycle_of(5), 6u);                                         // 5 * 1.2
  EXPECT_EQ(b40.chip_cycle_of(10), 12u);                                       // exact, no rounding
  EXPECT_EQ(b40.chip_cycle_of(3'600ULL * 40'000'000), 3'600ULL * 48'000'000);  // one hour
}

// One CPU clock range at every door (the scenario's `clock=`, --cpu 80c32:HZ, Python's hz=):
// 1..40 MHz, said in the refusal. The C++ board took up to 287.99 MHz with no range, past even
// its own bus limit (18 clocks at least one 4-clock access: 216 MHz at 48 MHz).
TEST(Cpu51Board, TheCpuClockRangeIsEveryDoorsAndSaid) {
  Chip chip({Profile::spc3, BusMode::intel});
  for (const std::uint32_t hz : {0u, 999'999u, 40'000'001u, 216'000'000u, 287'999'999u}) {
    EXPECT_EQ(refusal([&] { Cpu51Board b(chip, hz, 0); }),
              fmt::format("CPU clock {} Hz out of range (1000000..40000000)", hz));
  }
  EXPECT_EQ(refusal([&] { Cpu51Board b(chip, 40'000'000, 0); }), "");
}

// The CPU's clock counts from the chip's cycle 0 and one CPU drives the chip's bus: a board on a
// chip that has run had every instant off by the chip's cycle, a second board on one chip never
// ran (the first one's run took the chip's time). Both are refused where the board is made.
TEST(Cpu51Board, AChipThatHasRunOrHasABoardIsRefused) {
  Chip ran({Profile::spc3, BusMode::intel});
  ran.step(1000);
  EXPECT_EQ(refusal([&] { Cpu51Board b(ran, 24'000'000, 0x8000); }),
            "the chip has run (cycle 1000): a board starts with a chip at cycle 0");
  Chip chip({Profile::spc3, BusMode::intel});
  {
    Cpu51Board first(chip, 24'000'000, 0x8000);
    EXPECT_EQ(refusal([&] { Cpu51Board b(chip, 24'000'000, 0x8000); }),
              "the chip has a board already: one CPU drives a chip's bus");
  }
  EXPECT_EQ(refusal([&] { Cpu51Board b(chip, 24'000'000, 0x8000); }), "");  // the first is gone
  // A C31 refused after its chip was taken gives it back (c31_test makes one after).
  Chip dpc31({.profile = Profile::dpc31, .irq_controller = IrqController::c31});
  EXPECT_NE(refusal([&] { Cpu51Board b(dpc31, 24'000'000, Cpu51Board::C31{0x0800}); }), "");
  EXPECT_EQ(refusal([&] { Cpu51Board b(dpc31, 24'000'000, Cpu51Board::C31{0x1000}); }), "");
}

// 2^63 CPU clocks at 24 MHz are 2^64 chip cycles at 48 MHz: it wrapped to 0. The chip's time ends
// at Chip::kLastCycle = 2^62 - 1, the chip cycle of clock 2^61 - 1; later clocks are refused.
TEST(Cpu51Board, AClockPastTheChipsLastCycleIsRefusedNotWrapped) {
  Chip chip({Profile::spc3, BusMode::intel});
  Cpu51Board b(chip, 24'000'000, 0);
  EXPECT_EQ(b.chip_cycle_of((std::uint64_t{1} << 61) - 1), Chip::kLastCycle - 1);
  for (const std::uint64_t clock : {std::uint64_t{1} << 61, std::uint64_t{1} << 63, UINT64_MAX}) {
    EXPECT_EQ(refusal([&] { (void)b.chip_cycle_of(clock); }),
              fmt::format("cpu_clock {} out of range (0..2305843009213693951): past the chip's "
                          "last cycle",
                          clock));
  }
}

// dpc31_board_wait_1ms (firmware/mcs51/hooks51.c) inside itself: timer 1's ISR waits while main()'s
// wait runs, and both end (docs/cpu.md, "The HAL on the 80C32": the inner wait restarts timer 0
// and leaves it running with TF0 set, so the outer one ends with it). board/nested_wait.c marks
// main()'s call and each wait's end with a write to the chip's RAM at 40h. Machine cycles by hand
// from the manual's opcode map (the listings' [N] column, 12 clocks a cycle) and docs/cpu.md
// (an instruction acts at the end of its last cycle; a timer counts from the cycle after SETB TRx;
// a flag raised before an instruction's last cycle is served after it, the call 2 cycles):
// - crt0: LJMP 2, MOV SP 2, LCALL 2 + _sdcc_external_startup 4, MOV A,DPL 1, JZ 2, XINIT's test 5,
//   RAMCLEAR 2 + 255 x 3, PSEG's and XSEG's tests 5 + 5, LJMP 2, LJMP _main 2: main() at 799.
// - main(): MOV TMOD/TH1/TL1 3 x 2, SETB ET1, EA, TR1 [807,808): timer 1 counts from 808, FE0Ch
//   overflows at its 500th count, in cycle 1307. MOV DPTR 2, CLR A 1, MOVX [811,813): mark 0.
//   LCALL [813,815).
// - The outer wait: 14 cycles to SETB TR0 [828,829), timer 0 from F830h (2 000 counts) from 829;
//   JNB TF0 in [829 + 2k, 831 + 2k). TF1 in 1307, the first cycle of the JNB [1307,1309): the
//   call [1309,1311), LJMP 2, 14 PUSHes 28, MOV PSW 2, LCALL [1343,1345).
// - The inner wait: SETB TR0 [1358,1359), timer 0 restarted from F830h: its 2 000th count, in
//   cycle 3358, is the last cycle of the JNB [3357,3359), which sees it. MOV A, DEC, MOV R7 1
//   each, MOV _waits,R7 2, JNZ 2 (waits is 1: taken), RET [3366,3368): the inner wait ends at
//   3368. MOV DPTR 2, MOV A 1, MOVX [3371,3373): mark 1. 14 POPs 28, RETI [3401,3403).
// - The outer wait's JNB [3403,3405) sees TF0 still set (timer 0 left running): MOV A, DEC, MOV R7,
//   MOV _waits,R7 2, JNZ 2 (not taken), CLR TR0, CLR TF0, RET [3414,3416): ends at 3416, after
//   2 603 cycles (at least the 2 000 of 1 ms). MOV DPTR, MOV A, MOVX [3419,3421): mark 2.
// A MOVX starting in machine cycle M completes at chip cycle 2 x (12 M + 18) = 24 M + 36 (24 MHz).
// With the hook before the fix (the inner wait stopped timer 0 and cleared TF0) main() never ends
// its wait: no mark 2.
TEST(Cpu51Board, NestedWaitsEndTogether) {
  const mcs51::HexImage img = board_image("nested_wait");
  ASSERT_GT(img.size, 0u);
  Chip chip({Profile::spc3, BusMode::intel});
  std::vector<Seen> writes;
  chip.on_bus_access([&](std::uint64_t c, const BusAccess& a) {
    writes.push_back({c, a.write, a.addr, a.data});
  });
  Cpu51Board board(chip, 24'000'000, 0x8000);
  board.cpu().load_code(0, img.bytes);
  board.run_until(24 * 4000);  // machine cycle 4 000: 579 after the last mark
  auto mark = [](std::uint64_t machine_cycle, std::uint8_t n) {
    return Seen{24 * machine_cycle + 36, true, 0x040, n};
  };
  const std::vector<Seen> want = {mark(811, 0), mark(3371, 1), mark(3419, 2)};
  EXPECT_EQ(writes, want);
  EXPECT_EQ(board.cpu().in_service(), 0);
}

// run_until(T) leaves the chip at T exactly, whatever the CPU runs (docs/timing.md, "An 80C32
// beside the chip"): the built-in master sends its next request at now() and a scenario's
// `silence` lasts its time, so an overshoot moved the line with the CPU's clock (the chip at 7436
// or 7872 where the master's retry was due at 7424). A DIV loop (84h DIV AB 4 cycles, 80h FDh
// SJMP 2) at 1 MHz has steps of up to 4 x 12 x 48 = 2304 chip cycles; each end here lies inside
// one. With a step hook (`--trace-cpu`) the walk goes step by step: the same ends.
TEST(Cpu51Board, RunUntilEndsAtTheCycleAskedWhateverTheCpuRuns) {
  for (const bool hooked : {false, true}) {
    for (const std::uint32_t hz : {1'000'000u, 24'000'000u}) {
      Chip chip({Profile::spc3, BusMode::intel});
      Cpu51Board board(chip, hz, 0x8000);
      const std::vector<std::uint8_t> div_loop = {0x84, 0x80, 0xFD};
      board.cpu().load_code(0, div_loop);
      if (hooked) board.on_step = [](std::uint16_t, std::uint64_t) {};
      for (const std::uint64_t t : {1u, 7u, 1056u, 2208u, 3360u, 7424u, 7425u, 100'001u}) {
        board.run_until(t);
        EXPECT_EQ(chip.cycle(), t) << hz << " Hz, hooked " << hooked;
        // The CPU's last step sampled before T and ended 2 clocks after its last sample.
        EXPECT_LE(board.chip_cycle_of(board.cpu().clocks()), t + board.chip_cycle_of(2));
      }
    }
  }
}

// A hardware reset of the chip under a board (Chip::reset) is an event at the board's instant:
// the chip's new time line starts there and its clock counts on, as the CPU's does (docs/cpu.md,
// "The board"), and a run to a cycle before it runs nothing. SJMP $ (80h FEh, 2 machine cycles) at
// 24 MHz: chip cycle 48 000 is CPU clock 24 000, machine cycle 2 000; the step [1998, 2000)
// samples last at clock 23 998 (chip cycle 47 996) and runs, the next one's first sample (chip
// cycle 48 020) waits.
TEST(Cpu51Board, AResetChipCountsOnFromTheBoardsInstant) {
  Chip chip({Profile::spc3, BusMode::intel});
  Cpu51Board board(chip, 24'000'000, 0x8000);
  const std::vector<std::uint8_t> spin = {0x80, 0xFE};
  board.cpu().load_code(0, spin);
  board.run_until(48'000);
  ASSERT_EQ(board.cpu().cycles(), 2000u);
  chip.reset();
  EXPECT_EQ(chip.cycle(), 48'000u);
  board.run_until(10);
  EXPECT_EQ(chip.cycle(), 48'000u);
  EXPECT_EQ(board.cpu().cycles(), 2000u);
  board.run_until(96'000);
  EXPECT_EQ(chip.cycle(), 96'000u);
  EXPECT_EQ(board.cpu().cycles(), 4000u);
}

// A snapshot's load under a board (Chip::load_state) takes only the board's instant, where its
// last run ended: a chip put to another cycle would take the CPU's accesses at cycles the firmware
// never saw (the audit of the thirty-third session: loaded at 200 000 under a board at 50 000,
// the CPU's accesses of [50 000, 200 000) landed 4 cycles apart from 200 004). The refusal is
// `dpc31 serve --cpu`'s for `load` (docs/protocol.md), the chip unchanged; after a reset
// (docs/cpu.md, "The board") the board's instant is still where the run ended. SJMP $ at 24 MHz: 48
// 000 chip cycles are 2 000 machine cycles (AResetChipCountsOnFromTheBoardsInstant).
TEST(Cpu51Board, ALoadTakesOnlyASnapshotOfTheBoardsInstant) {
  const std::vector<std::uint8_t> spin = {0x80, 0xFE};
  std::vector<std::uint8_t> at48, at96;
  {
    Chip chip({Profile::spc3, BusMode::intel});
    Cpu51Board board(chip, 24'000'000, 0x8000);
    board.cpu().load_code(0, spin);
    board.run_until(48'000);
    at48 = chip.save_state();
    board.run_until(96'000);
    at96 = chip.save_state();
  }
  Chip chip({Profile::spc3, BusMode::intel});
  const auto refused = [&](const std::vector<std::uint8_t>& s, const std::string& message) {
    const std::vector<std::uint8_t> before = chip.save_state();
    try {
      chip.load_state(s);
      ADD_FAILURE() << "loaded; expected: " << message;
    } catch (const SnapshotError& e) {
      EXPECT_EQ(std::string(e.what()), message);
    }
    EXPECT_EQ(chip.save_state(), before) << "a refused snapshot changed the chip";
  };
  {
    Cpu51Board board(chip, 24'000'000, 0x8000);
    board.cpu().load_code(0, spin);
    board.run_until(48'000);
    refused(at96,
            "snapshot of cycle 96000 under a CPU board at cycle 48000: the CPU's state is not the "
            "chip's: it would run on against another chip");
    board.run_until(96'000);
    refused(at48,
            "snapshot of cycle 48000 under a CPU board at cycle 96000: the CPU's state is not the "
            "chip's: it would run on against another chip");
    chip.reset();  // at the board's instant, 96 000
    EXPECT_EQ(chip.cycle(), 96'000u);
    chip.load_state(at96);
    EXPECT_EQ(chip.cycle(), 96'000u);
    board.run_until(144'000);
    EXPECT_EQ(chip.cycle(), 144'000u);
    EXPECT_EQ(board.cpu().cycles(), 6000u);
  }
  chip.load_state(at48);  // the board is gone: any cycle again
  EXPECT_EQ(chip.cycle(), 48'000u);
}

// The same reset (Chip::reset(), as Chip::reset(board.instant())): the chip's new time line
// starts at the board's instant, so its edges are told there and an access after it lands after it
// (docs/cpu.md, "The board"); a reset at another cycle is refused, as a load of another cycle's
// snapshot is (ALoadTakesOnlyASnapshotOfTheBoardsInstant). User_Timer_Clock alone unmasked
// (Int_Mask_Reg 04h/05h) and Start_SPC3 (Mode_Reg1_S 08h) written before the board runs: 4, 8, 12;
// the first User_Timer_Clock at 12 + 48 000 (docs/timing.md, "Timers"); SJMP $ never serves it. A
// hardware reset clears Int_Req_Reg, the interrupt ends in the reset's cycle (docs/timing.md,
// "hardware reset"): 50 000, where the run ended; X/INT (low-active, INT_Pol 0 after it) high; a
// write then completes at 50 004.
TEST(Cpu51Board, AResetAtTheBoardsInstantTellsItsEdgesThere) {
  Chip chip({Profile::spc3, BusMode::intel});
  Cpu51Board board(chip, 24'000'000, 0x8000);
  const std::vector<std::uint8_t> spin = {0x80, 0xFE};
  board.cpu().load_code(0, spin);
  std::vector<std::pair<std::uint64_t, bool>> edges;
  chip.on_irq_change(
      [&edges](std::uint64_t cycle, bool active) { edges.emplace_back(cycle, active); });
  chip.write(0x04, 0xEF);  // all but User_Timer_Clock (bit 4) masked
  chip.write(0x05, 0xFF);
  chip.write(0x08, 0x01);  // Start_SPC3
  EXPECT_EQ(board.instant(), 0u);
  board.run_until(50'000);
  EXPECT_EQ(board.instant(), 50'000u);
  EXPECT_FALSE(chip.x_int_pin());
  chip.reset();
  const std::vector<std::pair<std::uint64_t, bool>> want = {{48'012, true}, {50'000, false}};
  EXPECT_EQ(edges, want);
  EXPECT_EQ(chip.cycle(), 50'000u);
  EXPECT_TRUE(chip.x_int_pin());
  EXPECT_FALSE(chip.started());
  chip.write(0x04, 0xFF);
  EXPECT_EQ(chip.cycle(), 50'004u);
  board.run_until(96'000);
  EXPECT_EQ(chip.cycle(), 96'000u);
  EXPECT_EQ(board.cpu().cycles(), 4000u);
  EXPECT_EQ(edges.size(), 2u);
  // Past the chip's last cycle, or another cycle than the board's instant: refused, the chip as
  // it was (started again: Mode_Reg1_S 08h).
  chip.write(0x08, 0x01);  // 96 004
  const auto refused = [&](std::uint64_t cycle, const std::string& message) {
    try {
      chip.reset(cycle);
      ADD_FAILURE() << "reset at " << cycle << "; expected: " << message;
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()), message);
    }
    EXPECT_EQ(chip.cycle(), 96'004u);
    EXPECT_TRUE(chip.started());
  };
  refused(Chip::kLastCycle + 1,
          fmt::format("Chip::reset: cycle {} is past the chip's last cycle {}",
                      Chip::kLastCycle + 1, Chip::kLastCycle));
  refused(0,
          "Chip::reset: cycle 0 under a CPU board at cycle 96000: a reset there is at the board's "
          "instant (the CPU's clock counts on)");
  refused(96'004,
          "Chip::reset: cycle 96004 under a CPU board at cycle 96000: a reset there is at the "
          "board's instant (the CPU's clock counts on)");
  chip.reset(board.instant());
  EXPECT_EQ(chip.cycle(), 96'000u);
  EXPECT_FALSE(chip.started());
}

// The board's RESET (docs/cpu.md, "The board's reset"), CPU and chip together at the board's
// instant. The program (machine cycles in brackets, 24 MHz beside 48 MHz: machine cycle m is chip
// cycles [24m, 24m + 24)): MOV DPTR,#4000h [0,2); INC 30h [2]; MOV A,30h [3]; MOVX @DPTR,A [4,6),
// its WR strobe ending at 24 x 4 + 36 = 132 (docs/cpu.md, "MOVX timing"); ORL PCON,#02h [6,8):
// power-down, which only a reset ends (Intel's manual). A run to 48 010 leaves the CPU at machine
// cycle 2 000 (the power-down's next cycle samples at clock 24 010, past the end's clock 24 005).
// The reset there starts the chip's new time line at 48 010 and the CPU in the first machine
// cycle starting at or after clock 24 005: 2 001 (24 012). RAM is kept, so the image writes
// 30h + 1 = 2 in MOVX [2 005, 2 007): at 24 x 2 005 + 36 = 48 156, and powers down again.
TEST(Cpu51Board, TheBoardsResetStartsCpuAndChipAtItsInstantAndEndsAPowerDown) {
  Chip chip({Profile::spc3, BusMode::intel});
  Cpu51Board board(chip, 24'000'000, 0x8000);
  const std::vector<std::uint8_t> code = {0x90, 0x40, 0x00, 0x05, 0x30, 0xE5, 0x30,
                                          0xF0, 0x43, 0x87, 0x02, 0x80, 0xFE};
  board.cpu().load_code(0, code);
  std::vector<Seen> latch;
  board.on_ram_write = [&latch](std::uint16_t addr, std::uint8_t value, std::uint64_t cycle) {
    latch.push_back({cycle, true, addr, value});
  };
  chip.write(0x08, 0x01);  // Start_SPC3: the reset must stop the chip too
  board.run_until(48'010);
  EXPECT_TRUE(board.cpu().powered_down());
  EXPECT_EQ(board.cpu().cycles(), 2000u);
  EXPECT_TRUE(chip.started());
  board.reset();
  EXPECT_EQ(chip.cycle(), 48'010u);
  EXPECT_FALSE(chip.started());
  EXPECT_FALSE(board.cpu().powered_down());
  EXPECT_EQ(board.cpu().pc(), 0u);
  EXPECT_EQ(board.cpu().cycles(), 2001u);
  board.run_until(96'000);
  const std::vector<Seen> want = {{132, true, 0x4000, 1}, {48'156, true, 0x4000, 2}};
  EXPECT_EQ(latch, want);
  EXPECT_TRUE(board.cpu().powered_down());
  EXPECT_EQ(chip.cycle(), 96'000u);
}

// An X/INT change whose S5P2 sample falls in a MOVX's first cycle is polled in its second (the
// manual: flags "sampled at S5P2 of every machine cycle; the samples are polled during the
// following machine cycle"), so the call follows the MOVX, whether it reads the chip or the
// board's RAM (docs/cpu.md, "INT0 from X/INT"). The program (bytes below, machine cycles in
// brackets, 24 MHz: chip cycle = 24 x cycle + 2 x clock-in-cycle): LJMP [0,2); MOV DPTR,#8004h
// [2,4), MOV A,#EFh [4,5), MOVX [5,7) unmasks User_Timer_Clock; MOV IE,#81h [7,9); MOV DPTR,#8008h
// [9,11), MOV A,#01h [11,12), MOVX [12,14) Start_SPC3, done at 2 x (144 + 18) = 324; seven NOPs
// [14,21); the loop MOV DPTR,#addr [21 + 10k, 23 + 10k), MOVX A,@DPTR [23 + 10k, 25 + 10k), MUL AB
// 4, SJMP 2. The first User_Timer_Clock at 324 + 48 000 = 48 324 (docs/timing.md, Timers): cycle
// j samples at chip cycle 24 j + 20 >= 48 324 first for j = 2013 = 23 + 10 x 199, the MOVX's
// first cycle. Polled in 2014, its last: the call [2015,2017), LJMP [2017,2019), MOV DPTR 2, MOV A
// 1, the acknowledge MOVX [2022,2024): X/INT inactive at 24 x 2022 + 36 = 48 564. (Seen only in
// the MOVX's second cycle, the call waited for the MUL: 4 cycles, 96 chip cycles, later.)
TEST(Cpu51Board, AnX_IntChangeInAMovxsFirstCycleIsCalledAfterTheMovx) {
  for (const std::uint16_t addr : {0x8016, 0x1000}) {
    std::vector<std::uint8_t> code(0x60, 0);
    const auto put = [&](std::size_t at, std::vector<std::uint8_t> bytes) {
      std::copy(bytes.begin(), bytes.end(), code.begin() + static_cast<std::ptrdiff_t>(at));
    };
    put(0x00, {0x02, 0x00, 0x30});  // LJMP start
    put(0x03, {0x02, 0x00, 0x50});  // LJMP isr
    put(0x30, {0x90, 0x80, 0x04, 0x74, 0xEF, 0xF0, 0x75, 0xA8, 0x81, 0x90, 0x80, 0x08, 0x74, 0x01,
               0xF0});  // the seven NOPs follow at 3Fh
    put(0x46, {0x90, static_cast<std::uint8_t>(addr >> 8), static_cast<std::uint8_t>(addr), 0xE0,
               0xA4, 0x80, 0xF9});
    put(0x50, {0x90, 0x80, 0x02, 0x74, 0x10, 0xF0, 0xC2, 0xAF, 0x32});  // ack, CLR EA, RETI
    const std::vector<std::pair<std::uint64_t, bool>> want = {{48'324, true}, {48'564, false}};
    EXPECT_EQ(irq_changes(code, {50'000}), want) << fmt::format("MOVX from {:04X}h", addr);
  }
}

// A run cut anywhere gives the run in one piece: the samples of the step that waits for the next
// run are walked up to the cut, the rest after it (AnX_IntChangeIsSampledInTheCycleWhoseS5p2SeesIt
// in pieces of 997 chip cycles, the cut at 48 324 too: the MUL's sample in cycle 2013 lies
// after it).
TEST(Cpu51Board, ARunInPiecesSamplesAsARunInOne) {
  const mcs51::HexImage img = board_image("user_timer");
  ASSERT_GT(img.size, 0u);
  std::vector<std::uint64_t> ends;
  for (std::uint64_t t = 997; t < 48'324; t += 997) ends.push_back(t);
  for (std::uint64_t t = 48'324; t < 50'000; t += 7) ends.push_back(t);
  ends.push_back(50'000);
  const std::vector<std::pair<std::uint64_t, bool>> want = {{48'324, true}, {48'588, false}};
  EXPECT_EQ(irq_changes(img.bytes, ends), want);
}

}  // namespace
}  // namespace dpc31

// The DPC31's internal C31 (session/cpu51_board.*, Cpu51Board::C31; docs/dpc31.md "The C31"):
// its XDATA is the chip's own address space, its code the chip's RAM from the code area's start,
// INT0 the C31's interrupt controller. Expected cycles by hand, as for the 80C32 (board_test.cpp):
// docs/cpu.md ("MOVX timing": WR rises 18 oscillator clocks after the MOVX starts; the chip cycle
// is ceil(clock * 48 MHz / f_cpu)) and docs/timing.md (an access completes 4 clocks after it
// starts; the interrupt output follows the request in the same cycle).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <vector>

#include "board_image.hpp"
#include "cpu51_board.hpp"
#include "scenario.hpp"

namespace dpc31 {
namespace {

struct Access {
  std::uint64_t cycle;
  bool write;
  std::uint16_t addr;
  std::uint8_t data;
  bool operator==(const Access&) const = default;
};

bool load(Cpu51Board& board, const std::vector<std::uint8_t>& code) {
  return board.load_c31_code(code, std::vector<bool>(code.size(), true));
}

ChipOptions c31_chip() {
  return {.profile = Profile::dpc31, .bus = BusMode::intel, .irq_controller = IrqController::c31};
}

// The board's RESET on the C31 (docs/cpu.md, "The board's reset"): the chip's reset clears its RAM,
// the code area too, and the board puts the loaded image there again, as its loader did. The
// program: MOV DPTR,#0900h [0,2); INC 30h [2]; MOV A,30h [3]; MOVX @DPTR,A [4,6) into the user
// area; SJMP $. 30h + 1 = 1 at 0900h, and after the reset, RAM 30h kept, 2 (without the image put
// back the C31 ran the cleared RAM: NOPs, 0900h stayed 00h).
TEST(C31, TheBoardsResetPutsTheImageBackIntoTheClearedRam) {
  Chip chip(c31_chip());
  Cpu51Board board(chip, 24'000'000, Cpu51Board::C31{0x1000});
  ASSERT_TRUE(load(board, {0x90, 0x09, 0x00, 0x05, 0x30, 0xE5, 0x30, 0xF0, 0x80, 0xFE}));
  chip.poke(0x0901, 0x55);  // user area: cleared by the reset
  board.run_until(48'000);
  EXPECT_EQ(chip.peek(0x0900), 1);
  board.reset();
  EXPECT_EQ(chip.peek(0x0900), 0);
  EXPECT_EQ(chip.peek(0x0901), 0);
  EXPECT_EQ(chip.peek(0x1000), 0x90);  // the image again
  EXPECT_EQ(chip.peek(0x1009), 0xFE);
  board.run_until(96'000);
  EXPECT_EQ(chip.peek(0x0900), 2);
}

TEST(C31, RunsFromTheChipsRamAndTakesTheC31sInterrupt) {
  // C31 at 24 MHz (one oscillator clock = 2 chip clocks), code area from 1000h. MOVX in machine
  // cycles [5,7), [12,14), in the routine [22,24), then [29,31) and [34,36) (board/c31_ack.asm):
  // strobes end at clocks 78, 162, 282, 366, 426 = chip cycles 156, 324, 564, 732, 852. The C31's
  // interrupt goes active at the second (Int_Req_Reg), INT0 is sampled low in cycle 13, polled
  // in 14, the call is [15,17); the routine's Int_Ack_Reg ends it at 564. The write at 732 is
  // to the operand of the instruction at code 0046h (chip 1047h), which then loads 77h into A:
  // the C31 fetches from the chip's RAM; A goes to the user area's first byte (08A0h) at 852.
  Chip chip(c31_chip());
  std::vector<Access> seen;
  chip.on_bus_access([&](std::uint64_t c, const BusAccess& a) {
    seen.push_back({c, a.write, a.addr, a.data});
  });
  std::vector<std::pair<std::uint64_t, bool>> irq;
  chip.on_irq_change([&](std::uint64_t c, bool active) { irq.emplace_back(c, active); });
  Cpu51Board board(chip, 24'000'000, Cpu51Board::C31{0x1000});
  const mcs51::HexImage img = board_image("c31_ack");
  ASSERT_TRUE(board.load_c31_code(img.bytes, img.used));
  EXPECT_EQ(chip.peek(0x1000), 0x02);  // LJMP start: the image is in the code area
  bool x_int_went_low = false;
  chip.on_bus_access([&](std::uint64_t, const BusAccess&) {
    x_int_went_low = x_int_went_low || !chip.x_int_pin();
  });
  board.run_until(1000);
  const std::vector<Access> want = {{156, true, 0x0004, 0xEF},
                                    {324, true, 0x0000, 0x10},
                                    {564, true, 0x0002, 0x10},
                                    {732, true, 0x1047, 0x77},
                                    {852, true, 0x08A0, 0x77}};
  EXPECT_EQ(seen, want);
  const std::vector<std::pair<std::uint64_t, bool>> want_irq = {{324, true}, {564, false}};
  EXPECT_EQ(irq, want_irq);
  EXPECT_EQ(board.cpu().a(), 0x77);
  EXPECT_EQ(chip.peek(0x1047), 0x77);
  EXPECT_EQ(chip.peek(0x08A0), 0x77);
  EXPECT_FALSE(x_int_went_low);  // X/INT is the external processor's: never active
  EXPECT_EQ(board.cpu().in_service(), 0);
}

TEST(C31, NothingAnswersAbove1FFFh) {
  // MOVX A,@DPTR from 2000h and MOVX @DPTR,A to it: no chip access, FFh read (modelled).
  Chip chip(c31_chip());
  unsigned accesses = 0;
  chip.on_bus_access([&](std::uint64_t, const BusAccess&) { ++accesses; });
  Cpu51Board board(chip, 24'000'000, Cpu51Board::C31{0x1F00});
  const std::vector<std::uint8_t> code = {0x90, 0x20, 0x00,  // MOV DPTR,#2000h
                                          0xF0,              // MOVX @DPTR,A
                                          0xE0,              // MOVX A,@DPTR
                                          0x80, 0xFE};       // SJMP $
  ASSERT_TRUE(load(board, code));
  board.run_until(500);
  EXPECT_EQ(accesses, 0u);
  EXPECT_EQ(board.cpu().a(), 0xFF);
}

// Code address c is RAM address code + c (docs/dpc31.md, "The C31"): past the code area, above
// 1FFFh, nothing answers and a fetch reads FFh (MOV R7,A), as the 80C32's empty program memory
// does (docs/cpu.md); inside it the chip's RAM, whatever the image left there. The program:
// MOV A,#5Ah [0,1), LJMP F000h [1,3), then FFh from F000h, one cycle each: at 24 MHz the run to
// chip cycle 2 400 takes the steps whose sample 24m + 20 lies before it, m = 3..99, 97 of them:
// PC F061h, R7 = A = 5Ah (00h, a NOP, left R7 at 0 and slid on to FFFFh and round to 0000h).
TEST(C31, EmptyCodeReadsFFhPastTheCodeArea) {
  Chip chip(c31_chip());
  chip.poke(0x1F10, 0xA5);  // the RAM inside the code area, past the image
  Cpu51Board board(chip, 24'000'000, Cpu51Board::C31{0x1F00});
  ASSERT_TRUE(load(board, {0x74, 0x5A, 0x02, 0xF0, 0x00}));
  EXPECT_EQ(board.cpu().code(0x0010), 0xA5);
  EXPECT_EQ(board.cpu().code(0x0100), 0xFF);  // RAM address 2000h: nothing
  board.run_until(2400);
  EXPECT_EQ(board.cpu().pc(), 0xF061);
  EXPECT_EQ(board.cpu().reg(7), 0x5A);
}

TEST(C31, OnlyTheDpc31sC31WithItsControllerAndACodeAreaInItsRam) {
  Chip spc3({.profile = Profile::spc3});
  EXPECT_THROW(Cpu51Board(spc3, 24'000'000, Cpu51Board::C31{0x1000}), std::invalid_argument);
  Chip external({.profile = Profile::dpc31});
  EXPECT_THROW(Cpu51Board(external, 24'000'000, Cpu51Board::C31{0x1000}), std::invalid_argument);
  Chip chip(c31_chip());
  EXPECT_THROW(Cpu51Board(chip, 24'000'000, Cpu51Board::C31{0x0800}), std::invalid_argument);
  EXPECT_THROW(Cpu51Board(chip, 24'000'000, Cpu51Board::C31{0x2000}), std::invalid_argument);
  Cpu51Board board(chip, 24'000'000, Cpu51Board::C31{0x1FF0});
  EXPECT_FALSE(load(board, std::vector<std::uint8_t>(0x11, 0)));  // past 1FFFh
  EXPECT_TRUE(load(board, std::vector<std::uint8_t>(0x10, 0)));
}

// The scenario's door: `cpu c31 firmware FILE.ihx code=A` on profile dpc31 (docs/dpc31.md, "The
// C31"). The same program: its last write puts 77h at 08A0h at chip cycle 852 (above).
TEST(C31, TheScenarioHeaderRunsTheImageOnTheC31) {
  Scenario s;
  ScenarioError err;
  const std::string head =
      "profile dpc31\ncpu c31 clock=24000000 firmware " BOARD_DIR "/c31_ack.ihx code=0x1000\n";
  ASSERT_TRUE(parse_scenario(head + "silence 20us\nexpect ram 0x08A0 77\n", "t.scn", s, err))
      << err.text();
  EXPECT_EQ(s.chip.irq_controller, IrqController::c31);  // the C31 serves its own controller
  std::vector<std::string> errors;
  std::vector<std::string> walk;
  const ScenarioOutcome out = run_scenario(
      s, [&](const std::string& l) { walk.push_back(l); },
      [&](const std::string& l) { errors.push_back(l); });
  EXPECT_TRUE(errors.empty()) << errors.front();
  EXPECT_NE(std::find_if(walk.begin(), walk.end(),
                         [](const std::string& l) {
                           return l.find("C31 at 24000000 Hz") != std::string::npos;
                         }),
            walk.end());
  // Before the write (chip cycle 852 = 17.75 us) the byte is still 00h. The board runs whole
  // instructions: at 16 us (chip 768, machine cycle 32) the MOVX [34,36) has not begun.
  ASSERT_TRUE(parse_scenario(head + "silence 16us\nexpect ram 0x08A0 00\n", "t.scn", s, err));
  errors.clear();
  run_scenario(
      s, [](const std::string&) {}, [&](const std::string& l) { errors.push_back(l); });
  EXPECT_TRUE(errors.empty()) << errors.front();
}

TEST(C31, TheScenarioHeaderIsCheckedWhenParsed) {
  const auto error = [](const std::string& text) {
    Scenario s;
    ScenarioError err;
    return parse_scenario(text, "t.scn", s, err) ? std::string() : err.text();
  };
  // As `irq-controller` (docs/scenario-format.md): `profile dpc31` on a line before it, not the
  // default profile, not a profile line after it, not another profile.
  const std::string rule =
      "'cpu c31' needs 'profile dpc31' before it: only the DPC31 has a C31 core";
  EXPECT_EQ(error("profile spc3\ncpu c31 firmware a.ihx\n"), "t.scn:2: " + rule);
  EXPECT_EQ(error("cpu c31 firmware a.ihx\nsilence 1ms\n"), "t.scn:1: " + rule);
  EXPECT_EQ(error("baud 1500000\ncpu c31 firmware a.ihx\nprofile dpc31\n"), "t.scn:2: " + rule);
  EXPECT_EQ(error("profile dpc31\ncpu c31 firmware a.ihx\nprofile dpc31\n"),
            "t.scn:3: 'profile' given twice: first at line 1");
  EXPECT_EQ(error("profile dpc31\ncpu c31 firmware a.ihx base=0x8000\n"),
            "t.scn:2: 'cpu c31' takes clock= and code= ('base=' is the 80C32 board's)");
  EXPECT_EQ(error("profile dpc31\ncpu c31 firmware a.ihx code=0x0800\n"),
            "t.scn:2: code 0x0800 out of range (0x08A0..0x1FFF)");
  EXPECT_EQ(error("profile dpc31\ncpu c31 firmware a.ihx code=0x1F00\nsilence 1ms\n"), "");
}

// An image past 1FFFh is one line, FILE: reason, exit 2, nothing run (docs/bad-input.md).
TEST(C31, AnImagePastTheCodeAreaIsRefusedWhenTheRunStarts) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "c31_test_image";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "big.ihx") << ":0101000000FE\n:00000001FF\n";  // one byte at 0100h
  std::ofstream(dir / "s.scn") << "profile dpc31\ncpu c31 firmware big.ihx code=0x1F00\n"
                                  "silence 1ms\n";
  std::vector<std::string> errors;
  std::vector<std::string> walk;
  EXPECT_EQ(
      run_scenario_file((dir / "s.scn").string(), [&](const std::string& l) { walk.push_back(l); },
                        [&](const std::string& l) { errors.push_back(l); }),
      2);
  ASSERT_EQ(errors.size(), 1u);
  // The image's errors begin with the scenario's `cpu` line (docs/bad-input.md).
  EXPECT_EQ(errors[0], (dir / "s.scn").string() + ":2: " + (dir / "big.ihx").string() +
                           ": the image does not fit the C31's code area (1F00h..1FFFh)");
  EXPECT_TRUE(walk.empty());
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace dpc31

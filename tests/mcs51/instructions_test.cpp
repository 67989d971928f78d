// The instruction set against the Intel MCS-51 User's Manual, chapter "Instruction Set": every
// expected value is the manual's operation and flag description applied by hand.
#include <gtest/gtest.h>

#include <string>

#include "mcs51_test_util.hpp"

namespace mcs51::test {
namespace {

// The manual's opcode map, one row per high nibble: the machine cycles of each opcode (A5h is
// reserved; the model runs it as a one-cycle no-op, docs/cpu.md).
constexpr const char* cycle_map[16] = {
    "1221111111111111", "2221111111111111", "2221111111111111", "2221111111111111",
    "2212111111111111", "2212111111111111", "2212111111111111", "2222121111111111",
    "2222422222222222", "2222111111111111", "2212412222222222", "2211222222222222",
    "2211111111111111", "2211121122222222", "2222111111111111", "2222111111111111"};

TEST(Mcs51Cycles, EveryOpcodeTakesTheManualsMachineCycles) {
  for (unsigned op = 0; op < 256; ++op) {
    Cpu cpu = with_code({static_cast<std::uint8_t>(op), 0x00, 0x00}, 0x0100);
    cpu.set_iram(0x07, 0x70);  // SP after a pop stays inside RAM; B = 0 makes DIV overflow
    unsigned expected = static_cast<unsigned>(cycle_map[op >> 4][op & 15] - '0');
    StepResult r = cpu.step();
    EXPECT_EQ(r.kind, StepKind::instruction);
    EXPECT_EQ(r.cycles, expected) << "opcode " << std::hex << op;
    EXPECT_EQ(cpu.cycles(), expected);
    EXPECT_EQ(cpu.clocks(), expected * 12u);
  }
}

TEST(Mcs51Arithmetic, AddSetsCarryAuxiliaryCarryAndOverflow) {
  // Manual, ADD: "CY set if a carry out of bit 7, AC if out of bit 3, OV if a carry out of bit
  // 6 but not out of bit 7, or out of bit 7 but not bit 6". Example: A=C3h + R0=AAh = 6Dh,
  // AC=0, CY=1, OV=1.
  Cpu cpu = with_code({0x74, 0xC3, 0x78, 0xAA, 0x28});  // MOV A,#C3h; MOV R0,#AAh; ADD A,R0
  steps(cpu, 3);
  EXPECT_EQ(cpu.a(), 0x6D);
  EXPECT_EQ(cpu.psw() & 0xC4, 0x84);  // CY, OV; not AC
  // 0Fh + 01h: AC only; 7Fh + 01h: OV and AC; P follows the ones in A.
  Cpu c2 = with_code({0x74, 0x0F, 0x24, 0x01, 0x74, 0x7F, 0x24, 0x01});
  steps(c2, 2);
  EXPECT_EQ(c2.a(), 0x10);
  EXPECT_EQ(c2.psw(), 0x41);  // AC, P (one bit set)
  steps(c2, 2);
  EXPECT_EQ(c2.a(), 0x80);
  EXPECT_EQ(c2.psw(), 0x45);  // AC, OV, P
}

TEST(Mcs51Arithmetic, AddcAddsTheCarryAndSubbSubtractsIt) {
  // Manual, ADDC example: A=C3h, R0=AAh, CY=1 → 6Eh, CY=1, AC=0, OV=1.
  Cpu cpu = with_code({0xD3, 0x74, 0xC3, 0x78, 0xAA, 0x38});
  steps(cpu, 4);
  EXPECT_EQ(cpu.a(), 0x6E);
  EXPECT_EQ(cpu.psw() & 0xC4, 0x84);
  // Manual, SUBB example: A=C9h, R2=54h, CY=1 → 74h, CY=0, AC=0, OV=1.
  Cpu s = with_code({0xD3, 0x74, 0xC9, 0x7A, 0x54, 0x9A});
  steps(s, 4);
  EXPECT_EQ(s.a(), 0x74);
  EXPECT_EQ(s.psw() & 0xC4, 0x04);
  // 00h - 01h: borrow into bit 7 and bit 3.
  Cpu b = with_code({0xE4, 0x94, 0x01});
  steps(b, 2);
  EXPECT_EQ(b.a(), 0xFF);
  EXPECT_EQ(b.psw() & 0xC4, 0xC0);
}

TEST(Mcs51Arithmetic, IncDecWrapWithoutFlagsAndIncDptrCarriesIntoDph) {
  // INC 0FFh → 00h and DEC 00h → FFh leave the flags alone; INC DPTR: DPL FFh → DPH + 1.
  Cpu cpu =
      with_code({0x74, 0xFF, 0x04, 0x15, 0x30, 0x78, 0x40, 0x06, 0x18, 0x90, 0x12, 0xFF, 0xA3});
  steps(cpu, 2);
  EXPECT_EQ(cpu.a(), 0x00);
  EXPECT_EQ(cpu.psw(), 0x00);
  steps(cpu, 4);  // DEC 30h; MOV R0,#40h; INC @R0; DEC R0
  EXPECT_EQ(cpu.iram(0x30), 0xFF);
  EXPECT_EQ(cpu.iram(0x40), 0x01);
  EXPECT_EQ(cpu.reg(0), 0x3F);
  steps(cpu, 2);
  EXPECT_EQ(cpu.dptr(), 0x1300);
}

TEST(Mcs51Arithmetic, MulAndDivSetOverflowAndClearCarry) {
  // Manual, MUL example: A=80 (50h), B=160 (A0h) → 12800 (3200h): A=00h, B=32h, OV=1, CY=0.
  Cpu cpu = with_code({0xD3, 0x74, 0x50, 0x75, 0xF0, 0xA0, 0xA4});
  steps(cpu, 4);
  EXPECT_EQ(cpu.a(), 0x00);
  EXPECT_EQ(cpu.b(), 0x32);
  EXPECT_EQ(cpu.psw() & 0x84, 0x04);
  // Manual, DIV example: A=251 (FBh), B=18 (12h) → A=13 (0Dh), B=17 (11h), OV=0, CY=0.
  Cpu d = with_code({0xD3, 0x74, 0xFB, 0x75, 0xF0, 0x12, 0x84});
  steps(d, 4);
  EXPECT_EQ(d.a(), 0x0D);
  EXPECT_EQ(d.b(), 0x11);
  EXPECT_EQ(d.psw() & 0x84, 0x00);
  // "If B had originally contained 00H ... OV will be set"; CY cleared.
  Cpu z = with_code({0xD3, 0x74, 0x07, 0x84});
  steps(z, 3);
  EXPECT_EQ(z.psw() & 0x84, 0x04);
}

TEST(Mcs51Arithmetic, DecimalAdjustAfterAdd) {
  // Manual, DA example: A=56h (BCD 56), R3=67h, CY=1: ADDC → BEh, DA → 24h, CY=1 (124).
  Cpu cpu = with_code({0xD3, 0x74, 0x56, 0x7B, 0x67, 0x3B, 0xD4});
  steps(cpu, 5);
  EXPECT_EQ(cpu.a(), 0x24);
  EXPECT_TRUE(cpu.psw() & 0x80);
  // Second example: 30 + 99 = 129 → A=29h, CY=1 (ADD A,#99h; DA).
  Cpu c = with_code({0x74, 0x30, 0x24, 0x99, 0xD4});
  steps(c, 3);
  EXPECT_EQ(c.a(), 0x29);
  EXPECT_TRUE(c.psw() & 0x80);
}

TEST(Mcs51Logic, AnlOrlXrlOnAccumulatorAndDirect) {
  // A=C3h ANL R0=55h → 41h; ORL 30h,#0Fh; XRL A,@R1.
  Cpu cpu = with_code({0x74, 0xC3, 0x78, 0x55, 0x58, 0x75, 0x30, 0xA0, 0x43, 0x30, 0x0F, 0x79, 0x30,
                       0x67, 0x62, 0x30});
  steps(cpu, 3);
  EXPECT_EQ(cpu.a(), 0x41);
  steps(cpu, 2);
  EXPECT_EQ(cpu.iram(0x30), 0xAF);
  steps(cpu, 2);  // MOV R1,#30h; XRL A,@R1
  EXPECT_EQ(cpu.a(), 0x41 ^ 0xAF);
  steps(cpu, 1);  // XRL 30h,A
  EXPECT_EQ(cpu.iram(0x30), 0x41);
}

TEST(Mcs51Logic, RotatesSwapClearAndComplement) {
  // A=C5h: RL → 8Bh, RR → C5h, RLC with CY=0 → 8Ah CY=1, RRC → C5h CY=0, SWAP → 5Ch,
  // CPL → A3h, CLR → 00h.
  Cpu cpu = with_code({0x74, 0xC5, 0x23, 0x03, 0xC3, 0x33, 0x13, 0xC4, 0xF4, 0xE4});
  steps(cpu, 2);
  EXPECT_EQ(cpu.a(), 0x8B);
  steps(cpu, 1);
  EXPECT_EQ(cpu.a(), 0xC5);
  steps(cpu, 2);
  EXPECT_EQ(cpu.a(), 0x8A);
  EXPECT_TRUE(cpu.psw() & 0x80);
  steps(cpu, 1);
  EXPECT_EQ(cpu.a(), 0xC5);
  EXPECT_FALSE(cpu.psw() & 0x80);
  steps(cpu, 1);
  EXPECT_EQ(cpu.a(), 0x5C);
  steps(cpu, 1);
  EXPECT_EQ(cpu.a(), 0xA3);
  steps(cpu, 1);
  EXPECT_EQ(cpu.a(), 0x00);
}

TEST(Mcs51Transfer, MovDirectDirectTakesTheSourceFirst) {
  // Encoding of MOV direct,direct: 85h, source, destination.
  Cpu cpu = with_code({0x75, 0x30, 0x5A, 0x85, 0x30, 0x31, 0x78, 0x31, 0xA6, 0x30, 0x86, 0x32, 0xE6,
                       0xF5, 0x40, 0xA8, 0x40, 0x88, 0x41});
  steps(cpu, 2);
  EXPECT_EQ(cpu.iram(0x31), 0x5A);
  steps(cpu, 3);  // MOV R0,#31h; MOV @R0,30h; MOV 32h,@R0
  EXPECT_EQ(cpu.iram(0x32), 0x5A);
  steps(cpu, 4);  // MOV A,@R0; MOV 40h,A; MOV R0,40h; MOV 41h,R0
  EXPECT_EQ(cpu.iram(0x41), 0x5A);
}

TEST(Mcs51Transfer, RegisterBanksFollowRs1Rs0AndIndirectReachesUpperRam) {
  // PSW.4..3 select bank 0..3 at 00h, 08h, 10h, 18h; @Ri reaches 80h..FFh (8052 RAM), direct
  // 80h..FFh is the SFRs.
  Cpu cpu = with_code({0x75, 0xD0, 0x18, 0x7F, 0x11, 0x78, 0x90, 0x76, 0x22, 0x75, 0x90, 0x00});
  steps(cpu, 4);
  EXPECT_EQ(cpu.iram(0x1F), 0x11);
  EXPECT_EQ(cpu.iram(0x90), 0x22);
  steps(cpu, 1);
  EXPECT_EQ(cpu.iram(0x90), 0x22);  // MOV 90h,#0 wrote P1, not RAM
  EXPECT_EQ(cpu.sfr_latch(sfr::P1), 0x00);
}

TEST(Mcs51Transfer, MovcMovxPushPopXchXchd) {
  // MOVC A,@A+PC reads the byte after the instruction + A; MOVX @Ri puts P2 on A15..A8.
  Cpu cpu = with_code({0x74, 0x01, 0x83, 0x00, 0x77,              // MOVC: code[4] = 77h
                       0x90, 0x12, 0x34, 0xF0,                    // MOVX @DPTR,A
                       0x75, 0xA0, 0x12, 0x78, 0x34, 0xE4, 0xE2,  // MOVX A,@R0
                       0xC0, 0xE0, 0xD0, 0x30,                    // PUSH ACC; POP 30h
                       0x79, 0x30, 0x74, 0x5A, 0xD7,              // XCHD A,@R1
                       0xC5, 0x30});                              // XCH A,30h
  steps(cpu, 2);
  EXPECT_EQ(cpu.a(), 0x77);
  EXPECT_EQ(cpu.pc(), 3);
  cpu.set_pc(5);
  steps(cpu, 2);
  EXPECT_EQ(cpu.xram(0x1234), 0x77);
  steps(cpu, 4);
  EXPECT_EQ(cpu.a(), 0x77);
  steps(cpu, 1);
  EXPECT_EQ(cpu.sp(), 0x08);
  EXPECT_EQ(cpu.iram(0x08), 0x77);
  steps(cpu, 1);
  EXPECT_EQ(cpu.sp(), 0x07);
  EXPECT_EQ(cpu.iram(0x30), 0x77);
  steps(cpu, 3);
  EXPECT_EQ(cpu.a(), 0x57);
  EXPECT_EQ(cpu.iram(0x30), 0x7A);
  steps(cpu, 1);
  EXPECT_EQ(cpu.a(), 0x7A);
  EXPECT_EQ(cpu.iram(0x30), 0x57);
}

TEST(Mcs51Boolean, BitAddressesMapToRamAndSfrs) {
  // Bits 00h..7Fh are 20h..2Fh, bits 80h.. are the SFRs at multiples of 8.
  Cpu cpu = with_code({0xD2, 0x00, 0xD2, 0x7F, 0xD2, 0xE7, 0xB2, 0x00, 0xA2, 0xE7,
                       0x92, 0x08, 0x82, 0x7F, 0xB0, 0x7F, 0x72, 0x00, 0xA0, 0x7F});
  steps(cpu, 3);
  EXPECT_EQ(cpu.iram(0x20), 0x01);
  EXPECT_EQ(cpu.iram(0x2F), 0x80);
  EXPECT_EQ(cpu.a(), 0x80);
  steps(cpu, 3);  // CPL 00h; MOV C,ACC.7; MOV 08h,C
  EXPECT_EQ(cpu.iram(0x20), 0x00);
  EXPECT_EQ(cpu.iram(0x21), 0x01);
  steps(cpu, 1);  // ANL C,7Fh: 1 and 1
  EXPECT_TRUE(cpu.psw() & 0x80);
  steps(cpu, 1);  // ANL C,/7Fh
  EXPECT_FALSE(cpu.psw() & 0x80);
  steps(cpu, 1);  // ORL C,00h (0)
  EXPECT_FALSE(cpu.psw() & 0x80);
  steps(cpu, 1);  // ORL C,/7Fh (0)
  EXPECT_FALSE(cpu.psw() & 0x80);
}

TEST(Mcs51Boolean, ReadModifyWriteReadsThePortLatchOthersThePins) {
  // Manual, "Read-Modify-Write Feature": ANL P1,A and friends read the latch; MOV A,P1 the pin.
  Cpu cpu = with_code({0xE5, 0x90, 0x63, 0x90, 0x00, 0xB2, 0x97});
  cpu.set_port_input(1, 0x0F);
  steps(cpu, 1);
  EXPECT_EQ(cpu.a(), 0x0F);
  steps(cpu, 1);  // XRL P1,#0: latch FFh stays FFh
  EXPECT_EQ(cpu.sfr_latch(sfr::P1), 0xFF);
  steps(cpu, 1);  // CPL P1.7 reads latch 1 → 0, although the pin reads 0
  EXPECT_EQ(cpu.sfr_latch(sfr::P1), 0x7F);
}

TEST(Mcs51Branch, JumpsCallsAndReturns) {
  // AJMP stays in the 2 KB page of the next instruction; ACALL/LCALL push PC low byte first.
  Cpu cpu = with_code({0x02, 0x08, 0x00});                                  // LJMP 0800h
  std::vector<std::uint8_t> at800 = {0x31, 0x10,                            // ACALL 0910h
                                     0x80, 0xFE};                           // SJMP $
  std::vector<std::uint8_t> at910 = {0x12, 0x20, 0x00,                      // LCALL 2000h
                                     0x22};                                 // RET
  std::vector<std::uint8_t> at2000 = {0x74, 0x02, 0x90, 0x30, 0x00, 0x73};  // JMP @A+DPTR
  std::vector<std::uint8_t> at3002 = {0x22};                                // RET
  cpu.load_code(0x0800, at800);
  cpu.load_code(0x0910, at910);
  cpu.load_code(0x2000, at2000);
  cpu.load_code(0x3002, at3002);
  steps(cpu, 2);
  EXPECT_EQ(cpu.pc(), 0x0910);
  EXPECT_EQ(cpu.sp(), 0x09);
  EXPECT_EQ(cpu.iram(0x08), 0x02);  // low byte of 0802h
  EXPECT_EQ(cpu.iram(0x09), 0x08);
  steps(cpu, 4);  // LCALL; MOV A; MOV DPTR; JMP @A+DPTR
  EXPECT_EQ(cpu.pc(), 0x3002);
  steps(cpu, 2);  // RET (to 0913h), RET (to 0802h)
  EXPECT_EQ(cpu.pc(), 0x0802);
  EXPECT_EQ(cpu.sp(), 0x07);
  steps(cpu, 1);  // SJMP $: rel FEh
  EXPECT_EQ(cpu.pc(), 0x0802);
}

TEST(Mcs51Branch, ConditionalJumpsCjneDjnzJbc) {
  // CJNE sets CY when the first operand is less; DJNZ jumps while not zero; JBC clears the bit.
  Cpu cpu = with_code({0x74, 0x10, 0xB4, 0x20, 0x00,  // CJNE A,#20h,+0: CY=1
                       0x78, 0x02, 0xD8, 0xFE,        // MOV R0,#2; DJNZ R0,$
                       0xD2, 0x05, 0x10, 0x05, 0x01,  // SETB 05h; JBC 05h,+1
                       0x00, 0x60, 0x01, 0x00,        // (skipped NOP); JZ +1 (A=10h: no)
                       0x70, 0x00});                  // JNZ +0
  steps(cpu, 2);
  EXPECT_TRUE(cpu.psw() & 0x80);
  EXPECT_EQ(steps(cpu, 3), 1u + 2u + 2u);
  EXPECT_EQ(cpu.reg(0), 0);
  EXPECT_EQ(cpu.pc(), 9);
  steps(cpu, 2);
  EXPECT_EQ(cpu.iram(0x20), 0x00);
  EXPECT_EQ(cpu.pc(), 15);
  steps(cpu, 1);
  EXPECT_EQ(cpu.pc(), 17);
}

}  // namespace
}  // namespace mcs51::test

// Timers, serial port, interrupts, idle and power-down against the Intel MCS-51 User's Manual
// ("Hardware Description of the 8051, 8052 and 80C51"), with the sampling rule of docs/cpu.md.
#include <gtest/gtest.h>

#include <vector>

#include "mcs51_test_util.hpp"

namespace mcs51::test {
namespace {

// A routine at `vector`: INC R7; RETI.
void isr_counting_r7(Cpu& cpu, std::uint16_t vector) {
  std::vector<std::uint8_t> isr = {0x0F, 0x32};
  cpu.load_code(vector, isr);
}

TEST(Mcs51Timers, Mode1CountsMachineCyclesAndSetsTf0OnOverflow) {
  // MOV TMOD,#01h; MOV TL0,#FFh; MOV TH0,#FFh; SETB TR0; NOP. TR0 arrives at the end of SETB's
  // cycle (docs/cpu.md), so the first count is in NOP's cycle: FFFFh → 0000h, TF0.
  Cpu cpu = with_code({0x75, 0x89, 0x01, 0x75, 0x8A, 0xFF, 0x75, 0x8C, 0xFF, 0xD2, 0x8C, 0x00});
  steps(cpu, 4);
  EXPECT_EQ(cpu.sfr_latch(sfr::TL0), 0xFF);
  EXPECT_FALSE(cpu.sfr_latch(sfr::TCON) & 0x20);
  steps(cpu, 1);
  EXPECT_EQ(cpu.cycles(), 8u);
  EXPECT_EQ(cpu.sfr_latch(sfr::TL0), 0x00);
  EXPECT_EQ(cpu.sfr_latch(sfr::TH0), 0x00);
  EXPECT_TRUE(cpu.sfr_latch(sfr::TCON) & 0x20);
}

TEST(Mcs51Timers, Mode0Is13BitsMode2ReloadsMode3SplitsTimer0) {
  // Mode 0: TL1's low 5 bits carry into TH1. TL1=1Fh, TH1=00h: one count → TL1=00h, TH1=01h.
  Cpu m0 = with_code({0x75, 0x8B, 0x1F, 0xD2, 0x8E, 0x00});  // MOV TL1,#1Fh; SETB TR1; NOP
  steps(m0, 3);
  EXPECT_EQ(m0.sfr_latch(sfr::TL1), 0x00);
  EXPECT_EQ(m0.sfr_latch(sfr::TH1), 0x01);
  // Mode 2: TL0 FFh overflows, reloads from TH0 (80h), TF0 set.
  Cpu m2 = with_code({0x75, 0x89, 0x02, 0x75, 0x8C, 0x80, 0x75, 0x8A, 0xFF, 0xD2, 0x8C, 0x00});
  steps(m2, 5);
  EXPECT_EQ(m2.sfr_latch(sfr::TL0), 0x80);
  EXPECT_TRUE(m2.sfr_latch(sfr::TCON) & 0x20);
  // Mode 3: TH0 counts under TR1 and sets TF1; TL0 under TR0.
  Cpu m3 = with_code({0x75, 0x89, 0x03, 0x75, 0x8C, 0xFF, 0xD2, 0x8E, 0x00});
  steps(m3, 4);
  EXPECT_EQ(m3.sfr_latch(sfr::TH0), 0x00);
  EXPECT_TRUE(m3.sfr_latch(sfr::TCON) & 0x80);
  EXPECT_EQ(m3.sfr_latch(sfr::TL0), 0x00);
}

TEST(Mcs51Timers, GateHoldsTimer0WhileInt0IsLowAndCounterModeCountsT0Edges) {
  // TMOD=09h (GATE, mode 1): with INT0 low the timer holds.
  Cpu g = with_code({0x75, 0x89, 0x09, 0xD2, 0x8C, 0x00, 0x00});
  g.set_int0(false);
  steps(g, 4);
  EXPECT_EQ(g.sfr_latch(sfr::TL0), 0x00);
  g.set_int0(true);
  steps(g, 1);
  EXPECT_EQ(g.sfr_latch(sfr::TL0), 0x01);
  // TMOD=05h (C/T, mode 1): one count per falling edge on T0 (P3.4), none for a steady pin.
  Cpu c = with_code({0x75, 0x89, 0x05, 0xD2, 0x8C, 0x00, 0x00, 0x00, 0x00});
  steps(c, 3);
  c.set_port_input(3, 0xEF);
  steps(c, 2);
  c.set_port_input(3, 0xFF);
  steps(c, 1);
  EXPECT_EQ(c.sfr_latch(sfr::TL0), 0x01);
}

TEST(Mcs51Timers, Timer2AutoReloadCaptureAndExternalFlag) {
  // RCAP2=FFFEh, TH2:TL2=FFFEh, TR2 (T2CON=04h): overflow every 2 cycles, reload, TF2.
  Cpu r = with_code({0x75, 0xCB, 0xFF, 0x75, 0xCA, 0xFE, 0x75, 0xCD, 0xFF, 0x75, 0xCC, 0xFE, 0x75,
                     0xC8, 0x04, 0x00, 0x00});
  steps(r, 7);  // two NOPs after MOV T2CON: FFFEh → FFFFh → overflow → FFFEh
  EXPECT_EQ(r.sfr_latch(sfr::TL2), 0xFE);
  EXPECT_EQ(r.sfr_latch(sfr::TH2), 0xFF);
  EXPECT_TRUE(r.sfr_latch(sfr::T2CON) & 0x80);
  // Capture mode (CP/RL2) with EXEN2: a falling edge on T2EX (P1.1) copies TH2:TL2 into
  // RCAP2 and sets EXF2. T2CON = 0Dh: EXEN2, TR2, CP/RL2.
  Cpu c = with_code({0x75, 0xC8, 0x0D, 0x00, 0x00, 0x00});
  steps(c, 2);  // MOV T2CON (TR2 arrives at its end); NOP: TL2 = 1
  c.set_port_input(1, 0xFD);
  steps(c, 1);  // TL2 = 2, then the capture in the same cycle
  EXPECT_EQ(c.sfr_latch(sfr::RCAP2L), 0x02);
  EXPECT_TRUE(c.sfr_latch(sfr::T2CON) & 0x40);
}

TEST(Mcs51Interrupts, AFlagSetInTheLastCycleIsServedAfterTheNextInstruction) {
  // IE=82h (EA, ET0), TMOD=01h, TH0:TL0=FFFFh, SETB TR0, NOP: overflow in the NOP's only
  // cycle C. Sampled in C, polled in C+1 (the next NOP's last cycle): the LCALL follows that NOP
  // (manual: "the samples are polled during the following machine cycle").
  Cpu cpu = with_code({0x75, 0xA8, 0x82, 0x75, 0x89, 0x01, 0x75, 0x8A, 0xFF, 0x75, 0x8C, 0xFF, 0xD2,
                       0x8C, 0x00, 0x00, 0x00},
                      0x30);
  isr_counting_r7(cpu, 0x000B);
  steps(cpu, 6);
  EXPECT_TRUE(cpu.sfr_latch(sfr::TCON) & 0x20);
  std::uint64_t c = cpu.cycles();
  EXPECT_EQ(cpu.step().kind, StepKind::instruction);  // the NOP
  StepResult call = cpu.step();
  EXPECT_EQ(call.kind, StepKind::interrupt);
  EXPECT_EQ(call.cycles, 2u);  // the hardware LCALL: 2 machine cycles
  EXPECT_EQ(cpu.pc(), 0x000B);
  EXPECT_EQ(cpu.cycles(), c + 3);                 // 3 complete cycles from the flag to the routine
  EXPECT_FALSE(cpu.sfr_latch(sfr::TCON) & 0x20);  // TF0 cleared by the call
  EXPECT_EQ(cpu.iram(0x08), 0x40);                // return address 0040h, low byte first
  steps(cpu, 2);                                  // INC R7; RETI
  EXPECT_EQ(cpu.pc(), 0x0040);
  EXPECT_EQ(cpu.reg(7), 1);
  EXPECT_EQ(cpu.in_service(), 0);
}

TEST(Mcs51Interrupts, AFlagSetBeforeTheLastCycleIsServedAfterThisInstruction) {
  // TH0:TL0 = FFFEh, SETB TR0, MUL AB: overflow in MUL's second cycle → call after MUL.
  Cpu cpu = with_code({0x75, 0xA8, 0x82, 0x75, 0x89, 0x01, 0x75, 0x8A, 0xFE, 0x75, 0x8C, 0xFF, 0xD2,
                       0x8C, 0xA4, 0x00},
                      0x30);
  isr_counting_r7(cpu, 0x000B);
  steps(cpu, 6);
  EXPECT_EQ(cpu.pc(), 0x003F);
  EXPECT_EQ(cpu.step().kind, StepKind::interrupt);
}

TEST(Mcs51Interrupts, WritesToIeOrIpAndRetiHoldOffTheCallForOneInstruction) {
  // TF0 set by software with EA off; SETB EA: one more instruction runs before the call.
  Cpu cpu = with_code({0x75, 0xA8, 0x02, 0xD2, 0x8D, 0x00, 0xD2, 0xAF, 0x00, 0x00}, 0x30);
  isr_counting_r7(cpu, 0x000B);
  steps(cpu, 4);  // MOV IE; SETB TF0; NOP; SETB EA
  EXPECT_EQ(cpu.step().kind, StepKind::instruction);
  EXPECT_EQ(cpu.step().kind, StepKind::interrupt);
  // RETI with TF0 set again inside the routine: one main-program instruction between calls.
  std::vector<std::uint8_t> isr = {0xD2, 0x8D, 0x32};  // SETB TF0; RETI
  cpu.load_code(0x000B, isr);
  steps(cpu, 2);
  EXPECT_EQ(cpu.pc(), 0x0039);
  EXPECT_EQ(cpu.step().kind, StepKind::instruction);
  EXPECT_EQ(cpu.step().kind, StepKind::interrupt);
}

TEST(Mcs51Interrupts, PrioritiesAndPollingOrder) {
  // TCON=23h: TF0 and IE0 (edge mode) pending; IP=02h: timer 0 high. The high one is called
  // first; the low IE0 waits until RETI and one more instruction; a high request preempts the
  // low routine, a low one never preempts a routine in service.
  Cpu cpu = with_code({0x75, 0x88, 0x23, 0x75, 0xB8, 0x02, 0x75, 0xA8, 0x83, 0x00, 0x00}, 0x30);
  std::vector<std::uint8_t> low = {0xD2, 0x8D, 0x00, 0x00, 0x32};  // SETB TF0; NOP; NOP; RETI
  cpu.load_code(0x0003, low);
  isr_counting_r7(cpu, 0x000B);
  steps(cpu, 4);
  EXPECT_EQ(cpu.step().kind, StepKind::interrupt);
  EXPECT_EQ(cpu.pc(), 0x000B);
  EXPECT_EQ(cpu.in_service(), 2);
  EXPECT_EQ(cpu.step().kind, StepKind::instruction);  // INC R7: IE0 cannot interrupt
  EXPECT_EQ(cpu.step().kind, StepKind::instruction);  // RETI to 003Ah
  EXPECT_EQ(cpu.step().kind, StepKind::instruction);  // the NOP at 003Ah
  EXPECT_EQ(cpu.step().kind, StepKind::interrupt);
  EXPECT_EQ(cpu.pc(), 0x0003);
  EXPECT_EQ(cpu.in_service(), 1);
  EXPECT_EQ(cpu.step().kind, StepKind::instruction);  // SETB TF0 in its last cycle
  EXPECT_EQ(cpu.step().kind, StepKind::instruction);  // NOP: the poll sees TF0
  EXPECT_EQ(cpu.step().kind, StepKind::interrupt);
  EXPECT_EQ(cpu.pc(), 0x000B);
  EXPECT_EQ(cpu.in_service(), 3);
  steps(cpu, 2);  // INC R7; RETI: back in the low routine
  EXPECT_EQ(cpu.pc(), 0x0006);
  EXPECT_EQ(cpu.in_service(), 1);
  EXPECT_EQ(cpu.reg(7), 2);
}

TEST(Mcs51Interrupts, Int0EdgeLatchesLevelFollowsThePin) {
  // IT0=1: a falling edge sets IE0, the call clears it.
  Cpu e = with_code({0x75, 0x88, 0x01, 0x75, 0xA8, 0x81, 0x00, 0x00, 0x00, 0x00}, 0x30);
  isr_counting_r7(e, 0x0003);
  steps(e, 2);
  e.set_int0(false);
  steps(e, 2);  // NOP (edge seen), NOP (polled)
  EXPECT_TRUE(e.sfr_latch(sfr::TCON) & 0x02);
  EXPECT_EQ(e.step().kind, StepKind::interrupt);
  EXPECT_FALSE(e.sfr_latch(sfr::TCON) & 0x02);
  steps(e, 2);  // INC R7; RETI: the pin is still low but no new edge
  EXPECT_EQ(e.step().kind, StepKind::instruction);
  EXPECT_EQ(e.step().kind, StepKind::instruction);
  // IT0=0: a low pin requests again after every RETI (plus one instruction), until it rises.
  Cpu l = with_code({0x75, 0xA8, 0x81, 0x00, 0x00, 0x00, 0x00, 0x00}, 0x30);
  isr_counting_r7(l, 0x0003);
  steps(l, 1);
  l.set_int0(false);
  steps(l, 2);
  EXPECT_EQ(l.step().kind, StepKind::interrupt);
  steps(l, 3);  // INC R7; RETI; NOP
  EXPECT_EQ(l.step().kind, StepKind::interrupt);
  l.set_int0(true);
  steps(l, 2);
  EXPECT_FALSE(l.sfr_latch(sfr::TCON) & 0x02);
  EXPECT_EQ(l.reg(7), 2);
}

// 11.0592 MHz, timer 1 mode 2 with TH1 = FDh, SMOD = 0: 9600 baud, a bit is 96 machine cycles.
Cpu uart_9600(std::initializer_list<std::uint8_t> tail) {
  std::vector<std::uint8_t> code = {0x75, 0x89, 0x20, 0x75, 0x8D, 0xFD, 0x75,
                                    0x8B, 0xFD, 0x75, 0x98, 0x50, 0xD2, 0x8E};
  code.insert(code.end(), tail);
  Cpu cpu;
  cpu.load_code(0, code);
  return cpu;
}

TEST(Mcs51Serial, Mode1SendsTenBitTimesPerCharacterAt9600Baud) {
  // MOV SBUF,#55h; wait for TI (JNB TI,$); CLR TI; MOV SBUF,#AAh; JNB TI,$.
  Cpu cpu = uart_9600({0x75, 0x99, 0x55, 0x30, 0x99, 0xFD, 0xC2, 0x99, 0x75, 0x99, 0xAA, 0x30, 0x99,
                       0xFD, 0x80, 0xFE});
  std::vector<std::pair<std::uint8_t, std::uint64_t>> sent;
  cpu.on_serial_tx = [&](std::uint8_t d, bool, std::uint64_t c) { sent.emplace_back(d, c); };
  std::uint64_t written = 0;
  while (sent.size() < 2 && cpu.cycles() < 10000) {
    if (cpu.pc() == 0x0E) written = cpu.cycles() + 2;
    cpu.step();
  }
  ASSERT_EQ(sent.size(), 2u);
  EXPECT_EQ(sent[0].first, 0x55);
  EXPECT_EQ(sent[1].first, 0xAA);
  // TI as the stop bit begins: 9 bit times after the start bit, which waits for a boundary.
  EXPECT_GT(sent[0].second, written + 9 * 96 - 1);
  EXPECT_LE(sent[0].second, written + 10 * 96);
  // Written at once after TI, the next character starts as the stop bit ends: 10 bit times.
  EXPECT_EQ(sent[1].second - sent[0].second, 10u * 96u);
}

TEST(Mcs51Serial, Mode1ReceivesWithRiAtTheStopBitAndSm2NeedsAStopBit) {
  Cpu cpu = uart_9600({0x80, 0xFE});
  steps(cpu, 5);
  std::uint64_t start = cpu.cycles();
  cpu.serial_receive(0xC3, true);
  while (!(cpu.sfr_latch(sfr::SCON) & 0x01) && cpu.cycles() < start + 2000) cpu.step();
  // 9.5 bit times = 912 cycles, to within one 16x tick (6 cycles) and one instruction.
  EXPECT_GE(cpu.cycles(), start + 912 - 6);
  EXPECT_LE(cpu.cycles(), start + 912 + 8);
  EXPECT_EQ(cpu.sfr_latch(sfr::SBUF), 0xC3);
  EXPECT_TRUE(cpu.sfr_latch(sfr::SCON) & 0x04);  // RB8: the stop bit
  // SM2=1 (SCON=70h) and a stop bit of 0: no RI.
  Cpu m = uart_9600({0x75, 0x98, 0x70, 0x80, 0xFE});
  steps(m, 6);
  m.serial_receive(0x11, false);
  m.run(2000);
  EXPECT_FALSE(m.sfr_latch(sfr::SCON) & 0x01);
}

TEST(Mcs51Serial, Mode2IsOsc64PerBit) {
  // SCON=80h (mode 2), SMOD=0: a bit is 64 clocks, 16/3 machine cycles; TI after 10 bits
  // (start, 8 data, TB8) from the first bit boundary after the write.
  Cpu cpu = with_code({0x75, 0x98, 0x80, 0x75, 0x99, 0x12, 0x80, 0xFE});
  std::uint64_t at = 0;
  cpu.on_serial_tx = [&](std::uint8_t, bool, std::uint64_t c) { at = c; };
  cpu.run(200);
  ASSERT_NE(at, 0u);
  EXPECT_GE(at * 12, 2u * 12 + 10 * 64);
  EXPECT_LE(at * 12, 2u * 12 + 11 * 64 + 12);
}

TEST(Mcs51PowerSaving, IdleEndsWithAnInterruptPowerDownOnlyWithReset) {
  // Timer 0 mode 2 from 00h; ORL PCON,#01h stops the CPU with TL0 = 02h (counted in the ORL's
  // two cycles): 254 idle cycles to the overflow, one more to poll it; the call ends idle and
  // RETI returns after the ORL.
  Cpu cpu = with_code(
      {0x75, 0x89, 0x02, 0x75, 0xA8, 0x82, 0xD2, 0x8C, 0x43, 0x87, 0x01, 0x00, 0x80, 0xFE}, 0x30);
  isr_counting_r7(cpu, 0x000B);
  steps(cpu, 4);
  EXPECT_TRUE(cpu.idle());
  EXPECT_EQ(cpu.sfr_latch(sfr::TL0), 0x02);
  unsigned idle_steps = 0;
  StepResult r{};
  while ((r = cpu.step()).kind == StepKind::idle) ++idle_steps;
  EXPECT_EQ(idle_steps, 255u);
  EXPECT_EQ(r.kind, StepKind::interrupt);
  EXPECT_FALSE(cpu.idle());
  steps(cpu, 2);
  EXPECT_EQ(cpu.pc(), 0x003B);
  // ORL PCON,#02h: power-down; nothing counts, only reset leaves it.
  Cpu pd = with_code({0x75, 0x89, 0x01, 0xD2, 0x8C, 0x43, 0x87, 0x02, 0x00});
  steps(pd, 3);
  std::uint8_t tl0 = pd.sfr_latch(sfr::TL0);
  EXPECT_TRUE(pd.powered_down());
  EXPECT_EQ(pd.step().kind, StepKind::power_down);
  pd.run(100);
  EXPECT_EQ(pd.sfr_latch(sfr::TL0), tl0);
  pd.reset();
  EXPECT_FALSE(pd.powered_down());
  EXPECT_EQ(pd.step().kind, StepKind::instruction);
}

TEST(Mcs51PowerSaving, ACallAcceptedAfterTheInstructionThatSetsIdleEndsIdle) {
  // INT0 low (level-triggered) and enabled; ORL PCON,#01h sets IDL while the request is pending:
  // the call follows the ORL and ends idle ("the activation of any enabled interrupt will cause
  // PCON.0 to be cleared by hardware"), so the routine (INC R7; RETI) runs and returns to SJMP $.
  Cpu cpu = with_code({0x75, 0xA8, 0x81, 0x43, 0x87, 0x01, 0x80, 0xFE}, 0x30);
  isr_counting_r7(cpu, 0x0003);
  cpu.set_int0(false);
  steps(cpu, 2);
  EXPECT_TRUE(cpu.idle());
  EXPECT_EQ(cpu.step().kind, StepKind::interrupt);
  EXPECT_FALSE(cpu.idle());
  cpu.set_int0(true);
  steps(cpu, 2);
  EXPECT_EQ(cpu.reg(7), 1);
  EXPECT_EQ(cpu.pc(), 0x0036);
}

TEST(Mcs51PowerSaving, RunWithinGivesWhatStepByStepGives) {
  // Cpu::run_within (the 80C32 board's run between chip events) defers idle cycles, serial mode 0
  // with nothing to shift and a level-triggered INT0 whose flag follows its low pin: the state
  // after it must be the state step() gives at the same cycle. Timer 0 mode 1 reloaded to F000h
  // by its routine (INC R7; MOV TH0,#F0h; RETI), the CPU idling in between; INT0 held low with
  // EX0 off (IE0 set, never called).
  auto make = [] {
    Cpu cpu = with_code(
        {0x75, 0x89, 0x01, 0x75, 0xA8, 0x82, 0xD2, 0x8C, 0x43, 0x87, 0x01, 0x80, 0xFB}, 0x30);
    cpu.load_code(0x000B, std::vector<std::uint8_t>{0x0F, 0x75, 0x8C, 0xF0, 0x32});
    cpu.set_int0(false);
    return cpu;
  };
  Cpu bulk = make();
  Cpu one = make();
  for (std::uint64_t end : {3u, 100u, 4'000u, 20'000u, 70'001u}) {
    bulk.run_within(end);
    EXPECT_LE(bulk.cycles(), end);
    while (one.cycles() < bulk.cycles()) one.step();
    ASSERT_EQ(one.cycles(), bulk.cycles());
    EXPECT_EQ(one.pc(), bulk.pc());
    EXPECT_EQ(one.reg(7), bulk.reg(7));
    EXPECT_EQ(one.idle(), bulk.idle());
    for (std::uint8_t r : {sfr::TL0, sfr::TH0, sfr::TCON, sfr::SP})
      EXPECT_EQ(one.sfr_latch(r), bulk.sfr_latch(r)) << int{r} << " at " << end;
  }
  // Counting from cycle 5 (after SETB TR0): overflows near 65 541 and 69 637, the next past 70 001.
  EXPECT_EQ(bulk.reg(7), 2);
}

}  // namespace
}  // namespace mcs51::test

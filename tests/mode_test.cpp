// Mode_Reg0/1/2, Start / Go_Offline, Status_Reg, user timer, RAM access violation, profile layout.
#include <gtest/gtest.h>

#include <array>
#include <limits>
#include <stdexcept>

#include "dpc31/reg_ids.hpp"
#include "harness.hpp"
#include "responder.hpp"
#include "test_util.hpp"

using namespace dpc31;
using testutil::bus_read16;
using testutil::bus_write16;
using testutil::user_go_offline;
using testutil::user_leave_master;
using testutil::user_start;

namespace {

class Mode : public testutil::ChipTest {};

}  // namespace

TEST_P(Mode, StartAndGoOffline) {
  Chip c = make();
  const std::uint16_t release = GetParam().profile == Profile::vpc3plus ? 0xC000 : 0x0000;
  EXPECT_EQ(bus_read16(c, 0x04, 16), release);  // Offline, Wait_Prm, Baud_Search, 12M code 0
  user_start(c);                                // Start_SPC3 (dpc31: MAC_Start)
  EXPECT_TRUE(c.started());
  EXPECT_EQ(c.peek_reg(RegId::Status_Reg), release | 0x0001);  // Passive_Idle
  // Power-on clear of the outputs raised DX_Out at the cycle Start completed.
  EXPECT_EQ(c.peek_reg(RegId::Int_Req_Reg), irq::DX_Out);
  harness::asic_prm_received(c);
  EXPECT_EQ(c.read(0x0E), 0x00);  // Prm OK: Wait_Cfg
  EXPECT_EQ(c.peek_reg(RegId::Status_Reg), release | 0x0011);
  user_go_offline(c);  // Go_Offline (MAC_Stop): the DP state machine back to its reset state
  EXPECT_FALSE(c.started());
  EXPECT_EQ(c.peek_reg(RegId::Status_Reg), release);
  EXPECT_EQ(c.peek_reg(RegId::Int_Req_Reg) & (irq::DX_Out | irq::MAC_Reset),
            irq::DX_Out | irq::MAC_Reset);
  // Go_Offline stays, Start_SPC3 cleared; the DPC31's Mode_Reg1 has neither (requests).
  const bool dpc31 = GetParam().profile == Profile::dpc31;
  EXPECT_EQ(c.peek_reg(RegId::Mode_Reg1), dpc31 ? 0x00 : 0x04);
  user_start(c);  // Start again clears Go_Offline
  EXPECT_EQ(c.peek_reg(RegId::Mode_Reg1), dpc31 ? 0x00 : 0x01);
  EXPECT_TRUE(c.started());
}

// Start_SPC3 and Go_Offline in one Mode_Reg1_S write (docs/timing.md, "Start and Go_Offline in
// one write": Start first, then Go_Offline; Go_Offline "stays 1 until the next Start"): the chip
// Offline with MAC_Reset, and Mode_Reg1 as after a Start then a Go_Offline, 04h (the VPC3+ reads
// it back at 15h).
TEST_P(Mode, StartAndGoOfflineInOneWriteEndsAsStartThenGoOffline) {
  if (GetParam().profile == Profile::dpc31) return;  // requests, not Mode_Reg1 bits (below)
  Chip c = make();
  c.write(static_cast<std::uint32_t>(c.addr_of(RegId::Mode_Reg1_S)), 0x05);
  EXPECT_FALSE(c.started());
  EXPECT_NE(c.peek_reg(RegId::Int_Req_Reg) & irq::MAC_Reset, 0);
  EXPECT_EQ(c.peek_reg(RegId::Mode_Reg1), 0x04);
  if (GetParam().profile == Profile::vpc3plus) {
    EXPECT_EQ(c.read(0x15) & 0x80, 0x00);
  }
  user_start(c);  // the next Start clears it
  EXPECT_EQ(c.peek_reg(RegId::Mode_Reg1), 0x01);
}

// Mode bits the model stores but does not act on are UNIMP (docs/registers.md; docs/decisions.md,
// "The twenty-ninth session: s29-chip"): Mode_Reg0 MinTSDR (bit 3), Early_Rdy (5),
// Spec_Prm_Buf_Mode (12); on the VPC3+ Mode_Reg2 DX_Int_Port, SYNC_Ena, SYNC_Pol (3..5) and
// Mode_Reg1's En_Chk_SSAP (7, set and cleared through Mode_Reg1_S / _R). A write of 1 to one is
// logged, as a read while one is 1; a write that leaves them 0 is not, so a driver's standard
// set-up logs nothing.
TEST_P(Mode, UnmodelledModeBitsAreLoggedWhenWrittenAsOne) {
  Chip c = make();
  const auto logged = [&](const std::string& what) {
    return log_.count_containing(what + " stored, behaviour not modelled");
  };
  const auto write = [&](RegId id, std::uint8_t v) {
    c.write(static_cast<std::uint32_t>(c.addr_of(id)), v);
  };
  Responder user(ResponderConfig{});
  DirectBus bus(c);
  user.init(bus);
  EXPECT_EQ(log_.count_containing("behaviour not modelled"), 0u);
  user_go_offline(c);  // Mode_Reg0 is written Offline
  for (const auto& [bit, name] : {std::pair{0x0008, "MinTSDR"}, std::pair{0x0020, "Early_Rdy"},
                                  std::pair{0x1000, "Spec_Prm_Buf_Mode"}}) {
    bus_write16(c, 0x06, 16, static_cast<std::uint16_t>(bit));
    EXPECT_EQ(logged(std::string("Mode_Reg0: ") + name), 1u);
    EXPECT_EQ(c.peek_reg(RegId::Mode_Reg0), bit);  // stored
    bus_write16(c, 0x06, 16, 0x0000);
    log_.clear();
  }
  bus_write16(c, 0x06, 16, 0x0000);
  EXPECT_EQ(log_.count_containing("behaviour not modelled"), 0u);
  if (GetParam().profile != Profile::vpc3plus) return;
  write(RegId::Mode_Reg2, 0x38);
  EXPECT_EQ(logged("Mode_Reg2: DX_Int_Port, SYNC_Ena, SYNC_Pol"), 1u);
  write(RegId::Mode_Reg2, 0x05);  // clears them (a change, logged); GC_Int_Mode, DX_Int_Mode
  log_.clear();
  write(RegId::Mode_Reg2, 0x05);
  EXPECT_EQ(log_.count_containing("behaviour not modelled"), 0u);
  write(RegId::Mode_Reg1_S, 0x80);  // En_Chk_SSAP set
  EXPECT_EQ(logged("Mode_Reg1_S: En_Chk_SSAP"), 1u);
  EXPECT_EQ(c.read(0x15) & 0x80, 0x80);  // read back
  EXPECT_EQ(log_.count_containing("read of Mode_Reg1: behaviour not modelled"), 1u);
  write(RegId::Mode_Reg1_R, 0x80);  // and cleared
  EXPECT_EQ(logged("Mode_Reg1_R: En_Chk_SSAP"), 1u);
  log_.clear();
  EXPECT_EQ(c.read(0x15) & 0x80, 0x00);
  write(RegId::Mode_Reg1_S, 0x02);  // EOI: no UNIMP bit
  EXPECT_EQ(log_.count_containing("behaviour not modelled"), 0u);
  // With En_Chk_SSAP set, a port's other writes (each EOI, each Res_User_WD) do not write it:
  // only its set once, no line per EOI (the review of the twenty-ninth session).
  write(RegId::Mode_Reg1_S, 0x80);
  log_.clear();
  for (int i = 0; i < 3; ++i) write(RegId::Mode_Reg1_S, 0x22);  // EOI, Res_User_WD
  write(RegId::Mode_Reg1_R, 0x10);                              // En_Change_Cfg_Buffer reset
  EXPECT_EQ(log_.count_containing("behaviour not modelled"), 0u);
}

// The DPC31 starts, stops and leaves the master through its Instruction_Queue (DPC31 p.22,
// Table 5.1-3; docs/dpc31.md): the SPC3's Start_SPC3, Go_Offline, User_Leave_Master and
// Res_User_WD bits of Mode_Reg1_S do nothing there, and a written 1 is logged at debug level.
TEST(ModeDpc31, ModeReg1StartStopBitsAreIgnored) {
  Chip c({Profile::dpc31});
  testutil::LogCapture log;
  log.attach(c);
  c.write(0x08, 0x01);  // Start_SPC3
  EXPECT_FALSE(c.started());
  EXPECT_EQ(c.peek_reg(RegId::Mode_Reg1), 0x00);
  EXPECT_EQ(c.peek_reg(RegId::Int_Req_Reg), 0x0000);
  ASSERT_EQ(log.count_containing("Mode_Reg1_S: Start_SPC3 not changed by this register"), 1u);
  EXPECT_EQ(log.records.back().level, LogLevel::debug);
  user_start(c);
  c.write(0x08, 0x2C);  // Go_Offline, User_Leave_Master, Res_User_WD
  EXPECT_TRUE(c.started());
  EXPECT_EQ(c.peek_reg(RegId::Mode_Reg1), 0x00);
  EXPECT_EQ(c.peek_reg(RegId::Int_Req_Reg) & irq::MAC_Reset, 0);
  c.write(0x08, 0x12);  // EOI and En_Change_Cfg_Buffer still act
  EXPECT_EQ(c.peek_reg(RegId::Mode_Reg1), 0x10);
}

// The chip's time ends at Chip::kLastCycle, 2^62 - 1 (include/dpc31/chip.hpp): a step past it
// stops there instead of wrapping to 0 or reaching UINT64_MAX, where every timer that is off
// would fire (a step of UINT64_MAX cycles, the "no limit" of a caller, crashed the chip's buffer
// requests). A chip started there arms its timers beyond the end, and they do not wrap: its next
// steps end (the review's case: armed at UINT64_MAX - 1 + N, they wrapped, fired, re-armed,
// and a step of one cycle never ended).
TEST_P(Mode, TimeEndsAtTheLastCycleAStepPastItStopsThere) {
  constexpr std::uint64_t kLast = (std::uint64_t{1} << 62) - 1;
  static_assert(Chip::kLastCycle == kLast);
  Chip c = make();
  c.step(std::uint64_t{1} << 63);
  c.step(std::uint64_t{1} << 63);
  EXPECT_EQ(c.cycle(), kLast);
  EXPECT_FALSE(c.step_until_irq(std::numeric_limits<std::uint64_t>::max()));
  EXPECT_EQ(c.cycle(), kLast);
  Chip d = make();
  d.step(100);
  EXPECT_FALSE(d.step_until_irq(std::numeric_limits<std::uint64_t>::max() - 100));
  EXPECT_EQ(d.cycle(), kLast);
  EXPECT_EQ(d.read(0x3F0 & ((1u << d.profile().address_bits) - 1)), 0x00);  // RAM, cleared
  EXPECT_EQ(d.cycle(), kLast);
  user_start(d);  // Start_SPC3 (dpc31: MAC_Start): the baud search's and the user timer's deadlines
  d.write(0x08, 0x02);  // EOI: the inactive time
  d.step(1000);
  EXPECT_FALSE(d.step_until_irq(std::numeric_limits<std::uint64_t>::max()));
  EXPECT_EQ(d.cycle(), kLast);
}

// At the last cycle every access stops there, as a single one does (Chip::cycle_after): a
// block transfer's quiet run of RAM too, and so a Start after it and step_until_irq; the chip's
// snapshot there loads back (docs/timing.md, "Clock and time"; docs/decisions.md, "The
// thirty-first session: s31-reset").
TEST_P(Mode, AtTheLastCycleBlockTransfersAStartAndStepUntilIrqStopThere) {
  Chip c = make();
  c.step(std::numeric_limits<std::uint64_t>::max());  // no event: the end at once
  ASSERT_EQ(c.cycle(), Chip::kLastCycle);
  const auto ram = static_cast<std::uint32_t>(0x3F0 & ((1u << c.profile().address_bits) - 1));
  std::array<std::uint8_t, 8> bytes{1, 2, 3, 4, 5, 6, 7, 8};
  c.write_block(ram, bytes);
  EXPECT_EQ(c.cycle(), Chip::kLastCycle);
  c.read_block(ram, bytes);
  EXPECT_EQ(c.cycle(), Chip::kLastCycle);
  c.fill(ram, 0, bytes.size());
  EXPECT_EQ(c.cycle(), Chip::kLastCycle);
  EXPECT_TRUE(c.equal(ram, ram + 4, 4));
  EXPECT_EQ(c.cycle(), Chip::kLastCycle);
  user_start(c);
  EXPECT_EQ(c.cycle(), Chip::kLastCycle);
  EXPECT_FALSE(c.step_until_irq(10));
  EXPECT_EQ(c.cycle(), Chip::kLastCycle);
  Chip d = make();
  d.load_state(c.save_state());
  EXPECT_EQ(d.cycle(), Chip::kLastCycle);
}

TEST_P(Mode, ModeReg0OnlyWhileOffline) {
  Chip c = make();
  bus_write16(c, 0x06, 16, 0x0100);
  user_start(c);
  log_.clear();
  bus_write16(c, 0x06, 16, 0x0300);
  EXPECT_EQ(c.peek_reg(RegId::Mode_Reg0), 0x0100);
  EXPECT_EQ(log_.count_containing("while started"), 1u);  // only the byte that would change
}

TEST_P(Mode, UserTimerClockPeriods) {
  for (std::uint16_t base : {std::uint16_t{0}, std::uint16_t{0x0400}}) {
    Chip c = make();
    const std::uint64_t period = base != 0 ? 480000 : 48000;
    bus_write16(c, 0x06, 16, base);         // User_Time_Base; cycle 8
    const std::uint64_t s = user_start(c);  // Start_SPC3 at 12 (dpc31: MAC_Start, later)
    c.step(period - 1);
    EXPECT_EQ(c.peek_reg(RegId::Int_Req_Reg) & irq::User_Timer_Clock, 0);
    c.step(1);  // 12 + period
    EXPECT_NE(c.peek_reg(RegId::Int_Req_Reg) & irq::User_Timer_Clock, 0);
    bus_write16(c, 0x02, 16, irq::User_Timer_Clock);
    c.step(period - 8 - 1);  // one cycle before the second tick at s + 2 * period
    EXPECT_EQ(c.peek_reg(RegId::Int_Req_Reg) & irq::User_Timer_Clock, 0);
    c.step(1);
    EXPECT_NE(c.peek_reg(RegId::Int_Req_Reg) & irq::User_Timer_Clock, 0);
    EXPECT_EQ(c.cycle(), s + 2 * period);
    if (GetParam().profile != Profile::dpc31) {
      EXPECT_EQ(s, 12u);
    }
  }
}

TEST_P(Mode, UserLeaveMasterFromDataExchange) {
  Chip c = make();
  user_start(c);
  harness::asic_prm_received(c);
  EXPECT_EQ(c.read(0x0E), 0x00);  // User_Prm_Data_Okay: finished
  EXPECT_EQ(c.dp_state(), DpState::Wait_Cfg);
  harness::asic_cfg_received(c);
  EXPECT_EQ(c.read(0x10), 0x00);  // User_Cfg_Data_Okay
  EXPECT_EQ(c.dp_state(), DpState::Data_Exchange);
  EXPECT_EQ(c.peek_reg(RegId::Status_Reg) & 0x30, 0x20);
  bus_write16(c, 0x02, 16, 0xFFFF);
  user_leave_master(c);
  EXPECT_EQ(c.dp_state(), DpState::Wait_Prm);
  EXPECT_EQ(c.peek_reg(RegId::Int_Req_Reg), irq::Go_Leave_Data_Exchange | irq::DX_Out);
  EXPECT_EQ(c.peek_reg(RegId::Mode_Reg1) & 0x08, 0);  // the chip clears the bit
}

TEST_P(Mode, RamAccessViolation) {
  Chip c = make();
  const ProfileDesc& p = c.profile();
  if (p.violation_from == 0) {
    // dpc31: the whole 8 KB space is decoded; nothing wraps.
    c.write(0x1FFF, 0x5A);
    EXPECT_EQ(c.read(0x1FFF), 0x5A);
    EXPECT_EQ(c.peek_reg(RegId::Status_Reg) & 0x08, 0);
    return;
  }
  c.write(p.violation_from - 0x100, 0x11);  // a plain RAM byte
  user_start(c);
  const std::uint32_t wraps_to = p.violation_from + 0x100 - p.violation_subtract;  // plain RAM
  c.write(wraps_to, 0x77);
  log_.clear();
  EXPECT_EQ(c.read(p.violation_from + 0x100), 0x77);  // the access lands at address - subtract
  EXPECT_EQ(log_.count_containing("RAM access violation"), 1u);
  // A block past the RAM while Status bit 3 stands adds no line per byte (docs/decisions.md).
  std::vector<std::uint8_t> block(0x40);
  c.read_block(p.violation_from, block);
  EXPECT_EQ(block[0x10], c.read(p.violation_from + 0x10 - p.violation_subtract));
  EXPECT_EQ(log_.count_containing("RAM access violation"), 1u);
  EXPECT_NE(c.peek_reg(RegId::Status_Reg) & 0x08, 0);             // RAM_Access_Violation
  EXPECT_FALSE(c.started());                                      // forced Offline ...
  EXPECT_NE(c.peek_reg(RegId::Int_Req_Reg) & irq::MAC_Reset, 0);  // ... with MAC_Reset
  c.write(0x08, 0x01);                                            // Start clears the flag
  EXPECT_EQ(c.peek_reg(RegId::Status_Reg) & 0x08, 0);
  c.read(p.violation_from);  // ... and the next violation is logged again
  EXPECT_EQ(log_.count_containing("RAM access violation"), 2u);
}

// chip-facts.md §0: the VPC3+ has 2 KB, 4 KB with Mode_Reg2 bit 7 (4kB_Mode). In that mode
// 800h-FFFh is RAM like the rest: no log line for any of its bytes (audit a20, finding 5: one
// info line per byte before). Without the mode the access is the RAM access violation
// (docs/timing.md), one warning until Start clears Status bit 3, however many bytes follow.
TEST(Vpc3, FourKilobyteMode) {
  for (BusMode bus : {BusMode::intel, BusMode::motorola}) {
    Chip c({Profile::vpc3plus, bus});
    testutil::LogCapture log;
    log.attach(c);
    c.write(0x0C, 0x80);  // Mode_Reg2.4kB_Mode
    c.write(0x900, 0x42);
    c.write(0x100, 0x24);
    EXPECT_EQ(c.read(0x900), 0x42);  // a real upper 2 KB, no wrap
    EXPECT_EQ(c.peek_reg(RegId::Status_Reg) & 0x08, 0);
    std::vector<std::uint8_t> upper(0x800, 0x5A);
    c.write_block(0x800, upper);
    c.read_block(0x800, upper);
    for (std::uint32_t a = 0x800; a < 0x1000; ++a) c.write(a, c.read(a));
    EXPECT_EQ(upper, std::vector<std::uint8_t>(0x800, 0x5A));
    EXPECT_TRUE(log.records.empty()) << log.records.front().text;

    c.write(0x0C, 0x00);  // back to 2 KB: 900h wraps to 100h
    EXPECT_EQ(c.read(0x900), 0x24);
    c.write(0x901, 0x33);
    EXPECT_EQ(c.read(0x101), 0x33);
    ASSERT_EQ(log.records.size(), 1u);
    EXPECT_EQ(log.records[0].level, LogLevel::warn);
    EXPECT_EQ(log.records[0].text,
              "RAM access violation at 0x900: beyond the 2048 bytes of RAM, wraps to 0x100 "
              "(further ones are not logged until Start clears Status bit 3)");
    EXPECT_NE(c.peek_reg(RegId::Status_Reg) & 0x08, 0);
  }
}

// The debugger's back door never leaves a register and the chip disagreeing (audit s32
// siblings, finding 2; include/dpc31/chip.hpp, poke_reg). A poked Mode_Reg2.4kB_Mode is the
// mode, as the bus write's: 900h is RAM of its own, and a poke of 01h puts the 2 KB decode back
// (960h wraps to 160h, VPC3+ chip-facts.md §0). Before, the latch read 80h while 900h wrapped.
TEST(Vpc3, PokedFourKilobyteModeIsTheMode) {
  Chip c({Profile::vpc3plus, BusMode::intel});
  ASSERT_TRUE(c.poke_reg(RegId::Mode_Reg2, 0x80));
  c.write(0x900, 0x5A);
  EXPECT_EQ(c.peek(0x900), 0x5A);
  EXPECT_EQ(c.peek(0x100), 0x00);
  EXPECT_EQ(c.peek_reg(RegId::Status_Reg) & 0x08, 0);  // no RAM access violation
  ASSERT_TRUE(c.poke_reg(RegId::Mode_Reg2, 0x01));
  EXPECT_EQ(c.peek_reg(RegId::Mode_Reg2), 0x01);
  c.write(0x960, 0x55);
  EXPECT_EQ(c.peek(0x160), 0x55);
  EXPECT_NE(c.peek_reg(RegId::Status_Reg) & 0x08, 0);
}

// Mode_Reg1's Start_SPC3 and Go_Offline are the chip's run state, EOI and User_Leave_Master
// pulses: a poke that would change them is refused with the reason, nothing stored (a poked
// Start_SPC3 read 1 while the chip stayed Offline). Its other bits are the latch's own.
TEST_P(Mode, PokeOfModeReg1RunStateBitsIsRefused) {
  Chip c = make();
  for (const std::uint16_t bit : {0x01, 0x02, 0x04, 0x08}) {
    SCOPED_TRACE(bit);
    EXPECT_THROW(c.poke_reg(RegId::Mode_Reg1, bit), std::invalid_argument);
    EXPECT_EQ(c.peek_reg(RegId::Mode_Reg1), 0x00);
  }
  EXPECT_EQ(c.poke_reg_problem(RegId::Mode_Reg1, 0x01),
            "poke_reg Mode_Reg1 0x01: bits 0x01 would change; Start_SPC3 and Go_Offline are the "
            "chip's run state (Offline), EOI and User_Leave_Master pulses that never stay set: "
            "only a command changes them (Mode_Reg1_S / Mode_Reg1_R over the bus)");
  EXPECT_FALSE(c.started());
  EXPECT_TRUE(c.poke_reg(RegId::Mode_Reg1, 0x10));  // En_Change_Cfg_Buffer
  EXPECT_EQ(c.peek_reg(RegId::Mode_Reg1), 0x10);
  EXPECT_EQ(c.poke_reg_problem(RegId::Mode_Reg2, 0x80), "");
}

// The byte back door at Mode_Reg1's read-back (15h on the VPC3+ and the DPC31) keeps the same
// rule as poke_reg: Start_SPC3 / EOI poked there read 1 while Status_Reg said Offline.
TEST(ModeBackDoor, PokeAtModeReg1ReadBackKeepsTheRunStateRule) {
  for (const Profile p : {Profile::vpc3plus, Profile::dpc31}) {
    SCOPED_TRACE(static_cast<int>(p));
    Chip c({p, BusMode::intel});
    const auto a1 = static_cast<std::uint32_t>(c.addr_of(RegId::Mode_Reg1));
    ASSERT_EQ(a1, 0x15u);
    for (const std::uint8_t bits : {0x01, 0x02, 0x03}) {
      EXPECT_THROW(c.poke(a1, bits), std::invalid_argument);
      EXPECT_EQ(c.peek_reg(RegId::Mode_Reg1), 0x00);
      EXPECT_EQ(c.read(a1), 0x00);
    }
    EXPECT_EQ(c.poke_problem(a1, 0x03),
              "poke 0x0015 0x03: Mode_Reg1 0x03: bits 0x03 would change; Start_SPC3 and "
              "Go_Offline are the chip's run state (Offline), EOI and User_Leave_Master pulses "
              "that never stay set: only a command changes them (Mode_Reg1_S / Mode_Reg1_R over "
              "the bus)");
    EXPECT_FALSE(c.started());
    EXPECT_TRUE(c.poke(a1, 0x10));  // En_Change_Cfg_Buffer is the latch's own
    EXPECT_EQ(c.read(a1), 0x10);
    EXPECT_TRUE(c.poke_reg(RegId::Mode_Reg1, 0x00));
  }
  // Started by its command, the VPC3+ has Start_SPC3: a poke keeping it is taken, one clearing
  // it refused.
  Chip c({Profile::vpc3plus, BusMode::intel});
  c.write(static_cast<std::uint32_t>(c.addr_of(RegId::Mode_Reg1_S)), 0x01);
  ASSERT_TRUE(c.started());
  EXPECT_TRUE(c.poke(0x15, 0x11));
  EXPECT_THROW(c.poke(0x15, 0x10), std::invalid_argument);
  EXPECT_EQ(c.peek_reg(RegId::Mode_Reg1), 0x11);
}

TEST_P(Mode, GcCommandPreset) {
  Chip c = make();
  const RegDesc* r = find_reg(c.profile(), "R_GC_Command");
  EXPECT_EQ(c.read(static_cast<std::uint32_t>(r->read_addr)),
            GetParam().profile == Profile::dpc31 ? 0xFF : 0x00);
}

INSTANTIATE_TEST_SUITE_P(Chips, Mode, ::testing::ValuesIn(testutil::all_chip_params()),
                         testutil::param_name);

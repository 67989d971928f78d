// The interrupt controller as manual-quotes.md "Confirmed" and chip-facts §2 state it, driven
// only through the bus (events raised by writing Int_Req_Reg, which "is R/W (user may set events
// for test)" [S-IRR]) and observed on the X/INT pin with its cycle. docs/timing.md: an access
// takes 4 clocks and acts when it completes; X/INT follows in the same cycle; 1 us = 48 clocks,
// 1 ms = 48 000 at 48 MHz. Int_Req_Reg 00h/01h, Int_Ack_Reg 02h/03h, Int_Mask_Reg 04h/05h,
// Mode_Reg0 06h/07h, Mode_Reg1_S 08h (chip-facts §1.1, Intel: low byte first).
#include <utility>

#include "conformance.hpp"
#include "user_side.hpp"

using namespace dpc31;
using namespace conformance;

namespace {

class Interrupts : public ::testing::TestWithParam<Profile> {
 protected:
  Chip make() {
    Chip c({GetParam(), BusMode::intel, 0});
    c.set_log_sink(nullptr);
    c.on_irq_change([this](std::uint64_t at, bool active) { edges.emplace_back(at, active); });
    return c;
  }
  std::vector<std::pair<std::uint64_t, bool>> edges;
};

void w16(Chip& c, std::uint32_t a, std::uint16_t v) {
  testutil::bus_write16(c, static_cast<int>(a), 16, v);
}

}  // namespace

// manual-quotes.md Confirmed, SPC3 p.46 timing table (MIN = MAX = 1 us with EOI_Timebase 0):
// "After acknowledging an interrupt with EOI, a min. of 1 us or 1 ms is expected in SPC3 before
// a new interrupt is output." Unmask DX_Out and Diag_Buffer_Changed (writes complete at 4, 8);
// raise both (IRR low byte at 12, high at 16: X/INT active at 16, pin low); acknowledge one
// (20, 24: still active); EOI at 28: inactive at 28, active again at 28 + 48 = 76, not at 75.
TEST_P(Interrupts, EoiInactiveTime_Min1usBeforeNewInterrupt) {
  Chip c = make();
  w16(c, 0x04, static_cast<std::uint16_t>(~(irq::DX_Out | irq::Diag_Buffer_Changed)));
  w16(c, 0x00, irq::DX_Out | irq::Diag_Buffer_Changed);
  EXPECT_FALSE(c.x_int_pin());  // low-active
  w16(c, 0x02, irq::DX_Out);
  c.write(0x08, 0x02);  // EOI
  EXPECT_EQ(c.cycle(), 28u);
  EXPECT_TRUE(c.x_int_pin());
  c.step(47);
  EXPECT_TRUE(c.x_int_pin());  // cycle 75
  c.step(1);
  EXPECT_FALSE(c.x_int_pin());  // cycle 76
  const std::vector<std::pair<std::uint64_t, bool>> expect = {{16, true}, {28, false}, {76, true}};
  EXPECT_EQ(edges, expect);
}

// The same with EOI_Time_Base = 1 (Mode_Reg0 bit 9, "1 ms" in the SPC3 p.46 table): Mode_Reg0
// written at 4/8, unmask at 12/16, raise at 20/24 (active at 24), EOI at 28: active again at
// 28 + 48 000 = 48 028.
TEST_P(Interrupts, EoiInactiveTime_Min1msWithEoiTimeBase1) {
  Chip c = make();
  w16(c, 0x06, 0x0200);
  w16(c, 0x04, static_cast<std::uint16_t>(~irq::New_GC_Command));
  w16(c, 0x00, irq::New_GC_Command);
  c.write(0x08, 0x02);
  c.step(48'028 - 1 - c.cycle());
  EXPECT_TRUE(c.x_int_pin());
  c.step(1);
  EXPECT_FALSE(c.x_int_pin());
  const std::vector<std::pair<std::uint64_t, bool>> expect = {
      {24, true}, {28, false}, {48'028, true}};
  EXPECT_EQ(edges, expect);
}

// manual-quotes.md Confirmed, VPC3+S p.34: "If a new event and an acknowledge from the previous
// event are present at the IRR at the same time, the event remains stored." Start_SPC3 (the
// DPC31: MAC_Start) completes at s: User_Timer_Clock fires at s + 48 000 and again at
// s + 96 000. Its acknowledge completing at s + 96 000 (the cycle of the second tick) leaves the
// bit set; the one completing at s + 48 001 (one clock after the first tick) clears it.
TEST_P(Interrupts, NewEventAndAcknowledgeAtTheSameTime_EventRemainsStored) {
  Chip c = make();
  const std::uint64_t s = testutil::user_start(c);
  c.step(s + 48'001 - 4 - c.cycle());
  c.write(0x02, static_cast<std::uint8_t>(irq::User_Timer_Clock));  // completes at s + 48 001
  EXPECT_EQ(c.read(0x00) & irq::User_Timer_Clock, 0);               // cleared
  c.step(s + 96'000 - 4 - c.cycle());
  c.write(0x02, static_cast<std::uint8_t>(irq::User_Timer_Clock));  // completes at s + 96 000
  EXPECT_EQ(c.read(0x00) & irq::User_Timer_Clock, irq::User_Timer_Clock);  // kept
}

// manual-quotes.md Confirmed, SPC3 p.22: "Each interrupt event the processor processed must be
// deleted via the IAR (except for New_Prm_Data, New_DDB_Prm_Data, and New_Cfg_Data)." Every
// event bit of the profile, raised through Int_Req_Reg: a 1 written to Int_Ack_Reg clears it —
// except New_Prm_Data (11), New_Cfg_Data (10) and on the VPC3+ New_Ext_Prm_Data (6), which stay.
TEST_P(Interrupts, EachEventDeletedViaIar_ExceptNewPrmAndNewCfgData) {
  std::uint16_t events = 0x3F1F;  // SPC3 / DPC31: bits 13..8 and 4..0 (chip-facts §2.1)
  std::uint16_t kept = irq::New_Prm_Data | irq::New_Cfg_Data;
  if (GetParam() == Profile::vpc3plus) {
    events = 0xFFFF;
    kept |= irq::New_Ext_Prm_Data;
  }
  for (int bit = 0; bit < 16; ++bit) {
    const auto m = static_cast<std::uint16_t>(1u << bit);
    if ((events & m) == 0) continue;
    Chip c = make();
    w16(c, 0x00, m);
    ASSERT_EQ(irr(c), m) << bit;
    w16(c, 0x02, m);
    EXPECT_EQ(irr(c), (kept & m) != 0 ? m : 0) << bit;
  }
}

// ... the New_Prm_Data / New_Cfg_Data events of real telegrams are deleted by the user's
// verdict instead: the User_Prm_Data_Okay read (0Eh) and the User_Cfg_Data_Okay read (10h)
// (chip-facts §2.2 / §5.4), not by Int_Ack_Reg.
TEST_P(Interrupts, NewPrmAndNewCfgData_DeletedByTheVerdictReads) {
  Bare b(GetParam());
  ASSERT_TRUE(b.master.fdl_status().answer);
  // The event is set; Int_Ack_Reg (02h) leaves it; the verdict read (OK 00h) deletes it.
  const auto deleted_by_verdict = [&b](std::uint16_t event, std::uint32_t okay_addr) {
    ASSERT_NE(irr(b.chip) & event, 0);
    w16(b.chip, 0x02, event);
    EXPECT_NE(irr(b.chip) & event, 0);
    EXPECT_EQ(b.chip.read(okay_addr), 0x00);
    EXPECT_EQ(irr(b.chip) & event, 0);
  };
  b.master.set_prm();
  deleted_by_verdict(irq::New_Prm_Data, 0x0E);  // User_Prm_Data_Okay
  b.master.chk_cfg();
  deleted_by_verdict(irq::New_Cfg_Data, 0x10);  // User_Cfg_Data_Okay
}

// chip-facts §2.2 [S-IRR][S-VPC3S-INT]: "16 events latched in IRR independent of IMR. IR = IRR
// AND NOT IMR; the single X/INT output is the OR of IR bits. IMR: 1 = masked." Raise
// Baudrate_Detect and New_SSA_Data with all masked (reset FFFFh): IRR 0204h, IR 0, X/INT
// inactive; unmask New_SSA_Data: IR 0200h, active; mask it again: inactive, IRR unchanged.
TEST_P(Interrupts, IrIsIrrAndNotImr_XintIsTheOrOfIr) {
  Chip c = make();
  w16(c, 0x00, irq::Baudrate_Detect | irq::New_SSA_Data);
  EXPECT_EQ(irr(c), irq::Baudrate_Detect | irq::New_SSA_Data);
  EXPECT_EQ(testutil::bus_read16(c, 0x02, 16), 0);
  EXPECT_TRUE(c.x_int_pin());
  w16(c, 0x04, static_cast<std::uint16_t>(~irq::New_SSA_Data));
  EXPECT_EQ(testutil::bus_read16(c, 0x02, 16), irq::New_SSA_Data);
  EXPECT_FALSE(c.x_int_pin());
  w16(c, 0x04, 0xFFFF);
  EXPECT_TRUE(c.x_int_pin());
  EXPECT_EQ(irr(c), irq::Baudrate_Detect | irq::New_SSA_Data);
}

// chip-facts §2.2 / §4.1 [S-RU-SPC3]: "Mode_Reg0.bit4 INT_Pol: 0 = low-active (default), 1 =
// high-active." The same pending event gives X/INT low with INT_Pol 0 and high with INT_Pol 1.
TEST_P(Interrupts, IntPol0LowActive_1HighActive) {
  for (const bool high : {false, true}) {
    Chip c = make();
    if (high) w16(c, 0x06, 0x0010);
    EXPECT_EQ(c.x_int_pin(), !high);  // inactive
    w16(c, 0x04, static_cast<std::uint16_t>(~irq::DX_Out));
    w16(c, 0x00, irq::DX_Out);
    EXPECT_EQ(c.x_int_pin(), high);  // active
  }
}

// chip-facts §2.1 bit 4 / §4.1 bit 10 [S-IRR]: User_Timer_Clock "user time base elapsed (1 ms
// or 10 ms, Mode_Reg0.User_Time_Base)". Start completes at s: the events at s + 48 000 (base 0)
// or s + 480 000 (base 1), not one clock earlier.
TEST_P(Interrupts, UserTimerClock_Every1msOr10ms) {
  for (const bool ten : {false, true}) {
    Chip c = make();
    if (ten) w16(c, 0x06, 0x0400);
    const std::uint64_t s = testutil::user_start(c);
    const std::uint64_t p = ten ? 480'000 : 48'000;
    c.step(s + p - 1 - 4 - c.cycle());
    EXPECT_EQ(c.read(0x00) & irq::User_Timer_Clock, 0) << ten;  // completes at s + p - 1
    EXPECT_EQ(c.read(0x00) & irq::User_Timer_Clock, irq::User_Timer_Clock) << ten;  // s + p + 3
  }
}

INSTANTIATE_TEST_SUITE_P(Profiles, Interrupts, ::testing::ValuesIn(kAllProfiles),
                         [](const auto& i) { return testutil::pname(i.param); });

// Global_Control as seed 003 (DPC31 HW Description V1.0 p.32, Control_Command bits; p.33
// GC_Command and New_GC_Int mode) and manual-quotes.md "Confirmed" (DPC31 p.31) state it: Freeze,
// Unfreeze, reserved bits and Check_No_GC_Reserved, Sync_Supported = 0 / Freeze_Supported = 0,
// New_GC_Int mode, the GC_Command cell, Group_Select and the data length. (Clear_Data, Sync,
// Unsync, the fail-safe and the GC_Command presets are tested with their fixes, issue 13.)
#include <algorithm>
#include <string>

#include "conformance.hpp"
#include "user_side.hpp"

using namespace dpc31;
using namespace conformance;

namespace {

const Bytes kA = {0xA1, 0xA2, 0xA3, 0xA4};

class GlobalControl : public ::testing::TestWithParam<Profile> {};

std::uint8_t gc_command(Chip& c) { return c.read(rd(c, RegId::R_GC_Command)); }

// Diag St1 (byte 0) bit 4 Not_Supported; St2 (byte 1) bit 4 Freeze_Mode; byte 3 Master_Add.
Bytes diag(DpMaster& m) {
  const Exchange d = m.slave_diag();
  return d.answer ? d.answer->du : Bytes{};
}

// A Global_Control with `du` as its data (any length), SDN to 127 from master `sa`.
Exchange gc_raw(DpMaster& m, Bytes du, std::uint8_t sa = 2) {
  return m.transact(fdl::make_frame(fdl::kBroadcast, sa,
                                    fdl::make_request_fc(fdl::Function::SDN_high, false, false),
                                    std::move(du), dsap::Global_Control, dsap::Master));
}

// The profile's "do not check the reserved bits" option, set through the bus: DPC31 Param_Reg
// bit 1 Check_No_GC_Reserved (seed 003); VPC3+ Mode_Reg2 bit 1 No_Check_GC_Reserved
// (chip-facts §4.2), written only Offline: Go_Offline, write, Start.
void no_gc_reserved_check(Chip& c) {
  if (c.profile().id == Profile::dpc31) {
    c.write(wr(c, RegId::Param_Reg), 0x02);
    return;
  }
  testutil::user_go_offline(c);
  c.write(wr(c, RegId::Mode_Reg2), 0x03);  // GC_Int_Mode 1 (the VPC3+ default), no check
  testutil::user_start(c);
}

// Started, the inputs A1..A4 frozen by a Freeze, then the user hands B1..B4 over: the exchange
// that lets the ISR hand B to N still answers A1..A4.
void freeze_a_then_hand_over_b(Bench& b) {
  ASSERT_TRUE(b.master.startup());
  b.master.data_exchange({0, 0, 0, 0});
  b.master.global_control(kGC_Freeze);
  b.user.set_inputs({0xB1, 0xB2, 0xB3, 0xB4});
  EXPECT_EQ(b.master.data_exchange({0, 0, 0, 0}).answer->du, kA);
}

std::size_t gc_interrupts(const Responder& u) {
  std::size_t n = 0;
  for (const auto& [cycle, ir] : u.interrupts) n += (ir & irq::New_GC_Command) != 0 ? 1 : 0;
  return n;
}

}  // namespace

// Seed 003 Bit 3 Freeze: "The input data is fetched from 'N' to 'D', and 'frozen'. New input
// data will be fetched only if the master sends the next 'Freeze' command." A1..A4 frozen; the
// user hands B1..B4 over; the exchanges still answer A1..A4 until the next Freeze, after which
// they answer B1..B4. The diag shows Freeze_Mode (St2 bit 4).
TEST_P(GlobalControl, Freeze_InputsFetchedNToDAndFrozenUntilNextFreeze) {
  Bench b(GetParam(), 12'000'000);
  freeze_a_then_hand_over_b(b);
  EXPECT_EQ(b.master.data_exchange({0, 0, 0, 0}).answer->du, kA);
  EXPECT_EQ(b.master.read_inputs().answer->du, kA);
  EXPECT_EQ(diag(b.master).at(1) & 0x10, 0x10);
  b.master.global_control(kGC_Freeze);
  EXPECT_EQ(b.master.data_exchange({0, 0, 0, 0}).answer->du, (Bytes{0xB1, 0xB2, 0xB3, 0xB4}));
}

// Seed 003 Bit 2 Unfreeze: "With 'Unfreeze', freezing the input data is cancelled. In addition,
// as in the case of 'Freeze', new input data that was made available is fetched from 'N' to
// 'D'." After Unfreeze the B1..B4 in N are answered, then inputs flow again (C1..C4 one exchange
// after the user hands them over); Freeze_Mode off.
TEST_P(GlobalControl, Unfreeze_CancelsFreezeAndFetchesNewInputsNToD) {
  Bench b(GetParam(), 12'000'000);
  freeze_a_then_hand_over_b(b);
  b.master.global_control(kGC_Unfreeze);
  b.user.set_inputs({0xC1, 0xC2, 0xC3, 0xC4});
  EXPECT_EQ(b.master.data_exchange({0, 0, 0, 0}).answer->du, (Bytes{0xB1, 0xB2, 0xB3, 0xB4}));
  EXPECT_EQ(b.master.data_exchange({0, 0, 0, 0}).answer->du, (Bytes{0xC1, 0xC2, 0xC3, 0xC4}));
  EXPECT_EQ(diag(b.master).at(1) & 0x10, 0x00);
}

// Seed 003 Bit 7, 6, 0 Reserved: "If such a bit is set, DPS sets 'Diag.Not_Supported=1', and
// the 'Leave_Master macro' is executed." Each reserved bit alone: Wait_Prm (Status_Reg bits 5:4
// = 00), the diag shows Not_Supported (St1 bit 4) and no master (Master_Add FFh).
TEST_P(GlobalControl, ReservedBitSet_NotSupportedAndLeaveMaster) {
  for (const std::uint8_t bad : {0x01, 0x40, 0x80}) {
    Bench b(GetParam(), 12'000'000);
    ASSERT_TRUE(b.master.startup());
    b.master.global_control(bad);
    EXPECT_EQ(dp_bits(status(b.chip)), kWaitPrm) << int(bad);
    const Bytes d = diag(b.master);
    ASSERT_EQ(d.size(), 6u);
    EXPECT_EQ(d[0] & 0x10, 0x10) << int(bad);
    EXPECT_EQ(d[3], 0xFF) << int(bad);
  }
}

// Seed 003: "However, if the user parameterizes 'Check_No_GC_Reserved=1' in the param register,
// the Reserved bits are not checked." DPC31, and the VPC3+'s No_Check_GC_Reserved: a Freeze
// with all three reserved bits (C9h) keeps Data_Exchange, no Not_Supported, is stored in
// GC_Command and freezes the inputs.
// (The SPC3 has no such option.)
namespace {
class GcReservedUnchecked : public ::testing::TestWithParam<Profile> {};
}  // namespace

TEST_P(GcReservedUnchecked, CheckNoGcReserved1_ReservedBitsNotChecked) {
  Bench b(GetParam(), 12'000'000);
  no_gc_reserved_check(b.chip);
  ASSERT_TRUE(b.master.startup());
  b.master.data_exchange({0, 0, 0, 0});
  b.master.global_control(0xC9);
  EXPECT_EQ(dp_bits(status(b.chip)), kDataEx);
  EXPECT_EQ(gc_command(b.chip), 0xC9);
  b.user.set_inputs({0xB1, 0xB2, 0xB3, 0xB4});
  b.master.data_exchange({0, 0, 0, 0});
  EXPECT_EQ(b.master.data_exchange({0, 0, 0, 0}).answer->du, kA);  // frozen
  const Bytes d = diag(b.master);
  ASSERT_EQ(d.size(), 6u);
  EXPECT_EQ(d[0] & 0x10, 0x00);
  EXPECT_EQ(d[3], 0x02);
}

// Seed 003 Bit 5 Sync / Bit 3 Freeze: "The same reaction occurs for 'Sync_Supported=0' as does
// for a set Reserved bit." / "... for 'Freeze_Supported=0' ...". Mode_Reg0 bit 6 / bit 7 off:
// Sync (20h) or Freeze (08h) gives Not_Supported and Leave_Master.
TEST_P(GlobalControl, SyncOrFreezeNotSupported_ReactLikeAReservedBit) {
  for (const bool sync : {true, false}) {
    ResponderConfig rc;
    (sync ? rc.sync_supported : rc.freeze_supported) = false;
    Bench b(GetParam(), 12'000'000, rc);
    ASSERT_TRUE(b.master.startup());
    b.master.global_control(sync ? 0x20 : kGC_Freeze);
    EXPECT_EQ(dp_bits(status(b.chip)), kWaitPrm) << sync;
    const Bytes d = diag(b.master);
    ASSERT_EQ(d.size(), 6u);
    EXPECT_EQ(d[0] & 0x10, 0x10) << sync;
    EXPECT_EQ(d[3], 0xFF) << sync;
  }
}

// Seed 003 p.33: "For each valid Global_Control message, the Control_Command byte is stored in
// the RAM cell 'GC_Command'." Freeze 08h, Unfreeze 04h, 00h: each is read back from the cell
// through the bus.
TEST_P(GlobalControl, EachValidGc_ControlCommandStoredInGcCommand) {
  Bench b(GetParam(), 12'000'000);
  ASSERT_TRUE(b.master.startup());
  for (const std::uint8_t cmd : {kGC_Freeze, kGC_Unfreeze, std::uint8_t{0x00}, kGC_Freeze}) {
    b.master.global_control(cmd);
    EXPECT_EQ(gc_command(b.chip), cmd);
  }
}

// manual-quotes.md Confirmed (DPC31 p.31): "If more than two net data bytes (Control_Command,
// Group_Select) are received ... DPS also does not accept this service." A Freeze with a third
// byte: GC_Command keeps 04h, the inputs are not frozen.
TEST_P(GlobalControl, MoreThanTwoNetDataBytes_NotAccepted) {
  Bench b(GetParam(), 12'000'000);
  ASSERT_TRUE(b.master.startup());
  b.master.global_control(kGC_Unfreeze);
  gc_raw(b.master, {kGC_Freeze, 0x00, 0x00});
  EXPECT_EQ(gc_command(b.chip), kGC_Unfreeze);
  b.user.set_inputs({0xB1, 0xB2, 0xB3, 0xB4});
  b.master.data_exchange({0, 0, 0, 0});
  EXPECT_EQ(b.master.data_exchange({0, 0, 0, 0}).answer->du, (Bytes{0xB1, 0xB2, 0xB3, 0xB4}));
  EXPECT_EQ(dp_bits(status(b.chip)), kDataEx);
}

// A Global_Control the chip ignores is logged with its reason: another master's (the locking
// master is 2), one with 3 data bytes, and one outside Data_Exchange (after a reserved bit made
// the slave leave the master) each have their own words.
TEST_P(GlobalControl, IgnoredGc_LogNamesTheReason) {
  Bench b(GetParam(), 12'000'000);
  std::vector<std::string> log;
  b.chip.set_log_sink([&](const LogRecord& r) { log.push_back(r.text); });
  ASSERT_TRUE(b.master.startup());
  const auto logged = [&](const std::string& text) {
    return std::find(log.begin(), log.end(), text) != log.end();
  };
  gc_raw(b.master, {kGC_Freeze, 0x00}, 7);
  EXPECT_TRUE(logged("Global_Control from 7: not the locking master: ignored"));
  gc_raw(b.master, {kGC_Freeze, 0x00, 0x00});
  EXPECT_TRUE(logged("Global_Control from 2: 3 data bytes, not 2: ignored"));
  b.master.global_control(0x01);  // a reserved bit: Leave_Master
  ASSERT_EQ(dp_bits(status(b.chip)), kWaitPrm);
  b.master.global_control(kGC_Freeze);
  EXPECT_TRUE(logged("Global_Control from 2: not in Data_Exchange: ignored"));
}

// manual-quotes.md Confirmed (DPC31 p.31): the command is for us if Group_Select AND Group_Ident
// is not 0; Group_Select 0 addresses all. Group_Ident 05h: Group_Select 02h is not for us
// (GC_Command stays), 04h is, 00h is.
TEST_P(GlobalControl, GroupSelectAndGroupIdentNonZero_GroupSelect0AddressesAll) {
  ResponderConfig rc;
  rc.slave.group_ident = 0x05;
  Bench b(GetParam(), 12'000'000, rc);
  ASSERT_TRUE(b.master.startup());
  b.master.global_control(kGC_Unfreeze, 0x00);
  EXPECT_EQ(gc_command(b.chip), kGC_Unfreeze);
  b.master.global_control(kGC_Freeze, 0x02);
  EXPECT_EQ(gc_command(b.chip), kGC_Unfreeze);
  b.master.global_control(kGC_Freeze, 0x04);
  EXPECT_EQ(gc_command(b.chip), kGC_Freeze);
  b.master.global_control(0x00, 0x00);
  EXPECT_EQ(gc_command(b.chip), 0x00);
}

INSTANTIATE_TEST_SUITE_P(Vpc3AndDpc31, GcReservedUnchecked,
                         ::testing::Values(Profile::vpc3plus, Profile::dpc31),
                         [](const auto& i) { return testutil::pname(i.param); });

INSTANTIATE_TEST_SUITE_P(Profiles, GlobalControl, ::testing::ValuesIn(kAllProfiles),
                         [](const auto& i) { return testutil::pname(i.param); });

// Seed 003 p.33: "With 'New_GC_Int mode = 0', the interrupt is generated only if the
// Control_Command byte for the last received Global_Control message has changed." (DPC31; the
// VPC3+'s GC_Int_Mode is tested with its fix.) Param_Reg reset 00h: 08h, 08h, 04h, 04h, 08h give
// New_GC_Command at the 1st, 3rd and 5th, each in the cycle the telegram is acted on.
TEST(GlobalControlDpc31, NewGcIntMode0_InterruptOnlyOnAChangedCommandByte) {
  Bench b(Profile::dpc31, 12'000'000);
  ASSERT_TRUE(b.master.startup());
  std::vector<std::uint64_t> acted;
  for (const std::uint8_t cmd : {kGC_Freeze, kGC_Freeze, kGC_Unfreeze, kGC_Unfreeze, kGC_Freeze}) {
    acted.push_back(b.acted(b.master.global_control(cmd)));
    b.master.idle(2000);
  }
  EXPECT_EQ(gc_interrupts(b.user), 3u);
  for (const std::size_t k : {0u, 2u, 4u}) {
    EXPECT_TRUE(isr_saw(b.user, acted[k], irq::New_GC_Command)) << k;
  }
}

// Which command mode 0 compares with: the Control_Command "for the last received Global_Control
// message" is what the chip stores in the RAM cell GC_Command, and the comparison is with that
// cell, which the user may write (modelled, docs/decisions.md: the FFh preset "not a valid value"
// (p.33) makes the first Global_Control a change only so). Freeze (FFh -> 08h: interrupt); the
// user writes 00h, Freeze (08h vs 00h: interrupt); Unfreeze (04h vs 08h: interrupt); the user
// writes 08h, Freeze (08h vs 08h: none, though the last received command was 04h).
TEST(GlobalControlDpc31, NewGcIntMode0_ComparesWithTheGcCommandCellTheUserMayWrite) {
  Bench b(Profile::dpc31, 12'000'000);
  ASSERT_TRUE(b.master.startup());
  const std::pair<int, std::uint8_t> steps[] = {
      {-1, kGC_Freeze}, {0x00, kGC_Freeze}, {-1, kGC_Unfreeze}, {0x08, kGC_Freeze}};
  std::vector<std::uint64_t> acted;
  for (const auto& [cell, cmd] : steps) {
    if (cell >= 0) b.chip.write(wr(b.chip, RegId::R_GC_Command), static_cast<std::uint8_t>(cell));
    acted.push_back(b.acted(b.master.global_control(cmd)));
    b.master.idle(2000);
  }
  EXPECT_EQ(gc_interrupts(b.user), 3u);
  for (const std::size_t k : {0u, 1u, 2u}) {
    EXPECT_TRUE(isr_saw(b.user, acted[k], irq::New_GC_Command)) << k;
  }
  EXPECT_EQ(gc_command(b.chip), kGC_Freeze);
}

// Seed 003 p.33: "With 'New_GC_Int mode=1', the interrupt is generated after each receipt of a
// GC message." Param_Reg bit 0 = 1: three identical Freezes, three New_GC_Command, each at the
// cycle its telegram is acted on.
TEST(GlobalControlDpc31, NewGcIntMode1_InterruptAfterEachGc) {
  Bench b(Profile::dpc31, 12'000'000);
  ASSERT_TRUE(b.master.startup());
  b.chip.write(wr(b.chip, RegId::Param_Reg), 0x01);
  std::vector<std::uint64_t> acted;
  for (int i = 0; i < 3; ++i) {
    acted.push_back(b.acted(b.master.global_control(kGC_Freeze)));
    b.master.idle(2000);
  }
  EXPECT_EQ(gc_interrupts(b.user), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_TRUE(isr_saw(b.user, acted[k], irq::New_GC_Command)) << k;
  }
}

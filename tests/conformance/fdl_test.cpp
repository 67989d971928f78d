// The FDL layer and the remaining DP services as the sourced facts of chip-facts.md §4, §5.4 and
// §8 state them: the UART character on the chip's TxD pin, TSYN before a request, Set_Slave_Add
// with SSA_Buffer_Free_Cmd, Set_Prm's Spec_User_Prm_Byte in Mode_Reg0, Go_Leave_Data_Exchange.
// T = 4 clocks at 12 Mbaud (docs/timing.md).
#include "conformance.hpp"
#include "user_side.hpp"

using namespace dpc31;
using namespace conformance;

namespace {

class Fdl : public ::testing::TestWithParam<Profile> {};

using Edges = std::vector<std::pair<std::uint64_t, bool>>;

}  // namespace

// chip-facts §8 [S-PYPB-PHY]: "UART char: 11 bits = start, 8 data (LSB first), even parity, 1
// stop." The FDL_Status answer 10 02 05 00 07 16 starts 11 T after the request's end; its first
// character 10h on TxD: start bit low at s, data bits 0..3 low, bit 4 high at s + 5T, bits 5..7
// low from s + 6T, parity 1 (one 1 in 10h: even) high at s + 9T, stop bit high; the next
// character 02h starts at s + 11T (low), its bit 1 is high at s + 11T + 2T.
TEST_P(Fdl, UartCharacter_StartLsbFirstEvenParityStop) {
  Bare b(GetParam());
  Edges txd;
  b.chip.on_txd([&](std::uint64_t at, bool level) { txd.emplace_back(at, level); });
  const Exchange ex = b.master.fdl_status();
  ASSERT_TRUE(ex.answer);
  const std::uint64_t s = ex.request_end + 11 * 4;
  ASSERT_GE(txd.size(), 6u);
  const Edges expect = {{s, false},     {s + 20, true},  {s + 24, false},
                        {s + 36, true}, {s + 44, false}, {s + 52, true}};
  EXPECT_EQ(Edges(txd.begin(), txd.begin() + 6), expect);
}

// chip-facts §8 [S-PYPB-PHY]: "TSYN = 33 bit times idle before a request". An FDL_Status to
// station 9 fixes the rate (and is not answered); an FDL_Status to us (10 05 02 49 50 16) whose
// first start bit comes 32 bit times after the end of that telegram is not answered; one 33
// bit times after it is answered (TxD falls 11 T after its end).
TEST_P(Fdl, Tsyn_RequestNeeds33IdleBitTimesBeforeIt) {
  for (const std::uint64_t idle : {32u, 33u}) {
    Bare b(GetParam());
    Edges txd;
    b.chip.on_txd([&](std::uint64_t at, bool level) { txd.emplace_back(at, level); });
    const std::uint64_t e1 =
        send_on_rxd(b.chip, Bytes{0x10, 0x09, 0x02, 0x49, 0x54, 0x16}, b.chip.cycle() + 40 * 4, 4);
    const std::uint64_t e2 =
        send_on_rxd(b.chip, Bytes{0x10, 0x05, 0x02, 0x49, 0x50, 0x16}, e1 + idle * 4, 4);
    b.chip.step(e2 + 200 * 4 - b.chip.cycle());
    if (idle == 32) {
      EXPECT_TRUE(txd.empty());
    } else {
      ASSERT_FALSE(txd.empty());
      EXPECT_EQ(txd.front(), std::make_pair(e2 + 11 * 4, false));
    }
  }
}

// docs/timing.md "Telegrams", errors: a bad character "discards the telegram, counts one error of
// the first kind seen (of one bad character the first bit sampled: start bit, then parity, then
// stop bit), and the receiver waits for TSYN again: the rest of the broken telegram is its tail
// and counts nothing"; TSYN: a telegram begins with a character after >= 33 idle bit times. So an
// FDL_Status to us 33 bit times after a broken one is a telegram of its own whatever the one
// before was: three with a parity error in the SD (parity bit inverted) count three parity
// errors, one with a stop error in the SD (stop bit low) one stop_bit error, and nothing else
// is counted (their good characters are tails) and nothing answered.
TEST_P(Fdl, BadCharacter_AfterTsynOpensATelegramWhateverTheOneBeforeWas) {
  Bare b(GetParam());
  Edges txd;
  b.chip.on_txd([&](std::uint64_t at, bool level) { txd.emplace_back(at, level); });
  std::uint64_t end =
      send_on_rxd(b.chip, Bytes{0x10, 0x09, 0x02, 0x49, 0x54, 0x16}, b.chip.cycle() + 40 * 4, 4);
  b.chip.step(end - b.chip.cycle());
  FdlCounters want = b.chip.fdl_counters();
  const Bytes to_us{0x10, 0x05, 0x02, 0x49, 0x50, 0x16};
  for (const UartFault::Kind k : {UartFault::Kind::parity, UartFault::Kind::parity,
                                  UartFault::Kind::parity, UartFault::Kind::stop}) {
    end = send_on_rxd(b.chip, to_us, end + 33 * 4, 4, UartFault{0, k});
    b.chip.step(end - b.chip.cycle());
    ++(k == UartFault::Kind::parity ? want.parity : want.stop_bit);
    EXPECT_EQ(b.chip.fdl_counters(), want) << "after the telegram ending at " << end;
  }
  b.chip.step(end + 200 * 4 - b.chip.cycle());
  EXPECT_EQ(b.chip.fdl_counters(), want);
  EXPECT_TRUE(txd.empty());
}

// chip-facts §5.4 [S-SSA]: "SSA: after New_SSA_Data the user reads SSA_Buffer_Free_Cmd (14h) to
// re-enable SAP55; the ASIC internally adopts the new address". Set_Slave_Add to 9 (SC): New_SSA_
// Data, the chip answers at 9; a second one before the user freed the buffer: RR (10 02 09 02 0D
// 16); after the 14h read, Set_Slave_Add to 10 is taken (SC) and the chip answers at 10.
TEST_P(Fdl, SetSlaveAddress_SsaBufferFreeCmdReEnablesSap55) {
  Bare b(GetParam());
  ASSERT_TRUE(b.master.fdl_status().answer);
  EXPECT_EQ(wire(b.master.set_slave_address(9, false).answer), Bytes{0xE5});
  EXPECT_NE(irr(b.chip) & irq::New_SSA_Data, 0);
  b.master.set_target(9);
  ASSERT_TRUE(b.master.fdl_status().answer);
  EXPECT_EQ(wire(b.master.set_slave_address(10, false).answer),
            (Bytes{0x10, 0x02, 0x09, 0x02, 0x0D, 0x16}));
  b.chip.read(0x14);
  EXPECT_EQ(wire(b.master.set_slave_address(10, false).answer), Bytes{0xE5});
  b.master.set_target(10);
  EXPECT_TRUE(b.master.fdl_status().answer);
}

// chip-facts §2.1 bit 1 [S-IRR]: Go/Leave_Data_Exchange "DP_SM entered or left DATA_EX". In
// Data_Exchange, with Int_Req_Reg acknowledged, User_Leave_Master (Mode_Reg1 bit 3) latches it
// (with DX_Out, the cleared outputs) and Status_Reg shows Wait_Prm.
TEST_P(Fdl, GoLeaveDataExchange_WhenTheStateMachineLeavesDataExchange) {
  Bare b(GetParam());
  start_by_hand(b);
  b.master.data_exchange({0, 0, 0, 0});
  ASSERT_EQ(dp_bits(status(b.chip)), kDataEx);
  testutil::bus_write16(b.chip, static_cast<int>(wr(b.chip, RegId::Int_Ack_Reg)), 16, 0xF3FF);
  ASSERT_EQ(irr(b.chip) & (irq::Go_Leave_Data_Exchange | irq::DX_Out), 0);
  testutil::user_leave_master(b.chip);
  EXPECT_EQ(irr(b.chip) & (irq::Go_Leave_Data_Exchange | irq::DX_Out),
            irq::Go_Leave_Data_Exchange | irq::DX_Out);
  EXPECT_EQ(dp_bits(status(b.chip)), kWaitPrm);
}

INSTANTIATE_TEST_SUITE_P(Profiles, Fdl, ::testing::ValuesIn(kAllProfiles),
                         [](const auto& i) { return testutil::pname(i.param); });

class FdlSpcVpc : public ::testing::TestWithParam<Profile> {};

// chip-facts §4.1 [S-RU-SPC3] / §8 [S-PRM]: Mode_Reg0 bit 0 Dis_Start_Control, bit 1
// Dis_Stop_Control "Overwritten by Set_Prm in DP mode" from Set_Prm byte 7 bits 0 / 1
// (Spec_User_Prm_Byte), on the SPC3 and the VPC3+ (the DPC31 keeps that byte for itself, p.26:
// Dpc31Requests.Byte13DoesNotSetDisStartOrDisStop). Byte 7 = 02h: Mode_Reg0 read through the bus
// shows bits 1..0 = 10b; byte 7 = 01h: 01b.
TEST_P(FdlSpcVpc, SetPrmSpecUserPrmByte_OverwritesDisStartStopControl) {
  for (const std::uint8_t byte7 : {0x02, 0x01}) {
    ResponderConfig rc;
    rc.slave.user_prm = {byte7};
    Bare b(GetParam(), 12'000'000, rc);
    ASSERT_TRUE(b.master.fdl_status().answer);
    b.master.set_prm();
    EXPECT_EQ(b.chip.read(rd(b.chip, RegId::Mode_Reg0)) & 0x03, byte7) << int(byte7);
  }
}

INSTANTIATE_TEST_SUITE_P(Profiles, FdlSpcVpc, ::testing::Values(Profile::spc3, Profile::vpc3plus),
                         [](const auto& i) { return testutil::pname(i.param); });

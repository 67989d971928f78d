// Buffer state machines, diagnostics and the user watchdog as manual-quotes.md "Confirmed" and the
// sourced facts of chip-facts.md §4-§5 state them. The test is the user (Bare: no ISR runs) and
// reads the command addresses itself: Din_Buffer_SM 08h, New_Din_Buffer_Cmd 09h, Dout_Buffer_SM
// 0Ah, Next_Dout_Buffer_Cmd 0Bh, Diag_Buffer_SM 0Ch, New_Diag_Buffer_Cmd 0Dh (chip-facts §1.1).
// State machine fields: F 7:6 (dpc31: N_Cl in bit 7), U 5:4, N 3:2, D 1:0; 01/10/11 = buffer
// 1/2/3, 00 Nil.
#include "conformance.hpp"
#include "dpc31/pdu.hpp"
#include "user_side.hpp"

using namespace dpc31;
using namespace conformance;

namespace {

class BufferSm : public ::testing::TestWithParam<Profile> {};

std::uint32_t dout_buffer(Chip& c, int index) {
  static constexpr RegId kPtr[] = {RegId::R_Dout_Buf_Ptr1, RegId::R_Dout_Buf_Ptr2,
                                   RegId::R_Dout_Buf_Ptr3};
  return static_cast<std::uint32_t>(c.read(rd(c, kPtr[index - 1]))) << c.profile().segment_shift;
}

Bytes read_bytes(Chip& c, std::uint32_t at, std::size_t n) {
  Bytes v;
  for (std::size_t i = 0; i < n; ++i) v.push_back(c.read(at + static_cast<std::uint32_t>(i)));
  return v;
}

// The user's diag buffer (the one Diag_Buffer_SM shows as 01 = User) gets `bytes`.
void write_user_diag(Chip& c, const Bytes& bytes) {
  const std::uint8_t sm = c.read(0x0C);
  const bool first = (sm & 0x03) == 0x01;
  const std::uint32_t at = static_cast<std::uint32_t>(c.read(
                               rd(c, first ? RegId::R_Diag_Buf_Ptr1 : RegId::R_Diag_Buf_Ptr2)))
                           << c.profile().segment_shift;
  for (std::size_t i = 0; i < bytes.size(); ++i)
    c.write(at + static_cast<std::uint32_t>(i), bytes[i]);
  c.write(rd(c, first ? RegId::R_Len_Diag_Buf1 : RegId::R_Len_Diag_Buf2),
          static_cast<std::uint8_t>(bytes.size()));
}

}  // namespace

// manual-quotes.md Confirmed, VPC3+S p.51: "Diag_Buffer_SM: bits 3-2 Diag_Buf2, 1-0 Diag_Buf1:
// 00 Nil, 01 User, 10 VPC3+, 11 VPC3_Send_Mode." After the user hands its buffer over with
// New_Diag_Buffer_Cmd, one buffer is 01 (User) and the other 10 (ASIC); while the ASIC sends it
// (from the Slave_Diag being acted on to the end of the answer, docs/timing.md) it is 11; after
// the answer 10 again. Slave_Diag 5 <- 2 by hand: 68 05 05 68 85 82 4D 3C 3E CE 16 (FCS 85 + 82
// + 4D + 3C + 3E = 1CEh); its answer has 6 diag bytes: 17 characters, starting 11 T after the
// request's end, T = 4.
TEST_P(BufferSm, DiagBufferSm_Codes00Nil01User10Asic11SendMode) {
  Bare b(GetParam());
  ASSERT_TRUE(b.master.fdl_status().answer);
  const std::uint8_t user_buf = b.chip.read(0x0D) & 0x03;  // 01 or 10: the buffer now the user's
  ASSERT_TRUE(user_buf == 1 || user_buf == 2);
  const std::uint8_t idle = user_buf == 1 ? 0x09 : 0x06;  // user 01, ASIC 10
  EXPECT_EQ(b.chip.read(0x0C), idle);
  const Bytes req = {0x68, 0x05, 0x05, 0x68, 0x85, 0x82, 0x4D, 0x3C, 0x3E, 0xCE, 0x16};
  const std::uint64_t end = send_on_rxd(b.chip, req, b.chip.cycle() + 40 * 4, 4);
  const std::uint64_t answer_end = end + 11 * 4 + 17 * 11 * 4;
  b.chip.step(end + 100 - b.chip.cycle());
  const std::uint8_t sending = user_buf == 1 ? 0x0D : 0x07;  // the ASIC's buffer 11
  EXPECT_EQ(b.chip.read(0x0C), sending);
  // A read ends at answer_end - 1: still sending; a look at answer_end (peek: no bus time, where
  // a second read would end an access later): the ASIC's again.
  b.chip.step(answer_end - 1 - b.chip.bus_access_cycles() - b.chip.cycle());
  EXPECT_EQ(b.chip.read(0x0C), sending);
  ASSERT_EQ(b.chip.cycle(), answer_end - 1);
  b.chip.step(1);
  EXPECT_EQ(b.chip.peek(0x0C), idle);
}

namespace {

// The start-up with the test as the user, then the user hands a diag buffer (byte 0 = `byte0`)
// over: New_Diag_Buffer_Cmd.
void locked_with_new_diag(Bare& b, std::uint8_t byte0) {
  ASSERT_TRUE(b.master.fdl_status().answer);
  b.master.set_prm();
  ASSERT_EQ(b.chip.read(0x0E), 0x00);
  b.master.chk_cfg();
  ASSERT_EQ(b.chip.read(0x10), 0x00);
  write_user_diag(b.chip, {byte0, 0, 0, 0, 0, 0, 0x42});
  b.chip.read(0x0D);
}

}  // namespace

// chip-facts §5.3 [S-DIAG]: New_Diag_Buffer_Cmd "returns bits 1:0: 00 = no buffer (both with
// the ASIC), 01 = Diag_Buf1 now user's, 10 = Diag_Buf2 now user's"; "Exchange → Diag_Buffer_
// Changed interrupt". While the ASIC sends its buffer (a Slave_Diag answer in progress) the user
// hands its own over: 00h, no Diag_Buffer_Changed; when the answer has ended the sent buffer
// comes back: Diag_Buffer_Changed (IRR bit 12), and Diag_Buffer_SM shows it as User (01).
TEST_P(BufferSm, NewDiagBufferCmd_00WhileBothWithTheAsic_DiagBufferChangedWhenOneComesBack) {
  Bare b(GetParam());
  ASSERT_TRUE(b.master.fdl_status().answer);
  testutil::bus_write16(b.chip, static_cast<int>(wr(b.chip, RegId::Int_Ack_Reg)), 16, 0xF3FF);
  const Bytes req = {0x68, 0x05, 0x05, 0x68, 0x85, 0x82, 0x4D, 0x3C, 0x3E, 0xCE, 0x16};
  const std::uint64_t end = send_on_rxd(b.chip, req, b.chip.cycle() + 40 * 4, 4);
  const std::uint64_t answer_end = end + 11 * 4 + 17 * 11 * 4;
  b.chip.step(end + 100 - b.chip.cycle());
  const std::uint8_t sent = b.chip.read(0x0C);  // reset: buffer 2 is the ASIC's (11 now)
  EXPECT_EQ(b.chip.read(0x0D), 0x00);
  EXPECT_EQ(irr(b.chip) & irq::Diag_Buffer_Changed, 0);
  b.chip.step(answer_end + 4 - b.chip.cycle());
  EXPECT_NE(irr(b.chip) & irq::Diag_Buffer_Changed, 0);
  const std::uint8_t sm = b.chip.read(0x0C);
  // The buffer that was being sent (11) is the user's (01) now; the other one the ASIC's (10).
  EXPECT_EQ(sm, sent == 0x0D ? 0x06 : 0x09);
}

// manual-quotes.md Confirmed, SPC3 p.32: "Diag_Flag: set on the exchange, cleared when 'the
// relevant master' fetched, kept with Stat_Diag." Status_Reg bit 2: 1 after the user's
// New_Diag_Buffer_Cmd, 0 after master 2 (the one the slave is locked to) fetched the diag; with
// Stat_Diag (byte 0 bit 1) in the new buffer it stays 1 after the fetch.
TEST_P(BufferSm, DiagFlag_SetOnExchange_ClearedWhenFetched_KeptWithStatDiag) {
  Bare b(GetParam());
  locked_with_new_diag(b, 0x00);
  EXPECT_EQ(status(b.chip) & 0x04, 0x04);
  ASSERT_TRUE(b.master.slave_diag().answer);
  EXPECT_EQ(status(b.chip) & 0x04, 0x00);
  write_user_diag(b.chip, {0x02, 0, 0, 0, 0, 0, 0x43});
  b.chip.read(0x0D);
  EXPECT_EQ(status(b.chip) & 0x04, 0x04);
  ASSERT_TRUE(b.master.slave_diag().answer);
  EXPECT_EQ(status(b.chip) & 0x04, 0x04);
}

// SPC3 p.33: "The first 6 bytes are space holders, except for the three least significant bit
// positions in the first byte. ... When sending, SPC3 pre-processes the first six bytes
// corresponding to the standard." The sent buffer holds them where the user reads them through
// the bus: byte 3 Master_Add (FFh before the lock, 2 after master 2's Set_Prm; a driver learns
// the locking master there, as the Profichip driver's VPC3_GetMasterAddress does), bytes 1, 2, 4,
// 5 as sent, byte 0 the sent Station_Status_1 in bits 7..3 with the user's three bits kept
// (Ext_Diag, Ext_Diag_Overflow here), so a second Slave_Diag of the same buffer says the same.
TEST_P(BufferSm, DiagSpaceHolders_HoldTheSentStandardBytes_MasterAddInByte3) {
  Bare b(GetParam());
  const auto asic_buffer = [&b] {
    const bool first = (b.chip.read(0x0C) & 0x03) >= 0x02;  // 10 or 11: the ASIC's
    return static_cast<std::uint32_t>(
               b.chip.read(rd(b.chip, first ? RegId::R_Diag_Buf_Ptr1 : RegId::R_Diag_Buf_Ptr2)))
           << b.chip.profile().segment_shift;
  };
  ASSERT_TRUE(b.master.fdl_status().answer);
  ASSERT_TRUE(b.master.slave_diag().answer);
  EXPECT_EQ(b.chip.read(asic_buffer() + 3), 0xFF);
  locked_with_new_diag(b, 0x05);
  const Exchange d = b.master.slave_diag();
  ASSERT_TRUE(d.answer);
  const Bytes& du = d.answer->du;
  ASSERT_EQ(du.size(), 7u);
  const Bytes held = read_bytes(b.chip, asic_buffer(), 7);
  EXPECT_EQ(held[3], 0x02);
  EXPECT_EQ(held, (Bytes{static_cast<std::uint8_t>((du[0] & 0xF8) | 0x05), du[1], du[2], du[3],
                         du[4], du[5], 0x42}));
  EXPECT_EQ(du[0] & pdu::SlaveDiag::St1_Ext_Diag, pdu::SlaveDiag::St1_Ext_Diag);
  EXPECT_EQ(b.master.slave_diag().answer->du, du);
}

// The same sentence: the master's fetch clears the flag for the buffer it fetched. While master 2
// fetches one buffer the user hands the other over (New_Diag_Buffer_Cmd 00h: Diag_Flag 1): the
// fetched buffer is not the current one, so the flag stays 1 after the answer (a DH for the next
// Data_Exchange), and master 2's next Slave_Diag, of the newer buffer, clears it. Fixed (the
// twenty-second session's review): the end of the send took the old buffer's verdict.
TEST_P(BufferSm, DiagFlag_StaysSetForABufferHandedOverWhileTheOtherIsSent) {
  Bare b(GetParam());
  locked_with_new_diag(b, 0x00);
  ASSERT_TRUE(b.master.slave_diag().answer);
  ASSERT_EQ(status(b.chip) & 0x04, 0x00);
  // master 2's Slave_Diag (FCV 0), driven by hand so that the user can act during its answer
  const Bytes req = {0x68, 0x05, 0x05, 0x68, 0x85, 0x82, 0x4D, 0x3C, 0x3E, 0xCE, 0x16};
  const std::uint64_t end = send_on_rxd(b.chip, req, b.chip.cycle() + 40 * 4, 4);
  // TSDR 11 bits, then 18 characters (9 of frame, 2 SAPs, 7 diag bytes) at 4 cycles a bit
  const std::uint64_t answer_end = end + 11 * 4 + 18 * 11 * 4;
  b.chip.step(end + 100 - b.chip.cycle());
  write_user_diag(b.chip, {0x00, 0, 0, 0, 0, 0, 0x43});
  EXPECT_EQ(b.chip.read(0x0D), 0x00);  // both with the ASIC, one of them being sent
  EXPECT_EQ(status(b.chip) & 0x04, 0x04);
  b.chip.step(answer_end + 4 - b.chip.cycle());
  EXPECT_NE(irr(b.chip) & irq::Diag_Buffer_Changed, 0);
  EXPECT_EQ(status(b.chip) & 0x04, 0x04);
  const Exchange d = b.master.slave_diag();
  ASSERT_TRUE(d.answer);
  EXPECT_EQ(d.answer->du.back(), 0x43);
  EXPECT_EQ(status(b.chip) & 0x04, 0x00);
}

// The same sentence, "cleared when 'the relevant master' fetched": a fetch by master 7, which
// the slave is not locked to, leaves Diag_Flag set; master 2's fetch clears it.
// Fixed (issue 13); before: the model clears it on any master's fetch.
TEST_P(BufferSm, DiagFlag_NotClearedByAnotherMastersFetch) {
  Bare b(GetParam());
  locked_with_new_diag(b, 0x00);
  DpMaster other(b.chip, MasterConfig{7, 12'000'000, 100, 33}, b.master.slave());
  ASSERT_TRUE(other.slave_diag().answer);
  EXPECT_EQ(status(b.chip) & 0x04, 0x04);
  ASSERT_TRUE(b.master.slave_diag().answer);
  EXPECT_EQ(status(b.chip) & 0x04, 0x00);
}

// chip-facts §5.3 [S-DIAG]: "While Diag_Flag is set the next Data_Exchange answer is sent with
// high-priority response FC (DH) so the master fetches diagnostics." DL (08h) before, DH (0Ah)
// after the user's New_Diag_Buffer_Cmd, DL again after master 2 fetched the diag.
TEST_P(BufferSm, DiagFlag_DataExchangeAnsweredHighPriority) {
  Bench b(GetParam());
  ASSERT_TRUE(b.master.startup());
  EXPECT_EQ(b.master.data_exchange({0, 0, 0, 0}).answer->fc, kFcDL);
  write_user_diag(b.chip, {0x00, 0, 0, 0, 0, 0, 0x42});
  b.chip.read(0x0D);
  EXPECT_EQ(b.master.data_exchange({0, 0, 0, 0}).answer->fc, kFcDH);
  ASSERT_TRUE(b.master.slave_diag().answer);
  EXPECT_EQ(b.master.data_exchange({0, 0, 0, 0}).answer->fc, kFcDL);
}

// manual-quotes.md Confirmed, SPC3 p.34: Next_Dout_Buffer_Cmd "bits 7-4 0; bit 3
// U_Buffer_Cleared; bit 2 new U buffer; bits 1-0 pointer". VPC3+S p.53: with nothing in N "the
// buffer exchange is omitted". After Start (power-on: the cleared buffer in N): cleared | new |
// U, U = Dout_Buffer_SM bits 5:4 after the read. After a Data_Exchange 11 22 33 44: new | U, and
// buffer U holds 11 22 33 44. A second read: bit 2 = 0, U and Dout_Buffer_SM unchanged.
TEST_P(BufferSm, NextDoutBufferCmd_BitLayout_NoExchangeWithNothingInN) {
  Bare b(GetParam());
  std::uint8_t r = b.chip.read(0x0B);
  std::uint8_t u = (b.chip.read(0x0A) >> 4) & 3;
  EXPECT_EQ(r & 0xF0, 0x00);
  EXPECT_EQ(r & 0x0C, 0x0C);
  EXPECT_EQ(r & 0x03, u);
  EXPECT_NE(u, 0);
  start_by_hand(b);
  b.master.data_exchange({0x11, 0x22, 0x33, 0x44});
  r = b.chip.read(0x0B);
  u = (b.chip.read(0x0A) >> 4) & 3;
  EXPECT_EQ(r & 0xFC, 0x04);
  EXPECT_EQ(r & 0x03, u);
  EXPECT_EQ(read_bytes(b.chip, dout_buffer(b.chip, u), 4), (Bytes{0x11, 0x22, 0x33, 0x44}));
  const std::uint8_t sm = b.chip.read(0x0A);
  const std::uint8_t again = b.chip.read(0x0B);
  EXPECT_EQ(again & 0x04, 0x00);
  EXPECT_EQ(again & 0x03, u);
  EXPECT_EQ(b.chip.read(0x0A), sm);
}

// chip-facts §5.1 [S-DOUT]: "If the user is slower than the bus, N is overwritten several times;
// the user always gets the latest." Three Data_Exchanges before the user's Next_Dout_Buffer_Cmd:
// U holds the third's 03 03 03 03.
TEST_P(BufferSm, SlowUser_AlwaysGetsTheLatestOutputs) {
  Bare b(GetParam());
  start_by_hand(b);
  b.chip.read(0x0B);  // the power-on clear
  for (std::uint8_t v = 1; v <= 3; ++v) b.master.data_exchange({v, v, v, v});
  const std::uint8_t r = b.chip.read(0x0B);
  ASSERT_EQ(r & 0x04, 0x04);
  EXPECT_EQ(read_bytes(b.chip, dout_buffer(b.chip, r & 3), 4), (Bytes{3, 3, 3, 3}));
}

// manual-quotes.md Confirmed, SPC3 p.35: "New_Din_Buffer_Cmd bits 7..2 read 0"; chip-facts §5.2:
// the returned bits 1:0 are the new U buffer (Din_Buffer_SM bits 5:4 afterwards). Before sending,
// "the ASIC moves N → D if N holds new data; otherwise D is resent unchanged": the user's B1..B4
// handed over go out with the next answer, and again with the one after.
TEST_P(BufferSm, NewDinBufferCmd_Bits7To2Zero_NewInputsSentThenResent) {
  Bare b(GetParam());
  for (int i = 0; i < 4; ++i) {
    const std::uint8_t r = b.chip.read(0x09);
    EXPECT_EQ(r & 0xFC, 0x00) << i;
    EXPECT_EQ(r & 0x03, (b.chip.read(0x08) >> 4) & 3) << i;
  }
  ASSERT_TRUE(b.master.fdl_status().answer);
  b.master.set_prm();
  ASSERT_EQ(b.chip.read(0x0E), 0x00);
  b.master.chk_cfg();
  ASSERT_EQ(b.chip.read(0x10), 0x00);
  static constexpr RegId kPtr[] = {RegId::R_Din_Buf_Ptr1, RegId::R_Din_Buf_Ptr2,
                                   RegId::R_Din_Buf_Ptr3};
  const std::uint8_t u = (b.chip.read(0x08) >> 4) & 3;
  const std::uint32_t at = static_cast<std::uint32_t>(b.chip.read(rd(b.chip, kPtr[u - 1])))
                           << b.chip.profile().segment_shift;
  for (std::uint32_t i = 0; i < 4; ++i) b.chip.write(at + i, static_cast<std::uint8_t>(0xB1 + i));
  b.chip.read(0x09);
  EXPECT_EQ(b.master.data_exchange({0, 0, 0, 0}).answer->du, (Bytes{0xB1, 0xB2, 0xB3, 0xB4}));
  EXPECT_EQ(b.master.data_exchange({0, 0, 0, 0}).answer->du, (Bytes{0xB1, 0xB2, 0xB3, 0xB4}));
}

// manual-quotes.md Confirmed: "Clear_Data, Leave_Master, power-on: D cleared and shifted to N with
// DX_Out"; SPC3 p.23: "For a 'Power_On' or for a 'Leave_Master,' the SPC3 deletes the N buffer
// and also generates this interrupt."; VPC3+S p.53: "This also takes place during power-up
// (entering the WAIT-PRM state)". Power-on: the Dout buffers hold AAh (written by the user
// while Offline); Start raises DX_Out (IRR bit 13) and the user fetches 00 00 00 00 with
// U_Buffer_Cleared. Leave_Master (User_Leave_Master, Mode_Reg1 bit 3) after outputs 01 02 03 04:
// DX_Out again, the user fetches 00 00 00 00, U_Buffer_Cleared.
TEST_P(BufferSm, PowerOnAndLeaveMaster_ClearTheOutputsWithDxOut) {
  Bare b(GetParam());
  Chip& c = b.chip;
  // Power-on: Offline (Go_Offline), the three Dout buffers filled with AAh, DX_Out acknowledged,
  // then Start_SPC3.
  testutil::user_go_offline(c);
  for (int i = 1; i <= 3; ++i) {
    for (std::uint32_t k = 0; k < 4; ++k) c.write(dout_buffer(c, i) + k, 0xAA);
  }
  testutil::bus_write16(c, static_cast<int>(wr(c, RegId::Int_Ack_Reg)), 16, irq::DX_Out);
  ASSERT_EQ(irr(c) & irq::DX_Out, 0);
  testutil::user_start(c);
  EXPECT_NE(irr(c) & irq::DX_Out, 0);
  std::uint8_t r = c.read(0x0B);
  EXPECT_EQ(r & 0x0C, 0x0C);
  EXPECT_EQ(read_bytes(c, dout_buffer(c, r & 3), 4), (Bytes{0, 0, 0, 0}));
  // Leave_Master after real outputs. (Start reconfigured the receiver: TSYN of idle first.)
  b.master.idle(100 * b.T());
  ASSERT_TRUE(b.master.fdl_status().answer);
  b.master.set_prm();
  ASSERT_EQ(c.read(0x0E), 0x00);
  b.master.chk_cfg();
  ASSERT_EQ(c.read(0x10), 0x00);
  c.read(0x09);  // first inputs: the SPC3 enters Data_Exchange now (SPC3 p.31)
  b.master.data_exchange({0x01, 0x02, 0x03, 0x04});
  r = c.read(0x0B);
  ASSERT_EQ(r & 0x0C, 0x04);
  EXPECT_EQ(read_bytes(c, dout_buffer(c, r & 3), 4), (Bytes{0x01, 0x02, 0x03, 0x04}));
  testutil::bus_write16(c, static_cast<int>(wr(c, RegId::Int_Ack_Reg)), 16, irq::DX_Out);
  ASSERT_EQ(irr(c) & irq::DX_Out, 0);
  testutil::user_leave_master(c);
  EXPECT_NE(irr(c) & irq::DX_Out, 0);
  r = c.read(0x0B);
  EXPECT_EQ(r & 0x0C, 0x0C);
  EXPECT_EQ(read_bytes(c, dout_buffer(c, r & 3), 4), (Bytes{0, 0, 0, 0}));
}

// manual-quotes.md Confirmed: "User watchdog on SPC3 / VPC3+ counted per Data_Exchange (SPC3 p.35,
// VPC3+C p.50)"; docs/timing.md: Res_User_WD loads R_User_WD_Value at the next Data_Exchange,
// each later one counts down, the one reaching 0 is not answered and makes Leave_Master.
// R_User_WD_Value 3 with 400 ms of silence between the exchanges (time does not count; TWD is
// 1 s): the 1st, 2nd, 3rd are answered, the 4th is not; Wait_Prm.
// (SPC3 and VPC3+ only: the DPC31's DPS_User_Watchdog is a 10 ms timer, DPC31 p.31, issue 13.)
namespace {
class UserWatchdog : public ::testing::TestWithParam<Profile> {};
}  // namespace

TEST_P(UserWatchdog, CountedPerDataExchangeNotInTime) {
  ResponderConfig rc;
  rc.user_wd_value = 3;
  Bench b(GetParam(), 12'000'000, rc);
  ASSERT_TRUE(b.master.startup());
  for (int i = 1; i <= 4; ++i) {
    const Exchange dx = b.master.data_exchange({1, 1, 1, 1});
    EXPECT_EQ(dx.answer.has_value(), i < 4) << i;
    b.master.idle(400 * 48'000);
  }
  EXPECT_EQ(dp_bits(status(b.chip)), kWaitPrm);
}

// chip-facts §4.2 [S-RU-SPC3][S-IRR]: Go_Offline (Mode_Reg1 bit 2): "go Offline after the current
// request; MAC_Reset interrupt; Status.bit0 → 0"; Start_SPC3 (bit 0): "leave Offline →
// Passive_Idle". Status bit 0: 1 started, 0 after Go_Offline with MAC_Reset (IRR bit 0) latched;
// 1 again after Start.
TEST_P(BufferSm, GoOffline_MacResetAndStatusBit0) {
  Bare b(GetParam());
  EXPECT_EQ(status(b.chip) & 0x01, 0x01);
  EXPECT_EQ(irr(b.chip) & irq::MAC_Reset, 0);
  testutil::user_go_offline(b.chip);
  EXPECT_EQ(status(b.chip) & 0x01, 0x00);
  EXPECT_NE(irr(b.chip) & irq::MAC_Reset, 0);
  EXPECT_FALSE(b.master.fdl_status().answer);  // Offline: no answer
  testutil::user_start(b.chip);
  EXPECT_EQ(status(b.chip) & 0x01, 0x01);
}

// manual-quotes.md Confirmed (SPC3 status text, Beckhoff copy): "For addresses > 1536 bytes,
// 1024 is subtracted"; chip-facts §3: bit 3 RAM_Access_Violation. SPC3 only (1.5 KB RAM): a byte
// written at 300h reads back at 700h = 300h + 400h; Status_Reg bit 3 is set.
TEST(BufferSmSpc3, RamAccessViolation_Above1536Bytes1024IsSubtracted) {
  Chip c({Profile::spc3, BusMode::intel, 0});
  c.set_log_sink(nullptr);
  c.write(0x300, 0x77);
  EXPECT_EQ(c.read(0x700), 0x77);
  EXPECT_EQ(status(c) & 0x08, 0x08);
}

// chip-facts §4.2 / §7 [S-RU-SPC3][S-VPC3C-UWD]: Res_User_WD "reload user watchdog"; "Res_User_WD
// = 1 reloads it at the next DX". R_User_WD_Value 3 and Res_User_WD written by the ISR on every
// DX_Out: ten exchanges in a row are all answered, the slave stays in Data_Exchange.
TEST_P(UserWatchdog, ResUserWdReloadsAtTheNextDataExchange) {
  ResponderConfig rc;
  rc.user_wd_value = 3;
  rc.user_watchdog = true;
  Bench b(GetParam(), 12'000'000, rc);
  ASSERT_TRUE(b.master.startup());
  for (int i = 1; i <= 10; ++i) EXPECT_TRUE(b.master.data_exchange({1, 1, 1, 1}).answer) << i;
  EXPECT_EQ(dp_bits(status(b.chip)), kDataEx);
}

// chip-facts §4.2 [S-RU-SPC3]: EOI "ASIC clears the bit", User_Leave_Master "ASIC clears the
// bit". The Mode_Reg1 read-back (15h, [S-VPC3-IF]; dpc31 the same address, modelled) shows bits 1
// and 3 as 0 right after they were set through Mode_Reg1_S; Start_SPC3 (bit 0) stays 1 (the
// DPC31 started by MAC_Start: its Mode_Reg1 has no Start_SPC3, bit 0 reads 0, docs/dpc31.md).
namespace {
class ModeReg1ReadBack : public ::testing::TestWithParam<Profile> {};
}  // namespace

TEST_P(ModeReg1ReadBack, EoiAndUserLeaveMasterClearedByTheAsic) {
  Bare b(GetParam());
  const std::uint8_t start = GetParam() == Profile::dpc31 ? 0x00 : 0x01;
  b.chip.write(wr(b.chip, RegId::Mode_Reg1_S), 0x02);
  EXPECT_EQ(b.chip.read(0x15) & 0x0B, start);
  testutil::user_leave_master(b.chip);
  EXPECT_EQ(b.chip.read(0x15) & 0x0B, start);
}

INSTANTIATE_TEST_SUITE_P(Vpc3AndDpc31, ModeReg1ReadBack,
                         ::testing::Values(Profile::vpc3plus, Profile::dpc31),
                         [](const auto& i) { return testutil::pname(i.param); });

INSTANTIATE_TEST_SUITE_P(Spc3AndVpc3, UserWatchdog,
                         ::testing::Values(Profile::spc3, Profile::vpc3plus),
                         [](const auto& i) { return testutil::pname(i.param); });

INSTANTIATE_TEST_SUITE_P(Profiles, BufferSm, ::testing::ValuesIn(kAllProfiles),
                         [](const auto& i) { return testutil::pname(i.param); });

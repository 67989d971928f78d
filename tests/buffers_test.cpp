// Buffer state machines and the Prm/Cfg/SSA handshakes through their command reads. Expected
// bytes are worked out by hand from chip-facts §5 (F 7:6, U 5:4, N 3:2, D 1:0).
#include <gtest/gtest.h>

#include "dpc31/reg_ids.hpp"
#include "harness.hpp"
#include "test_util.hpp"

using namespace dpc31;

namespace {

class Buffers : public testutil::ChipTest {
 protected:
  std::uint32_t cell(const Chip& c, std::string_view name) {
    return static_cast<std::uint32_t>(find_reg(c.profile(), name)->read_addr);
  }
};

}  // namespace

TEST_P(Buffers, DoutRotation) {
  Chip c = make();
  // dpc31 shows N_Cl in bit 7 instead of F (see docs/decisions.md).
  const auto sm = [&](std::uint8_t v) {
    return GetParam().profile == Profile::dpc31 ? static_cast<std::uint8_t>(v & 0x3F) : v;
  };
  EXPECT_EQ(c.read(0x0A), sm(0xE1));  // reset: D=1 N=Nil U=2 F=3
  // Buffer 1 (D) holds stale bytes; Start clears it and passes it on to N.
  const ProfileDesc& p = c.profile();
  const auto seg = static_cast<std::uint8_t>((p.user_base >> p.segment_shift) + 1);
  c.write(cell(c, "R_Len_Dout_Buf"), 4);
  c.write(cell(c, "R_Dout_Buf_Ptr1"), seg);
  const std::uint32_t buf1 = static_cast<std::uint32_t>(seg) << p.segment_shift;
  for (std::uint32_t i = 0; i < 5; ++i) c.write(buf1 + i, 0xAA);
  testutil::user_start(c);
  for (std::uint32_t i = 0; i < 4; ++i) EXPECT_EQ(c.peek(buf1 + i), 0x00) << i;
  EXPECT_EQ(c.peek(buf1 + 4), 0xAA);  // only R_Len_Dout_Buf bytes are cleared
  EXPECT_EQ(c.read(0x0A), sm(0x27));  // D=3 N=1 U=2 F=Nil
  EXPECT_EQ(c.read(0x0B), 0x0D);      // cleared | new | U=1
  EXPECT_EQ(c.read(0x0A), sm(0x93));  // D=3 N=Nil U=1 F=2
  EXPECT_EQ(c.read(0x0B), 0x09);      // nothing new; U=1 still the cleared buffer
  harness::asic_dout_received(c);
  EXPECT_EQ(c.read(0x0A), sm(0x1E));  // D=2 N=3 U=1 F=Nil
  EXPECT_EQ(c.read(0x0B), 0x07);      // new | U=3, data (not cleared)
  EXPECT_EQ(c.read(0x0A), sm(0x72));  // D=2 N=Nil U=3 F=1
  // A slow user: two telegrams before the fetch; the user gets the newest.
  harness::asic_dout_received(c);
  EXPECT_EQ(c.read(0x0A), sm(0x39));  // D=1 N=2 U=3 F=Nil
  harness::asic_dout_received(c);
  EXPECT_EQ(c.read(0x0A), sm(0x36));  // D=2 N=1 U=3 F=Nil
  EXPECT_EQ(c.read(0x0B), 0x05);      // new | U=1
  EXPECT_EQ(c.read(0x0A), sm(0xD2));  // D=2 N=Nil U=1 F=3
}

TEST_P(Buffers, DinRotation) {
  Chip c = make();
  EXPECT_EQ(c.read(0x08), 0xE1);
  EXPECT_EQ(c.peek(0x09), 0x03);  // peek previews the command without doing it
  EXPECT_EQ(c.read(0x08), 0xE1);
  EXPECT_EQ(c.read(0x09), 0x03);  // U=2 -> N; new U = 3
  EXPECT_EQ(c.read(0x08), 0x39);  // D=1 N=2 U=3 F=Nil
  EXPECT_EQ(harness::asic_din_fetch(c), 2);
  EXPECT_EQ(c.read(0x08), 0x72);             // D=2 N=Nil U=3 F=1
  EXPECT_EQ(harness::asic_din_fetch(c), 2);  // nothing new: D resent
  EXPECT_EQ(c.read(0x09), 0x01);             // U=3 -> N; new U = 1 (from F)
  EXPECT_EQ(c.read(0x09), 0x03);             // again before a send: old N comes back as U
  EXPECT_EQ(c.read(0x08), 0x36);             // D=2 N=1 U=3 F=Nil
}

TEST_P(Buffers, DiagExchange) {
  Chip c = make();
  EXPECT_EQ(c.read(0x0C), 0x09);  // buffer 1 User, buffer 2 ASIC
  EXPECT_EQ(c.read(0x0D), 0x02);  // buffer 2 now the user's
  EXPECT_EQ(c.read(0x0C), 0x06);
  EXPECT_NE(c.peek_reg(RegId::Int_Req_Reg) & irq::Diag_Buffer_Changed, 0);
  EXPECT_NE(c.peek_reg(RegId::Status_Reg) & 0x04, 0);  // Diag_Flag
  // The ASIC sends buffer 1; meanwhile the user hands buffer 2: both with the ASIC (00).
  harness::asic_diag_send_begin(c);
  EXPECT_EQ(c.read(0x0C), 0x07);  // buffer 1 SPC3_Send_Mode, buffer 2 User
  testutil::bus_write16(c, 0x02, 16, irq::Diag_Buffer_Changed);
  EXPECT_EQ(c.read(0x0D), 0x00);
  EXPECT_EQ(c.read(0x0C), 0x0B);  // buffer 2 ASIC, buffer 1 still being sent
  EXPECT_EQ(c.peek_reg(RegId::Int_Req_Reg) & irq::Diag_Buffer_Changed, 0);
  harness::asic_diag_send_end(c);  // buffer 1 returns: Diag_Buffer_Changed now
  EXPECT_EQ(c.read(0x0C), 0x09);
  EXPECT_NE(c.peek_reg(RegId::Int_Req_Reg) & irq::Diag_Buffer_Changed, 0);
  // SPC3 p.32: Diag_Flag is cleared when the master fetched the current buffer: it fetched
  // buffer 1, and buffer 2, handed over meanwhile, is the current one: still set.
  EXPECT_NE(c.peek_reg(RegId::Status_Reg) & 0x04, 0);
  EXPECT_EQ(c.read(0x0D), 0x02);  // user hands buffer 1; unsent buffer 2 comes back at once
}

TEST_P(Buffers, PrmCfgHandshakes) {
  Chip c = make();
  testutil::user_start(c);
  EXPECT_EQ(c.read(0x0E), 0x03);  // nothing to accept: not allowed
  harness::asic_prm_received(c);
  harness::asic_prm_received(c);  // a second Set_Prm while the user checks the first
  testutil::bus_write16(c, 0x02, 16, irq::New_Prm_Data);  // IAR cannot clear it
  EXPECT_NE(c.peek_reg(RegId::Int_Req_Reg) & irq::New_Prm_Data, 0);
  EXPECT_EQ(c.read(0x0E), 0x01);  // conflict: re-check the newer buffer
  EXPECT_NE(c.peek_reg(RegId::Int_Req_Reg) & irq::New_Prm_Data, 0);
  EXPECT_EQ(c.read(0x0E), 0x00);  // finished
  EXPECT_EQ(c.peek_reg(RegId::Int_Req_Reg) & irq::New_Prm_Data, 0);
  EXPECT_EQ(c.dp_state(), DpState::Wait_Cfg);
  // En_Change_Cfg_Buffer: the OK read swaps the Cfg and Read_Cfg buffers.
  c.write(cell(c, "R_Cfg_Buf_Ptr"), 0x11);
  c.write(cell(c, "R_Read_Cfg_Buf_Ptr"), 0x22);
  c.write(0x08, 0x10);
  harness::asic_cfg_received(c);
  EXPECT_EQ(c.read(0x11), 0x00);  // Cfg not OK: back to Wait_Prm
  EXPECT_EQ(c.dp_state(), DpState::Wait_Prm);
  EXPECT_EQ(c.read(cell(c, "R_Cfg_Buf_Ptr")), 0x11);  // no swap on Not_OK
  harness::asic_prm_received(c);
  EXPECT_EQ(c.read(0x0E), 0x00);
  harness::asic_cfg_received(c);
  EXPECT_EQ(c.read(0x10), 0x00);
  EXPECT_EQ(c.dp_state(), DpState::Data_Exchange);
  EXPECT_EQ(c.read(cell(c, "R_Cfg_Buf_Ptr")), 0x22);
  EXPECT_EQ(c.read(cell(c, "R_Read_Cfg_Buf_Ptr")), 0x11);
  EXPECT_EQ(c.read(0x10), 0x03);  // nothing pending any more
}

// Found by fuzz_chip_bytes (tests/fuzz/regressions/chip_bytes/stale_new_prm_data_irq_storm): a
// Leave_Master between Set_Prm and the user's verdict discarded the handshake but left
// New_Prm_Data set; the OK read answered "not allowed" and kept it, Int_Ack_Reg cannot clear it,
// so X/INT stayed active and the firmware's ISR ran forever.
TEST_P(Buffers, NotAllowedVerdictClearsAStaleEvent) {
  Chip c = make();
  testutil::user_start(c);
  testutil::bus_write16(c, 0x04, 16,
                        static_cast<std::uint16_t>(~(irq::New_Prm_Data | irq::New_Cfg_Data)));
  harness::asic_prm_received(c);
  harness::asic_cfg_received(c);
  testutil::user_leave_master(c);  // both telegrams discarded
  EXPECT_TRUE(c.irq_active());
  EXPECT_EQ(c.read(0x0E), 0x03);  // nothing to accept any more
  EXPECT_EQ(c.peek_reg(RegId::Int_Req_Reg) & irq::New_Prm_Data, 0);
  EXPECT_TRUE(c.irq_active());  // New_Cfg_Data still set
  EXPECT_EQ(c.read(0x11), 0x03);
  EXPECT_EQ(c.peek_reg(RegId::Int_Req_Reg) & irq::New_Cfg_Data, 0);
  EXPECT_FALSE(c.irq_active());
  EXPECT_EQ(c.dp_state(), DpState::Wait_Prm);
}

TEST_P(Buffers, SsaBufferFree) {
  Chip c = make();
  harness::asic_ssa_received(c);
  EXPECT_FALSE(c.ssa_buffer_free());
  EXPECT_EQ(c.peek(0x14), 0x00);
  EXPECT_FALSE(c.ssa_buffer_free());  // peek has no side effect
  EXPECT_EQ(c.read(0x14), 0x00);
  EXPECT_TRUE(c.ssa_buffer_free());
}

INSTANTIATE_TEST_SUITE_P(Chips, Buffers, ::testing::ValuesIn(testutil::all_chip_params()),
                         testutil::param_name);

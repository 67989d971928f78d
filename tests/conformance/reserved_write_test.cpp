// Writes of 1s to reserved bits of the set/reset and acknowledge registers (QEMU's guest-error
// rule, anchors §2.3), on every profile and bus mode, the chip's log captured.
#include <algorithm>

#include "conformance.hpp"

using namespace dpc31;

namespace {

class ReservedWrite : public testutil::ChipTest {
 protected:
  [[nodiscard]] std::size_t warnings() const {
    return static_cast<std::size_t>(
        std::count_if(log_.records.begin(), log_.records.end(),
                      [](const LogRecord& r) { return r.level >= LogLevel::warn; }));
  }
};

void write_reg(Chip& c, RegId id, std::uint16_t v) {
  const RegDesc* r = find_reg(c.profile(), id);
  ASSERT_NE(r, nullptr);
  testutil::bus_write16(c, r->write_addr, r->width, v);
}

// QEMU's rule: a write that would change a reserved bit is a guest error. The standard driver
// init (SPC3/VPC3+ drivers: Mode_Reg1_R = FFh, Int_Ack_Reg = FFFFh before Start) writes 1s to
// the reserved bits of a reset and an acknowledge port; their target bits are 0 and a 1 there
// clears them, so nothing changes: no warning. (New_Prm_Data / New_Cfg_Data in Int_Ack_Reg are
// documented as unchanged by it, SPC3 p.22: reported at info level, not as an error.)
TEST_P(ReservedWrite, OnesToResetOrAcknowledgePortsOverZeroReservedBitsAreNoGuestError) {
  Chip c = make();
  write_reg(c, RegId::Mode_Reg1_R, 0xFF);
  write_reg(c, RegId::Int_Ack_Reg, 0xFFFF);
  EXPECT_EQ(warnings(), 0u);
  EXPECT_EQ(log_.count_containing("reserved"), 0u);
  EXPECT_EQ(c.peek_reg(RegId::Mode_Reg1), 0x00);
  EXPECT_EQ(c.peek_reg(RegId::Int_Req_Reg), 0x0000);
}

// The same rule still reports a write that really would change a reserved bit: bit 6 of
// Mode_Reg1 is reserved on every profile, and a 1 to the set port would set it.
TEST_P(ReservedWrite, OneToASetPortOverAZeroReservedBitIsStillAGuestError) {
  Chip c = make();
  write_reg(c, RegId::Mode_Reg1_S, 0x40);
  EXPECT_EQ(warnings(), 1u);
  EXPECT_EQ(log_.count_containing("Mode_Reg1_S: write would change reserved bits 0x0040"), 1u);
  EXPECT_EQ(c.peek_reg(RegId::Mode_Reg1), 0x00);
  EXPECT_FALSE(c.started());
}

INSTANTIATE_TEST_SUITE_P(Profiles, ReservedWrite, ::testing::ValuesIn(testutil::all_chip_params()),
                         testutil::param_name);

}  // namespace

// Seed 003 (DPC31 HW Description p.32): "the interrupt 'DX_OUT' can directly be applied to the
// port PB3 if a global control message is received with 'Sync', provided 'Enable DX_OUT_Port=1'
// was parameterized in the C31_Control register beforehand." Modelled (docs/timing.md): PB3 goes
// high in the cycle the Sync is acted on and low in the cycle the user's acknowledge of DX_Out
// completes.
#include "conformance.hpp"

using namespace dpc31;
using namespace conformance;  // the bench, the ISR that only acknowledges

namespace {

constexpr std::uint8_t kEnable_DX_Out_Port = 0x01;

// An ISR that acknowledges DX_Out (and the rest) and notes the cycle its acknowledge completed.
struct AckDxOut {
  std::uint64_t ack_done = 0;
  void isr(BusPort& c) {
    const Chip& chip = c.chip();
    const std::uint32_t ir = addr(chip, RegId::Int_Reg);
    const std::uint32_t ack = addr(chip, RegId::Int_Ack_Reg);
    const std::uint8_t lo = c.read(ir);
    const std::uint8_t hi = c.read(ir + 1);
    c.write(ack, lo);
    c.write(ack + 1,
            static_cast<std::uint8_t>(hi & ~(irq::New_Prm_Data >> 8) & ~(irq::New_Cfg_Data >> 8)));
    if ((hi & (irq::DX_Out >> 8)) != 0) ack_done = c.cycle();
    c.write(addr(chip, RegId::Mode_Reg1_S), 0x02);  // EOI
  }
};

struct Edges {
  std::vector<std::pair<std::uint64_t, bool>> seen;
};

// Started, Enable_DX_Out_Port set, `user` as the ISR, PB3's edges into `e`.
void enable_port(Bench& b, AckDxOut& user, Edges& e) {
  ASSERT_TRUE(b.master.startup());
  b.chip.write(addr(b.chip, RegId::C31_Control), kEnable_DX_Out_Port);
  b.master.set_firmware([&user](BusPort& c) { user.isr(c); });
  b.chip.on_pb3_change([&e](std::uint64_t c, bool level) { e.seen.emplace_back(c, level); });
}

TEST(Dpc31DxOutPort, SyncDrivesPb3UntilDxOutIsAcknowledged) {
  Bench b(Profile::dpc31);
  AckDxOut user;
  Edges e;
  ASSERT_NO_FATAL_FAILURE(enable_port(b, user, e));
  const Exchange gc = b.master.global_control(kGC_Sync);
  b.master.idle(4'800);
  ASSERT_EQ(e.seen.size(), 2u);
  EXPECT_EQ(e.seen[0], std::make_pair(b.acted(gc), true));
  EXPECT_EQ(e.seen[1], std::make_pair(user.ack_done, false));
  EXPECT_GT(user.ack_done, b.acted(gc));
  EXPECT_FALSE(b.chip.pb3_pin());
}

// Only a Global_Control with Sync drives the port: the DX_Out of a Data_Exchange does not, and
// without Enable_DX_Out_Port nothing does.
TEST(Dpc31DxOutPort, OnlySyncAndOnlyWhenEnabled) {
  Bench b(Profile::dpc31);
  ASSERT_TRUE(b.master.startup());
  Edges e;
  b.chip.on_pb3_change([&e](std::uint64_t c, bool level) { e.seen.emplace_back(c, level); });
  b.master.global_control(kGC_Sync);  // not enabled
  b.master.idle(4'800);
  b.master.global_control(0x10);  // Unsync
  b.master.idle(4'800);
  EXPECT_TRUE(e.seen.empty());
  b.chip.write(addr(b.chip, RegId::C31_Control), kEnable_DX_Out_Port);
  b.master.data_exchange({0x01, 0x02, 0x03, 0x04});  // DX_Out, but no Sync
  b.master.idle(4'800);
  EXPECT_TRUE(e.seen.empty());
}

// Sync and Unsync in one Global_Control: "Function will be inactive" (manual-quotes.md,
// Global_Control), Unsync wins (docs/decisions.md). The user still gets DX_Out, but it is the
// DX_Out of an Unsync, which does not drive PB3.
TEST(Dpc31DxOutPort, SyncWithUnsyncDoesNotDrivePb3) {
  Bench b(Profile::dpc31);
  AckDxOut user;
  Edges e;
  ASSERT_NO_FATAL_FAILURE(enable_port(b, user, e));
  const Exchange gc = b.master.global_control(kGC_Sync | kGC_Unsync);
  b.master.idle(4'800);
  EXPECT_GT(user.ack_done, b.acted(gc));  // the DX_Out came and was acknowledged
  EXPECT_TRUE(e.seen.empty());
  EXPECT_FALSE(b.chip.pb3_pin());
}

// A hardware reset (Chip::reset) clears Int_Req_Reg, DX_Out with it, and C31_Control: PB3 goes
// low in the reset's cycle, the first of the new time line (docs/timing.md, "dpc31 PB3";
// docs/decisions.md, "The twenty-ninth session: s29-chip"), and the observer sees that edge.
TEST(Dpc31DxOutPort, HardwareResetTakesPb3Low) {
  Bench b(Profile::dpc31);
  AckDxOut user;
  Edges e;
  ASSERT_NO_FATAL_FAILURE(enable_port(b, user, e));
  const std::uint32_t mask = addr(b.chip, RegId::Int_Mask_Reg);
  b.chip.write(mask, 0xFF);  // the user serves no interrupt: DX_Out stays
  b.chip.write(mask + 1, 0xFF);
  const Exchange gc = b.master.global_control(kGC_Sync);
  b.master.idle(4'800);
  ASSERT_TRUE(b.chip.pb3_pin());
  b.chip.reset();
  EXPECT_FALSE(b.chip.pb3_pin());
  ASSERT_EQ(e.seen.size(), 2u);
  EXPECT_EQ(e.seen[0], std::make_pair(b.acted(gc), true));
  EXPECT_EQ(e.seen[1], std::make_pair(std::uint64_t{0}, false));
}

}  // namespace

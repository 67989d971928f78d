// VPC3+ interrupt modes (manual-quotes.md): VPC3+C p.50 "The VPC3+C either generates the
// New_GC_Control interrupt after each receipt of a Global_Control telegram (default) or just in
// case if the Global_Control differs from the previous one." Profichip DpCfg.h: Mode_Reg2 bit 0
// GC_Int_Mode "1 - GC Interrupt is generated after every GC telegram (default)"; bit 2 DX_Int_Mode
// "0 - DX Interrupt only generated, if DOUT length not 0 (default). 1 - DX Interrupt generated
// after every DX-telegram"; Mode_Reg3 bit 1 DX_Int_Mode_2 "1 - DX_Out interrupt is only
// generated, if received data is not equal to current data".
#include "conformance.hpp"

using namespace dpc31;
using namespace conformance;  // the bench, the ISR that only acknowledges

namespace {

constexpr std::uint64_t kIsrTime = 4'800;  // 100 us: the ISR runs after an unanswered GC

std::size_t count(const Responder& u, std::size_t from, std::uint16_t bit) {
  std::size_t n = 0;
  for (std::size_t k = from; k < u.interrupts.size(); ++k)
    n += (u.interrupts[k].second & bit) != 0 ? 1 : 0;
  return n;
}

// Mode_Reg2 may only be written while Offline (docs/decisions.md): stop, write, start again.
void set_mode_reg2(Chip& c, std::uint8_t v) {
  testutil::user_go_offline(c);  // Go_Offline
  c.write(addr(c, RegId::Mode_Reg2), v);
  testutil::user_start(c);  // Start_SPC3
}

TEST(Vpc3GcIntMode, DefaultInterruptsOnEveryGlobalControl) {
  Bench b(Profile::vpc3plus);
  ASSERT_TRUE(b.master.startup());
  const std::size_t k = b.user.interrupts.size();
  b.master.global_control(0x08);
  b.master.idle(kIsrTime);
  b.master.global_control(0x08);  // the same command again
  b.master.idle(kIsrTime);
  EXPECT_EQ(count(b.user, k, irq::New_GC_Command), 2u);
}

TEST(Vpc3GcIntMode, ZeroInterruptsOnlyOnAChangedCommand) {
  Bench b(Profile::vpc3plus);
  set_mode_reg2(b.chip, 0x00);
  ASSERT_TRUE(b.master.startup());
  const std::size_t k = b.user.interrupts.size();
  b.master.global_control(0x08);
  b.master.idle(kIsrTime);
  b.master.global_control(0x08);
  b.master.idle(kIsrTime);
  b.master.global_control(0x04);
  b.master.idle(kIsrTime);
  EXPECT_EQ(count(b.user, k, irq::New_GC_Command), 2u);  // 08h (new), 04h (changed)
}

// The comparison is with the R_GC_Command cell, which the user may write (modelled,
// docs/decisions.md): VPC3+C p.50 "The R_GC_Command RAM cell is not initialized by the VPC3+C.
// Therefore the cell has to be preset with 00H during power-up" matters only so. A driver that
// preset 08h misses the first Freeze (08h); once it writes 00h, the same Freeze interrupts.
TEST(Vpc3GcIntMode, ZeroComparesWithTheGcCommandCellTheUserMayWrite) {
  Bench b(Profile::vpc3plus);
  set_mode_reg2(b.chip, 0x00);
  b.chip.write(addr(b.chip, RegId::R_GC_Command), 0x08);
  ASSERT_TRUE(b.master.startup());
  const std::size_t k = b.user.interrupts.size();
  b.master.global_control(0x08);
  b.master.idle(kIsrTime);
  EXPECT_EQ(count(b.user, k, irq::New_GC_Command), 0u);
  b.chip.write(addr(b.chip, RegId::R_GC_Command), 0x00);
  b.master.global_control(0x08);
  b.master.idle(kIsrTime);
  EXPECT_EQ(count(b.user, k, irq::New_GC_Command), 1u);
}

ResponderConfig inputs_only() {
  ResponderConfig rc;
  rc.slave.cfg = {0x13};  // 4 input bytes, no outputs
  rc.slave.out_len = 0;
  return rc;
}

TEST(Vpc3DxIntMode, DefaultNoDxOutWithoutOutputs) {
  Bench b(Profile::vpc3plus, 1'500'000, inputs_only());
  ASSERT_TRUE(b.master.startup());
  const std::size_t k = b.user.interrupts.size();
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(b.master.data_exchange({}).answer);
  EXPECT_EQ(count(b.user, k, irq::DX_Out), 0u);
}

TEST(Vpc3DxIntMode, OneDxOutAfterEveryDataExchange) {
  Bench b(Profile::vpc3plus, 1'500'000, inputs_only());
  set_mode_reg2(b.chip, 0x05);  // GC_Int_Mode, DX_Int_Mode
  ASSERT_TRUE(b.master.startup());
  const std::size_t k = b.user.interrupts.size();
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(b.master.data_exchange({}).answer);
  EXPECT_EQ(count(b.user, k, irq::DX_Out), 3u);
}

TEST(Vpc3DxIntMode2, DxOutOnlyOnChangedOutputs) {
  Bench b(Profile::vpc3plus);
  b.chip.write(addr(b.chip, RegId::Mode_Reg3), 0x02);
  ASSERT_TRUE(b.master.startup());
  const std::size_t n = b.user.outputs.size();
  b.master.data_exchange({0x01, 0x02, 0x03, 0x04});
  b.master.data_exchange({0x01, 0x02, 0x03, 0x04});
  b.master.data_exchange({0x01, 0x02, 0x03, 0x05});
  ASSERT_EQ(b.user.outputs.size(), n + 2);
  EXPECT_EQ(b.user.outputs[n].data, (conformance::Bytes{0x01, 0x02, 0x03, 0x04}));
  EXPECT_EQ(b.user.outputs[n + 1].data, (conformance::Bytes{0x01, 0x02, 0x03, 0x05}));
}

// Without DX_Int_Mode_2 equal outputs still raise DX_Out every time (control).
TEST(Vpc3DxIntMode2, OffEveryExchangeRaisesDxOut) {
  Bench b(Profile::vpc3plus);
  ASSERT_TRUE(b.master.startup());
  const std::size_t n = b.user.outputs.size();
  b.master.data_exchange({0x01, 0x02, 0x03, 0x04});
  b.master.data_exchange({0x01, 0x02, 0x03, 0x04});
  EXPECT_EQ(b.user.outputs.size(), n + 2);
}

}  // namespace

// R_GC_Command at the start of the DP slave, on every profile, through the bus only.
#include "conformance.hpp"

using namespace dpc31;

namespace {

class GcCommandPreset : public ::testing::TestWithParam<Profile> {};

// What the cell reads after the user wrote `before` into it and started the chip (Mode_Reg1_S
// bit 0, Start_SPC3; on the DPC31 a MAC_Start request, the start of the DPS).
std::uint8_t after_start(Chip& c, std::uint8_t before) {
  const auto cell = static_cast<std::uint32_t>(c.addr_of(RegId::R_GC_Command));
  c.write(cell, before);
  EXPECT_EQ(c.read(cell), before);
  testutil::user_start(c);
  EXPECT_TRUE(c.started());
  return c.read(cell);
}

// Seed 003 (DPC31 p.31): "The GC_Command cell is preset with FFh at initialization"; DPC31 p.26
// calls MAC_Start the moment "when the DPS is powered up". SPC3 p.36: "During initialization,
// SPC3 presets the 'R_GC_Command' RAM cell with 00H." VPC3+C p.50: "The R_GC_Command RAM cell is
// not initialized by the VPC3+C. Therefore the cell has to be preset with 00H during power-up."
// So every start (not only the hardware reset) presets it on the DPC31 and the SPC3; the VPC3+
// keeps what the user wrote.
TEST_P(GcCommandPreset, EveryStartPresetsTheCellDpc31FFhSpc300hVpc3plusLeavesIt) {
  Chip c({GetParam(), BusMode::intel, 0});
  c.set_log_sink(nullptr);
  const std::uint8_t preset = GetParam() == Profile::dpc31  ? 0xFF
                              : GetParam() == Profile::spc3 ? 0x00
                                                            : 0x5A;
  EXPECT_EQ(after_start(c, 0x5A), preset);
  // Go_Offline (Mode_Reg1_S bit 2; DPC31 MAC_Stop), then a second start: the same again.
  testutil::user_go_offline(c);
  ASSERT_FALSE(c.started());
  EXPECT_EQ(after_start(c, 0x5A), preset);
}

INSTANTIATE_TEST_SUITE_P(Profiles, GcCommandPreset, ::testing::ValuesIn(kAllProfiles),
                         [](const auto& i) { return testutil::pname(i.param); });

}  // namespace

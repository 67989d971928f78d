// The VPC3+ variants: Status_Reg bits 15..12 tell the firmware which ASIC it runs on.
#include <stdexcept>

#include "conformance.hpp"
#include "dpc31/dpc31_hal.h"

using namespace dpc31;

namespace {

struct VariantCase {
  std::optional<Vpc3Variant> variant;
  const char* hal_name;  // the variant's name (dpc31_create_variant, --variant), nullptr = none
  std::uint8_t asic_type;
  BusMode bus;
};

class Vpc3Variants : public ::testing::TestWithParam<VariantCase> {};

// The Profichip VPC3+ driver (dp_if.h) reads the ASIC type from the high byte of Status_Reg:
// "VPC3_GET_ASIC_TYPE() ( Vpc3Read( bVpc3RoStatus_H ) & AT_MASK )", AT_MASK F0h, AT_VPC3B B0h,
// AT_VPC3C C0h, AT_MPI12X D0h, AT_VPC3S E0h (chip-facts.md §3: "VPC3+: 0x0 VPC3, 0xB VPC3+B, 0xC
// VPC3+C, 0xD MPI12x, 0xE VPC3+S"). The serial-mode driver checks for VPC3+S on every main-loop
// pass. So the chip made as VPC3+B, C or S reads Bh, Ch or Eh there, in both bus modes, before and
// after Start; no variant given is the VPC3+C of the register description (Status_Reg reset C000h).
TEST_P(Vpc3Variants, StatusRegHighNibbleIsTheAsicType) {
  const VariantCase& v = GetParam();
  Chip c({Profile::vpc3plus, v.bus, 0, Engine::event, v.variant});
  c.set_log_sink(nullptr);
  const RegDesc* st = find_reg(c.profile(), RegId::Status_Reg);
  ASSERT_NE(st, nullptr);
  EXPECT_EQ(testutil::bus_read16(c, st->read_addr, 16) >> 12, v.asic_type);
  c.write(static_cast<std::uint32_t>(c.addr_of(RegId::Mode_Reg1_S)), 0x01);  // Start_SPC3
  ASSERT_TRUE(c.started());
  EXPECT_EQ(testutil::bus_read16(c, st->read_addr, 16), (v.asic_type << 12) | 0x0001);
}

INSTANTIATE_TEST_SUITE_P(Variants, Vpc3Variants,
                         ::testing::Values(VariantCase{Vpc3Variant::b, "b", 0xB, BusMode::intel},
                                           VariantCase{Vpc3Variant::c, "c", 0xC, BusMode::intel},
                                           VariantCase{Vpc3Variant::s, "s", 0xE, BusMode::intel},
                                           VariantCase{std::nullopt, nullptr, 0xC, BusMode::intel},
                                           VariantCase{Vpc3Variant::b, "b", 0xB, BusMode::motorola},
                                           VariantCase{Vpc3Variant::s, "s", 0xE,
                                                       BusMode::motorola}),
                         [](const auto& i) {
                           return std::string(i.param.hal_name != nullptr ? i.param.hal_name
                                                                          : "default") +
                                  (i.param.bus == BusMode::intel ? "_intel" : "_motorola");
                         });

// The same through the C HAL a ported driver uses: Vpc3Read(bVpc3RoStatus_H) & AT_MASK, with
// bVpc3RoStatus_H = 05h (Intel byte order, the drivers' VPC3_SERIAL_MODE addressing).
TEST(Vpc3Variants, TheCHalCreatesTheVariantTheDriverChecks) {
  for (const auto& [name, at] : {std::pair{"b", 0xB0}, std::pair{"c", 0xC0}, std::pair{"s", 0xE0},
                                 std::pair{static_cast<const char*>(nullptr), 0xC0}}) {
    dpc31_chip* chip = dpc31_create_variant("vpc3plus", name, 0);
    ASSERT_NE(chip, nullptr);
    dpc31_select(chip);
    EXPECT_EQ(Vpc3Read(0x05) & 0xF0, at) << (name != nullptr ? name : "none");
    dpc31_destroy(chip);
  }
}

// Only the VPC3+ has variants: the SPC3 reads release 0 there (SPC3: "0000 = release 0") and the
// DPC31 has no such field documented; asking either for a VPC3+ variant is refused.
TEST(Vpc3Variants, OnlyTheVpc3plusProfileHasVariants) {
  for (Profile p : {Profile::spc3, Profile::dpc31}) {
    EXPECT_THROW(Chip({p, BusMode::intel, 0, Engine::event, Vpc3Variant::s}),
                 std::invalid_argument);
    EXPECT_EQ(dpc31_create_variant(testutil::pname(p).c_str(), "s", 0), nullptr);
    Chip c({p, BusMode::intel, 0});
    EXPECT_EQ(c.read(static_cast<std::uint32_t>(c.addr_of(RegId::Status_Reg)) + 1) & 0xF0, 0);
  }
  EXPECT_EQ(dpc31_create_variant("vpc3plus", "x", 0), nullptr);
}

}  // namespace

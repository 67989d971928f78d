// The description (and so the generated tables) against the manuals' map in spec.hpp.
#include <gtest/gtest.h>

#include "dpc31/reg_ids.hpp"
#include "test_util.hpp"

using namespace dpc31;

class RegisterSpec : public ::testing::TestWithParam<Profile> {};

TEST_P(RegisterSpec, EveryRegisterMatchesTheManual) {
  const ProfileDesc& p = profile_desc(GetParam());
  const auto rows = spec::rows_for(GetParam());
  EXPECT_EQ(p.regs.size(), rows.size())
      << "the description has registers the spec table lacks or vice versa";
  for (const spec::Row& row : rows) {
    SCOPED_TRACE(std::string(row.name));
    const RegDesc* r = find_reg(p, row.name);
    ASSERT_NE(r, nullptr);
    EXPECT_EQ(r->read_addr, row.read);
    EXPECT_EQ(r->write_addr, row.write);
    EXPECT_EQ(r->width, row.width);
    EXPECT_EQ(r->has_reset, row.reset >= 0);
    if (row.reset >= 0) {
      EXPECT_EQ(r->reset, row.reset);
    }
    EXPECT_EQ(row.policy.size(), static_cast<std::size_t>(row.width));
    EXPECT_EQ(r->rw, spec::mask_of(row.policy, "w"));
    EXPECT_EQ(r->ro, spec::mask_of(row.policy, "rR"));
    EXPECT_EQ(r->w1c, spec::mask_of(row.policy, "cC"));
    EXPECT_EQ(r->w1s, spec::mask_of(row.policy, "sS"));
    EXPECT_EQ(r->pulse, spec::mask_of(row.policy, "CSR"));
    EXPECT_EQ(r->cmd, spec::mask_of(row.policy, "k"));
    EXPECT_EQ(r->wo, spec::mask_of(row.policy, "o"));
    EXPECT_EQ(r->ign, spec::mask_of(row.policy, "i"));
    EXPECT_EQ(r->rsvd, spec::mask_of(row.policy, "-"));
    EXPECT_EQ(r->unimp, spec::mask_of(row.policy, "u"));
    EXPECT_EQ(r->kind == Kind::cell, row.cell);
    EXPECT_EQ(r->kind == Kind::reserved || r->reserved, row.reserved);
    if (row.width == 16) {
      for (int off = 0; off < 2; ++off) {
        EXPECT_EQ(r->intel[off], spec::byte_index_at(BusMode::intel, off));
        EXPECT_EQ(r->motorola[off], spec::byte_index_at(BusMode::motorola, off));
      }
    }
  }
}

TEST_P(RegisterSpec, ProfileLayoutMatchesTheManual) {
  const ProfileDesc& p = profile_desc(GetParam());
  switch (GetParam()) {
    case Profile::spc3:  // 1.5 KB, 8-byte segments, release 0
      EXPECT_EQ(p.ram_begin, 0u);
      EXPECT_EQ(p.ram_size, 1536u);
      EXPECT_EQ(p.user_base, 0x40u);
      EXPECT_EQ(p.segment_shift, 3);
      EXPECT_EQ(p.release, 0);
      break;
    case Profile::vpc3plus:  // 2 KB / 4 KB with 16-byte segments, release C
      EXPECT_EQ(p.ram_size, 2048u);
      EXPECT_EQ(p.ram_size_large, 4096u);
      EXPECT_EQ(p.segment_shift, 3);
      EXPECT_EQ(p.segment_shift_large, 4);
      EXPECT_EQ(p.release, 0xC);
      break;
    case Profile::dpc31:  // 8 KB space, RAM from 0800h, cells from 0840h, users from 08A0h, 32-byte
                          // segments
      EXPECT_EQ(p.address_bits, 13);
      EXPECT_EQ(p.ram_begin, 0x800u);
      EXPECT_EQ(p.ram_size, 6144u);
      EXPECT_EQ(p.cells_base, 0x840u);
      EXPECT_EQ(p.user_base, 0x8A0u);
      EXPECT_EQ(p.segment_shift, 5);
      break;
  }
}

// A field's text is this profile's (the generated header, registers.md, the Verilog include and
// `dpc31 regs` print it): it names only what the profile has. The SPC3's New_GC_Command cited the
// DPC31's New_GC_Int mode, the DPC31's Status_Reg and MAC_Reset a Start_SPC3 and a RAM access
// violation it cannot have (audit s32 siblings, finding 3; chip-facts.md §5.5, registers.md).
TEST_P(RegisterSpec, FieldTextsNameOnlyWhatTheProfileHas) {
  const ProfileDesc& p = profile_desc(GetParam());
  const auto has_field = [&](std::string_view prefix) {
    for (const RegDesc& r : p.regs) {
      for (const FieldDesc& f : r.fields) {
        if (f.name.starts_with(prefix)) return true;
      }
    }
    return false;
  };
  const RegDesc* start = find_reg(p, "Mode_Reg1_S");
  ASSERT_NE(start, nullptr);
  const bool start_acts = (start->ign & fields::Mode_Reg1::Start_SPC3) == 0;
  for (const RegDesc& r : p.regs) {
    for (const FieldDesc& f : r.fields) {
      SCOPED_TRACE(std::string(r.name) + "." + std::string(f.name) + ": " + std::string(f.desc));
      const auto names = [&f](std::string_view what) {
        return f.desc.find(what) != std::string_view::npos;
      };
      EXPECT_TRUE(!names("New_GC_Int") || has_field("New_GC_Int"));
      for (const char* reg : {"Mode_Reg2", "Param_Reg"}) {
        EXPECT_TRUE(!names(reg) || find_reg(p, reg) != nullptr) << reg;
      }
      EXPECT_TRUE(!names("4kB_Mode") || p.ram_size_large != 0);
      EXPECT_TRUE(!names("Start_SPC3") || start_acts);
      EXPECT_TRUE(!names("RAM access violation") || p.violation_from != 0);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Profiles, RegisterSpec, ::testing::ValuesIn(kAllProfiles),
                         [](const auto& i) { return testutil::pname(i.param); });

// UVM RAL built-in register tests (anchors §3.6) as GoogleTest cases over every profile and both
// bus byte orders: hw_reset, bit_bash, front door vs back door, mem_walk, shared access
// (Intel vs Motorola), and accesses to reserved / unmapped addresses.
#include <fmt/core.h>
#include <gtest/gtest.h>

#include "dpc31/reg_ids.hpp"
#include "test_util.hpp"

using namespace dpc31;
using testutil::bus_read16;
using testutil::bus_write16;

namespace {

class Ral : public testutil::ChipTest {};

RegId id_of(Profile p, std::string_view name) { return find_reg(profile_desc(p), name)->id; }

// The register a write side stores into, per the manual: the acknowledge acts on IRR, the
// Mode_Reg1 set/reset pair on Mode_Reg1.
std::string_view target_name(std::string_view name) {
  if (name == "Int_Ack_Reg") return "Int_Req_Reg";
  if (name == "Mode_Reg1_S" || name == "Mode_Reg1_R") return "Mode_Reg1";
  return name;
}

// What one write does to one bit, by the spec policy letter (independent of the emulator).
bool predict(char policy, bool old, bool written) {
  switch (policy) {
    case 'w':
    case 'o':
    case 'u':
      return written;
    case 'c':
    case 'C':
      return written ? false : old;
    case 's':
    case 'S':
      return written ? true : old;
    default:
      return old;
  }
}

}  // namespace

TEST_P(Ral, HwReset) {
  Chip c = make();
  for (const spec::Row& row : spec::rows_for(GetParam().profile)) {
    if (row.reset < 0 || (row.read < 0 && row.write < 0)) continue;
    SCOPED_TRACE(std::string(row.name));
    const auto rsvd = spec::mask_of(row.policy, "-");
    const auto expected = static_cast<std::uint16_t>(row.reset & ~rsvd);
    if (row.read >= 0 && row.policy.find('k') == std::string_view::npos) {
      EXPECT_EQ(bus_read16(c, row.read, row.width), expected);  // front door
    }
    if (row.policy.find('c') == std::string_view::npos &&
        row.policy.find('s') == std::string_view::npos) {
      EXPECT_EQ(c.peek_reg(id_of(GetParam().profile, row.name)), expected);  // back door
    }
  }
}

TEST_P(Ral, BitBash) {
  const Profile prof = GetParam().profile;
  const auto rows = spec::rows_for(prof);
  for (const spec::Row& row : rows) {
    if (row.write < 0 || row.reserved) continue;
    const spec::Row* tgt = nullptr;
    for (const spec::Row& t : rows) {
      if (t.name == target_name(row.name)) tgt = &t;
    }
    ASSERT_NE(tgt, nullptr);
    const auto rsvd = spec::mask_of(tgt->policy, "-");
    const auto full = static_cast<std::uint16_t>(row.width == 16 ? 0xFFFF : 0xFF);
    for (int k = 0; k < row.width; ++k) {
      for (const std::uint16_t pattern : {std::uint16_t{0}, full}) {
        // The back door takes no run state (include/dpc31/chip.hpp, poke_reg): Mode_Reg1's
        // Start_SPC3, Go_Offline, EOI and User_Leave_Master start as the chip has them, 0.
        namespace m1 = fields::Mode_Reg1;
        const auto before = static_cast<std::uint16_t>(
            tgt->name == "Mode_Reg1"
                ? pattern & ~(m1::Start_SPC3 | m1::Go_Offline | m1::EOI | m1::User_Leave_Master)
                : pattern);
        for (bool b : {false, true}) {
          SCOPED_TRACE(fmt::format("{} bit {} before {:04X}h written {}", row.name, k, before, b));
          Chip c = make();
          const RegId target = id_of(prof, tgt->name);
          ASSERT_TRUE(c.poke_reg(target, before));
          // Write the byte lane that holds bit k; its other bits written 0.
          const int lane = k / 8;
          int offset = 0;
          if (row.width == 16) offset = spec::byte_index_at(c.bus_mode(), 0) == lane ? 0 : 1;
          const auto value = static_cast<std::uint8_t>(b ? 1u << (k % 8) : 0u);
          c.write(static_cast<std::uint32_t>(row.write + offset), value);
          std::uint16_t expect = 0;
          const std::size_t n = row.policy.size();
          for (int j = 0; j < row.width; ++j) {
            const char pol = row.policy[n - 1 - static_cast<std::size_t>(j)];
            const bool old = ((before >> j) & 1) != 0;
            bool now = old;
            if (j / 8 == lane) now = predict(pol, old, j == k && b);
            if (pol == 'C' || pol == 'S' || pol == 'R') now = false;  // pulse bits never stay set
            expect = static_cast<std::uint16_t>(expect | (now ? 1u << j : 0u));
          }
          // Documented side effect: Start_SPC3 written while Offline starts the chip, which clears
          // Go_Offline (docs/timing.md, Mode and state changes); the DPC31 starts by request.
          if (row.name == "Mode_Reg1_S" && k == 0 && b && c.profile().id != Profile::dpc31)
            expect = static_cast<std::uint16_t>(expect & ~0x04);
          expect = static_cast<std::uint16_t>(expect & ~rsvd);
          const bool readable = tgt->read >= 0 && tgt->policy.find('k') == std::string_view::npos;
          const std::uint16_t got =
              readable ? bus_read16(c, tgt->read, tgt->width) : c.peek_reg(target);
          EXPECT_EQ(got, expect);
        }
      }
    }
  }
}

TEST_P(Ral, FrontDoorVersusBackDoor) {
  const Profile prof = GetParam().profile;
  for (const spec::Row& row : spec::rows_for(prof)) {
    const auto store = spec::mask_of(row.policy, "wou");
    if (row.write < 0 || store == 0 || row.name == "Int_Ack_Reg") continue;
    SCOPED_TRACE(std::string(row.name));
    const RegId id = id_of(prof, row.name);
    const auto pattern = static_cast<std::uint16_t>(row.width == 16 ? 0xA55A : 0x5A);
    Chip c = make();
    bus_write16(c, row.write, row.width, pattern);  // front door in, back door out
    EXPECT_EQ(c.peek_reg(id), pattern & store);
    if (row.read >= 0) {
      Chip d = make();
      ASSERT_TRUE(d.poke_reg(id, static_cast<std::uint16_t>(~pattern)));  // back door in
      EXPECT_EQ(bus_read16(d, row.read, row.width), static_cast<std::uint16_t>(~pattern) & store);
      for (int off = 0; off < row.width / 8; ++off) {  // peek agrees with the bus, byte by byte
        const auto a = static_cast<std::uint32_t>(row.read + off);
        EXPECT_EQ(d.peek(a), d.read(a));
      }
    }
  }
}

// uvm_mem_walk_seq: write ~k at k, check k-1, over every RAM region of the profile, minus the
// registers that sit on RAM addresses (uvm_mem_walk_seq walks memories, not registers): the
// DPC31's Param_Reg (0872h) and status register (0874h-0875h) among its parameter cells.
TEST_P(Ral, MemWalk) {
  Chip c = make();
  if (GetParam().profile == Profile::vpc3plus) c.write(0x0C, 0x80);  // Mode_Reg2.4kB_Mode
  const auto is_register = [&c](std::uint32_t a) {
    for (const RegDesc& r : c.profile().regs) {
      if (r.kind == Kind::cell) continue;
      for (const std::int32_t base : {r.read_addr, r.write_addr}) {
        if (base >= 0 && a >= static_cast<std::uint32_t>(base) &&
            a < static_cast<std::uint32_t>(base) + r.width / 8u)
          return true;
      }
    }
    return false;
  };
  std::vector<std::uint32_t> walk;
  for (const RegionDesc& r : c.profile().regions) {
    if (!r.ram) continue;
    for (std::uint32_t a = r.begin; a < r.end; ++a) {
      if (!is_register(a)) walk.push_back(a);
    }
  }
  auto pattern = [](std::uint32_t a) { return static_cast<std::uint8_t>(~(a ^ (a >> 8))); };
  for (std::size_t i = 0; i < walk.size(); ++i) {
    c.write(walk[i], pattern(walk[i]));
    if (i > 0) {
      ASSERT_EQ(c.read(walk[i - 1]), pattern(walk[i - 1])) << fmt::format("{:#06x}", walk[i - 1]);
    }
  }
  for (const std::uint32_t a : walk) ASSERT_EQ(c.peek(a), pattern(a)) << fmt::format("{:#06x}", a);
  const ProfileDesc& p = c.profile();
  const std::uint32_t ram = p.ram_size_large != 0 ? p.ram_size_large : p.ram_size;
  // All RAM but the register block (SPC3, VPC3+), or but the DPC31's three register bytes.
  EXPECT_EQ(walk.size(), ram - (p.id == Profile::dpc31 ? 3u : 0x16u));
}

// uvm_reg_mem_shared_access_seq: the same 16-bit value through both byte orders.
TEST_P(Ral, IntelVersusMotorolaViews) {
  const Profile prof = GetParam().profile;
  for (std::string_view name : {"R_User_WD_Value", "Int_Req_Reg", "Mode_Reg0"}) {
    SCOPED_TRACE(std::string(name));
    Chip c = make();
    const RegDesc* r = find_reg(c.profile(), name);
    const auto store = static_cast<std::uint16_t>(r->rw | r->unimp);  // UNIMP bits are stored too
    c.write(static_cast<std::uint32_t>(r->write_addr), 0x12);
    c.write(static_cast<std::uint32_t>(r->write_addr + 1), 0x34);
    // Intel: the lower address holds bits 7..0; Motorola: bits 15..8.
    const std::uint16_t expect = c.bus_mode() == BusMode::intel ? 0x3412 : 0x1234;
    EXPECT_EQ(c.peek_reg(r->id), expect & store);
    EXPECT_EQ(c.peek(static_cast<std::uint32_t>(r->read_addr)),
              0x12 & (c.bus_mode() == BusMode::intel ? store : store >> 8));
  }
  // The release code sits in Status_Reg bits 15..12: the high byte's address depends on the mode.
  Chip c = make();
  const std::uint32_t high = c.bus_mode() == BusMode::intel ? 0x05 : 0x04;
  EXPECT_EQ(c.read(high), prof == Profile::vpc3plus ? 0xC0 : 0x00);
}

TEST_P(Ral, ReservedAddressesAreLoggedByName) {
  for (const spec::Row& row : spec::rows_for(GetParam().profile)) {
    if (!row.reserved) continue;
    SCOPED_TRACE(std::string(row.name));
    Chip c = make();
    log_.clear();
    if (row.read >= 0 && !row.cell) {
      EXPECT_EQ(c.read(static_cast<std::uint32_t>(row.read)), 0);
    }
    if (row.write >= 0) c.write(static_cast<std::uint32_t>(row.write), 0xA5);
    const std::size_t accesses =
        (row.read >= 0 && !row.cell ? 1u : 0u) + (row.write >= 0 ? 1u : 0u);
    EXPECT_EQ(log_.count_containing(std::string(row.name)), accesses);
  }
}

// Every unmapped address reads 00h and ignores writes; the log names the first accesses and then
// counts (docs/decisions.md, "Logs that never flood"): the first line says the likely cause, the
// first 16 addresses get a line each, and then one line at 10, 100, 1 000, ... accesses.
TEST_P(Ral, UnmappedAddressesReadZeroAndAreLogged) {
  Chip c = make();
  const ProfileDesc& p = c.profile();
  std::size_t unmapped = 0;
  for (const RegionDesc& r : p.regions) {
    if (r.ram || r.name == "processor parameters" || r.name == "access violation") continue;
    for (std::uint32_t a = r.begin; a < r.end; ++a) {
      c.write(a, 0xFF);
      ASSERT_EQ(c.read(a), 0) << a;
      ++unmapped;
    }
  }
  EXPECT_EQ(unmapped, p.id == Profile::dpc31 ? 0x800u - 0x18u : 0u);
  if (unmapped != 0) {
    // 4 048 accesses: 16 address lines and the counts at 10, 100 and 1 000.
    EXPECT_EQ(log_.count_containing("unmapped"), 16u + 3u);
    EXPECT_EQ(log_.count_containing("--profile"), 1u);
    EXPECT_EQ(log_.count_containing("1000 accesses to unmapped addresses so far"), 1u);
  }
  log_.clear();
  c.read(0x10000u | p.user_base);  // address lines the chip does not have
  EXPECT_EQ(log_.count_containing("beyond"), 1u);
}

// QEMU's rule: only a write that would change a reserved bit is reported.
TEST_P(Ral, ReservedBitWritesFollowQemusRule) {
  Chip c = make();
  const std::uint16_t rsvd =
      spec::mask_of(spec::row(GetParam().profile, "Int_Req_Reg").policy, "-");
  bus_write16(c, 0x04, 16, 0xFFFF);  // IMR: reserved bits already 1 (reset FFFFh): no change
  EXPECT_EQ(log_.count_containing("reserved bits"), 0u);
  bus_write16(c, 0x00, 16, 0xFFFF);  // IRR: reserved bits are 0, one report per lane holding some
  const std::size_t lanes = ((rsvd & 0x00FF) != 0 ? 1u : 0u) + ((rsvd & 0xFF00) != 0 ? 1u : 0u);
  EXPECT_EQ(log_.count_containing("Int_Req_Reg: write would change reserved bits"), lanes);
  EXPECT_EQ(c.peek_reg(RegId::Int_Req_Reg), static_cast<std::uint16_t>(~rsvd));
}

INSTANTIATE_TEST_SUITE_P(Chips, Ral, ::testing::ValuesIn(testutil::all_chip_params()),
                         testutil::param_name);

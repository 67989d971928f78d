// The SPC3's Status_Reg bit 1: manual-quotes.md ("Confirmed"): "SPC3 status bit 1 FDL_IND_ST".
// The quote names the bit and gives it no behaviour; regs/dpc31_regs.json's description reaches
// the user through every generated door, each checked here by the name the quote gives.
#include <fstream>
#include <sstream>
#include <string>

#include "conformance.hpp"
#include "dpc31/dpc31_regs.h"

using namespace dpc31;

namespace {

std::string slurp(const std::string& rel) {
  std::ifstream in(std::string(SOURCE_DIR) + "/" + rel);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The line of `text` that starts with `prefix` ("" when there is none).
std::string line_starting(const std::string& text, const std::string& prefix) {
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.starts_with(prefix)) return line;
  }
  return "";
}

TEST(Spc3StatusReg, Bit1IsFdlIndSt_InEveryGeneratedDoor) {
  // The C++ register table (find_reg, the CLI's and Python's source).
  const RegDesc* st = find_reg(profile_desc(Profile::spc3), RegId::Status_Reg);
  ASSERT_NE(st, nullptr);
  std::string bit1;
  for (const FieldDesc& f : st->fields) {
    if (f.lsb == 1 && f.width == 1) bit1 = std::string(f.name);
  }
  EXPECT_EQ(bit1, "FDL_IND_ST");
  // The C header of the drivers (include/dpc31/dpc31_regs.h).
  EXPECT_EQ(SPC3_Status_Reg_FDL_IND_ST_Pos, 1u);
  EXPECT_EQ(SPC3_Status_Reg_FDL_IND_ST_Msk, 0x0002u);
  // The Verilog header (rtl/dpc31_regs.vh).
  const std::string vh = slurp("rtl/dpc31_regs.vh");
  EXPECT_EQ(line_starting(vh, "`define SPC3_Status_Reg_FDL_IND_ST_POS"),
            "`define SPC3_Status_Reg_FDL_IND_ST_POS                  1");
  EXPECT_EQ(line_starting(vh, "`define SPC3_Status_Reg_FDL_IND_ST_W"),
            "`define SPC3_Status_Reg_FDL_IND_ST_W                    1");
  // The register document (docs/registers.md): the SPC3 section's Status_Reg row.
  const std::string md = slurp("docs/registers.md");
  const std::size_t spc3 = md.find("## Siemens SPC3");
  ASSERT_NE(spc3, std::string::npos);
  const std::string section = md.substr(spc3, md.find("\n## ", spc3) - spc3);
  EXPECT_NE(line_starting(section, "| 0x004 | - | `Status_Reg` |").find(", 1 FDL_IND_ST RO, "),
            std::string::npos);
}

// No behaviour in the quote: the bit is named, not modelled, and reads 0 on the bus (docs/
// decisions.md) at reset, after Start_SPC3 and in Data_Exchange.
TEST(Spc3StatusReg, Bit1ReadsZeroOnTheBus) {
  conformance::Bench b(Profile::spc3);
  const auto addr = static_cast<std::uint32_t>(b.chip.addr_of(RegId::Status_Reg));
  // The bench has started the chip: Offline_Passive_Idle 1 (SPC3 text, chip-facts.md §3).
  EXPECT_EQ(b.chip.read(addr) & 0x03, 0x01);
  ASSERT_TRUE(b.master.startup());
  EXPECT_EQ(b.chip.read(addr) & 0x33, 0x21);  // DP_State 10 Data_Exchange, bit 1 still 0
  Chip fresh({Profile::spc3, BusMode::intel, 0});
  EXPECT_EQ(fresh.read(addr) & 0x02, 0);
}

}  // namespace

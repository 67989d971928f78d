// ctest reggen_tables_roundtrip: the compiled tables (generated reg_tables.cpp) must describe
// exactly what reggen read from the JSON. The emitters run on the compiled-in tables have to
// reproduce reggen's outputs byte for byte, and a few facts of the description are spot-checked.
//   reggen_tables_roundtrip <DPC31_GEN_DIR>
#include <fmt/format.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "dpc31/reg_ids.hpp"
#include "dpc31/regdesc.hpp"
#include "regfmt.hpp"

namespace {

int g_failures = 0;

void check(bool ok, const std::string& what) {
  if (!ok) {
    fmt::print(stderr, "FAIL: {}\n", what);
    ++g_failures;
  }
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

const dpc31::RegDesc& reg(dpc31::Profile p, std::string_view name) {
  const dpc31::RegDesc* r = dpc31::find_reg(dpc31::profile_desc(p), name);
  if (r == nullptr) {
    fmt::print(stderr, "FAIL: register {} missing\n", name);
    std::exit(1);
  }
  return *r;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace dpc31;
  if (argc != 2) {
    fmt::print(stderr, "usage: reggen_tables_roundtrip <generated dir>\n");
    return 2;
  }
  const std::string dir = argv[1];
  std::vector<const ProfileDesc*> profiles;
  for (Profile p : kAllProfiles) profiles.push_back(&profile_desc(p));
  const std::vector<std::string> names(std::begin(kRegIdNames), std::end(kRegIdNames));

  const std::pair<std::string, std::string> outputs[] = {
      {"include/dpc31/reg_ids.hpp", regfmt::emit_reg_ids(names)},
      {"include/dpc31/reg_fields.hpp", regfmt::emit_reg_fields(profiles)},
      {"reg_tables.cpp", regfmt::emit_cpp_tables(profiles, chip_timing(), names)},
      {"include/dpc31/dpc31_regs.h", regfmt::emit_c_header(profiles)},
      {"dpc31_regs.vh", regfmt::emit_verilog(profiles)},
      {"registers.md", regfmt::emit_markdown(profiles)},
  };
  for (const auto& [file, text] : outputs) {
    check(read_file(dir + "/" + file) == text,
          file + " differs from the emitters' output on the compiled tables");
  }

  // Spot checks against regs/dpc31_regs.json.
  check(reg(Profile::dpc31, "R_TS_Adr").read_addr == 0x0840, "dpc31 R_TS_Adr at 0840h");
  check(reg(Profile::spc3, "R_TS_Adr").write_addr == 0x016, "spc3 R_TS_Adr at 016h");
  check(reg(Profile::vpc3plus, "Mode_Reg1").read_addr == 0x15,
        "vpc3plus Mode_Reg1 readable at 15h");
  check(reg(Profile::spc3, "Mode_Reg1").read_addr == -1, "spc3 Mode_Reg1 not readable");
  const RegDesc& ack = reg(Profile::spc3, "Int_Ack_Reg");
  check(ack.target == RegId::Int_Req_Reg, "Int_Ack_Reg acts on Int_Req_Reg");
  check((ack.ign & (1u << 11)) != 0 && (ack.w1c & (1u << 11)) == 0, "Int_Ack_Reg New_Prm_Data IGN");
  check(reg(Profile::spc3, "Mode_Reg1_S").pulse == 0x0A,
        "Mode_Reg1 EOI and User_Leave_Master pulse");
  check(reg(Profile::vpc3plus, "Status_Reg").reset == 0xC000, "vpc3plus Status_Reg release C");
  check(reg(Profile::spc3, "Int_Req_Reg").motorola[0] == 1, "Motorola: high byte first");
  check(reg(Profile::spc3, "Reserved_17h").reserved, "Reserved_17h is a reserved cell");
  check(!reg(Profile::spc3, "New_Din_Buffer_Cmd").has_reset, "command reads have no reset value");
  // Plain lanes (RegDesc::plain): IMR's two lanes are storage (reserved bits included), a port,
  // a command read, a pulse lane (Mode_Reg1_S) and a reserved cell are not.
  check(reg(Profile::spc3, "Int_Mask_Reg").plain == 0b11, "Int_Mask_Reg: both lanes plain");
  check(ack.plain == 0, "Int_Ack_Reg (a port) not plain");
  check(reg(Profile::spc3, "Mode_Reg1_S").plain == 0, "Mode_Reg1_S not plain");
  check(reg(Profile::spc3, "New_Din_Buffer_Cmd").plain == 0, "a command read is not plain");
  check(reg(Profile::spc3, "Reserved_17h").plain == 0, "a reserved cell is not plain");
  check(reg(Profile::spc3, "R_TS_Adr").plain == 0b01, "a cell is plain");
  check(find_reg(profile_desc(Profile::dpc31), RegId::Param_Reg) != nullptr, "find_reg by id");
  check(kRegIdNames[static_cast<std::size_t>(RegId::Mode_Reg1)] == "Mode_Reg1", "kRegIdNames");

  for (const ProfileDesc* p : profiles) {
    const auto j = nlohmann::json::parse(regfmt::emit_json(*p));
    check(j["registers"].size() == p->regs.size(),
          fmt::format("{}: emit_json lists every register", p->name));
    check(!regfmt::emit_text(*p).empty(), "emit_text");
  }
  if (g_failures == 0) fmt::print("reggen_tables_roundtrip: ok\n");
  return g_failures == 0 ? 0 : 1;
}

// The C++ emitters of the register description (see regfmt.hpp): dpc31/reg_ids.hpp and the
// register tables the emulator compiles (reg_tables.cpp), from the compiled types of
// dpc31/regdesc.hpp.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <set>
#include <stdexcept>
#include <utility>

#include "regfmt.hpp"

namespace dpc31::regfmt {

namespace {

std::string cpp_string(std::string_view s) {
  std::string out = "\"";
  for (char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    switch (ch) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      default:
        if (c < 0x20 || c == 0x7F) {
          fmt::format_to(std::back_inserter(out), "\\{:03o}", c);
        } else {
          out += ch;
        }
    }
  }
  out += '"';
  return out;
}

std::string cpp_bool(bool b) { return b ? "true" : "false"; }

std::string reg_id(std::span<const std::string> reg_names, RegId id) {
  const auto i = static_cast<std::size_t>(id);
  if (i >= reg_names.size()) {
    throw std::logic_error(
        fmt::format("RegId {} has no name (only {} names)", i, reg_names.size()));
  }
  return "RegId::" + reg_names[i];
}

std::string profile_enum(Profile id) {
  const std::string_view name = profile_name(id);
  if (name == "?") throw std::logic_error("bad profile id");
  return fmt::format("Profile::{}", name);
}

}  // namespace

std::string emit_reg_ids(std::span<const std::string> reg_names) {
  std::string out = fmt::format(
      "// dpc31/reg_ids.hpp -- one RegId per register name of regs/dpc31_regs.json.\n"
      "// {}.\n"
      "#pragma once\n\n"
      "#include <cstddef>\n#include <cstdint>\n#include <string_view>\n\n"
      "#include \"dpc31/regdesc.hpp\"\n\n"
      "namespace dpc31 {{\n\n"
      "enum class RegId : std::uint16_t {{\n",
      kGeneratedBanner);
  std::size_t width = 0;
  for (const auto& n : reg_names) width = std::max(width, n.size() + 1);
  for (std::size_t i = 0; i < reg_names.size(); ++i) {
    fmt::format_to(std::back_inserter(out), "  {:<{}}  // {}\n", reg_names[i] + ",", width, i);
  }
  fmt::format_to(std::back_inserter(out),
                 "}};\n\ninline constexpr std::size_t kRegIdCount = {};\n\n"
                 "// Name of each RegId, indexed by its value.\n"
                 "inline constexpr std::string_view kRegIdNames[kRegIdCount] = {{\n",
                 reg_names.size());
  for (const auto& n : reg_names)
    fmt::format_to(std::back_inserter(out), "    {},\n", cpp_string(n));
  out += "};\n\n}  // namespace dpc31\n";
  return out;
}

std::string emit_cpp_tables(Profiles profiles, const ChipTiming& timing,
                            std::span<const std::string> reg_names) {
  std::string out = fmt::format(
      "// reg_tables.cpp -- the register description tables (dpc31/regdesc.hpp).\n"
      "// {}.\n"
      "#include <cstddef>\n\n"
      "#include \"dpc31/reg_ids.hpp\"\n#include \"dpc31/regdesc.hpp\"\n\n"
      "namespace dpc31 {{\n\n"
      "static_assert(kRegIdCount == {}, \"reg_ids.hpp does not match reg_tables.cpp\");\n",
      kGeneratedBanner, reg_names.size());
  for (const ProfileDesc* pp : profiles) {
    const ProfileDesc& p = *pp;
    const std::string P{p.macro};
    fmt::format_to(std::back_inserter(out), "\n// ---- {} ({}) ----\n\n", p.title, p.name);
    if (p.regs.empty()) throw std::logic_error(fmt::format("profile {} has no registers", p.name));
    // Field arrays.
    for (const RegDesc& r : p.regs) {
      if (r.fields.empty()) continue;
      fmt::format_to(std::back_inserter(out), "static constexpr FieldDesc k{}_{}_fields[] = {{\n",
                     P, r.name);
      for (const FieldDesc& f : r.fields) {
        fmt::format_to(std::back_inserter(out),
                       "    {{.name = {}, .lsb = {}, .width = {}, .access = Access::{}, "
                       ".pulse = {}, .desc = {}}},\n",
                       cpp_string(f.name), f.lsb, f.width, access_name(f.access), cpp_bool(f.pulse),
                       cpp_string(f.desc));
      }
      out += "};\n";
    }
    // Registers.
    fmt::format_to(std::back_inserter(out), "\nstatic constexpr RegDesc k{}_regs[] = {{\n", P);
    for (const RegDesc& r : p.regs) {
      std::string mask_init;
      for (const NamedMask& nm : masks(r)) {
        fmt::format_to(std::back_inserter(mask_init), " .{} = {},", nm.name, hex(nm.value, 4));
      }
      mask_init.pop_back();
      fmt::format_to(
          std::back_inserter(out),
          "    {{.id = {},\n"
          "     .name = {},\n"
          "     .kind = Kind::{},\n"
          "     .block = Block::{},\n"
          "     .width = {},\n"
          "     .has_reset = {},\n"
          "     .reset = {},\n"
          "     .read_addr = {},\n"
          "     .write_addr = {},\n"
          "     .target = {},\n"
          "    {},\n"
          "     .intel = {{{}, {}}},\n"
          "     .motorola = {{{}, {}}},\n"
          "     .documented = {},\n"
          "     .source = {},\n"
          "     .note = {},\n"
          "     .desc = {},\n"
          "     .fields = {},\n"
          "     .reserved = {},\n"
          "     .alias = {},\n"
          "     .plain = {:#04b}}},\n",
          reg_id(reg_names, r.id), cpp_string(r.name), kind_name(r.kind), block_name(r.block),
          r.width, cpp_bool(r.has_reset), hex(r.reset, 4),
          r.read_addr < 0 ? std::string{"-1"} : hex(static_cast<std::uint32_t>(r.read_addr), 4),
          r.write_addr < 0 ? std::string{"-1"} : hex(static_cast<std::uint32_t>(r.write_addr), 4),
          reg_id(reg_names, r.target), mask_init, r.intel[0], r.intel[1], r.motorola[0],
          r.motorola[1], cpp_bool(r.documented), cpp_string(r.source), cpp_string(r.note),
          cpp_string(r.desc),
          r.fields.empty() ? std::string{"{}"} : fmt::format("k{}_{}_fields", P, r.name),
          cpp_bool(r.reserved), cpp_string(r.alias), r.plain);
    }
    out += "};\n";
    // Regions.
    if (!p.regions.empty()) {
      fmt::format_to(std::back_inserter(out), "\nstatic constexpr RegionDesc k{}_regions[] = {{\n",
                     P);
      for (const RegionDesc& g : p.regions) {
        fmt::format_to(std::back_inserter(out),
                       "    {{.name = {}, .begin = {}, .end = {}, .ram = {}, .reserved = {}, "
                       ".desc = {}}},\n",
                       cpp_string(g.name), hex(g.begin, 4), hex(g.end, 4), cpp_bool(g.ram),
                       cpp_bool(g.reserved), cpp_string(g.desc));
      }
      out += "};\n";
    }
    // RAM layouts: the values of each byte, the bytes of each layout, the layouts.
    for (std::size_t li = 0; li < p.layouts.size(); ++li) {
      const LayoutDesc& l = p.layouts[li];
      for (std::size_t bi = 0; bi < l.bytes.size(); ++bi) {
        if (l.bytes[bi].values.empty()) continue;
        fmt::format_to(std::back_inserter(out),
                       "\nstatic constexpr LayoutValue k{}_layout{}_byte{}[] = {{\n", P, li, bi);
        for (const LayoutValue& v : l.bytes[bi].values) {
          fmt::format_to(std::back_inserter(out),
                         "    {{.name = {}, .value = {}, .mask = {}, .desc = {}}},\n",
                         cpp_string(v.name), hex(v.value, 2), cpp_bool(v.mask), cpp_string(v.desc));
        }
        out += "};\n";
      }
      fmt::format_to(std::back_inserter(out), "\nstatic constexpr LayoutByte k{}_layout{}[] = {{\n",
                     P, li);
      for (std::size_t bi = 0; bi < l.bytes.size(); ++bi) {
        const LayoutByte& b = l.bytes[bi];
        fmt::format_to(
            std::back_inserter(out),
            "    {{.name = {}, .offset = {}, .desc = {}, .values = {}}},\n", cpp_string(b.name),
            b.offset, cpp_string(b.desc),
            b.values.empty() ? std::string{"{}"} : fmt::format("k{}_layout{}_byte{}", P, li, bi));
      }
      out += "};\n";
    }
    if (!p.layouts.empty()) {
      fmt::format_to(std::back_inserter(out), "\nstatic constexpr LayoutDesc k{}_layouts[] = {{\n",
                     P);
      for (std::size_t li = 0; li < p.layouts.size(); ++li) {
        const LayoutDesc& l = p.layouts[li];
        fmt::format_to(std::back_inserter(out),
                       "    {{.name = {}, .size = {}, .source = {}, .desc = {}, .bytes = "
                       "k{}_layout{}}},\n",
                       cpp_string(l.name), l.size, cpp_string(l.source), cpp_string(l.desc), P, li);
      }
      out += "};\n";
    }
    // The profile.
    fmt::format_to(
        std::back_inserter(out),
        "\nstatic constexpr ProfileDesc k{P}_profile{{\n"
        "    .id = {id},\n"
        "    .name = {name},\n"
        "    .title = {title},\n"
        "    .macro = {macro},\n"
        "    .address_bits = {ab},\n"
        "    .ram_begin = {rb},\n"
        "    .ram_size = {rs},\n"
        "    .ram_size_large = {rsl},\n"
        "    .cells_base = {cb},\n"
        "    .user_base = {ub},\n"
        "    .segment_shift = {ss},\n"
        "    .segment_shift_large = {ssl},\n"
        "    .violation_from = {vf},\n"
        "    .violation_subtract = {vs},\n"
        "    .release = {rel},\n"
        "    .bus_access_cycles = {bac},\n"
        "    .note = {note},\n"
        "    .regs = k{P}_regs,\n"
        "    .regions = {regions},\n"
        "    .layouts = {layouts}}};\n",
        fmt::arg("P", P), fmt::arg("id", profile_enum(p.id)), fmt::arg("name", cpp_string(p.name)),
        fmt::arg("title", cpp_string(p.title)), fmt::arg("macro", cpp_string(p.macro)),
        fmt::arg("ab", p.address_bits), fmt::arg("rb", hex(p.ram_begin, 4)),
        fmt::arg("rs", p.ram_size), fmt::arg("rsl", p.ram_size_large),
        fmt::arg("cb", hex(p.cells_base, 4)), fmt::arg("ub", hex(p.user_base, 4)),
        fmt::arg("ss", p.segment_shift), fmt::arg("ssl", p.segment_shift_large),
        fmt::arg("vf", hex(p.violation_from, 4)), fmt::arg("vs", hex(p.violation_subtract, 4)),
        fmt::arg("rel", p.release), fmt::arg("bac", p.bus_access_cycles),
        fmt::arg("note", cpp_string(p.note)),
        fmt::arg("regions", p.regions.empty() ? std::string{"{}"} : fmt::format("k{}_regions", P)),
        fmt::arg("layouts", p.layouts.empty() ? std::string{"{}"} : fmt::format("k{}_layouts", P)));
  }
  fmt::format_to(std::back_inserter(out),
                 "\nstatic constexpr ChipTiming kChipTiming{{.clock_hz = {}}};\n\n"
                 "const ProfileDesc& profile_desc(Profile p) {{\n"
                 "  switch (p) {{\n",
                 timing.clock_hz);
  for (const ProfileDesc* pp : profiles) {
    fmt::format_to(std::back_inserter(out), "    case {}:\n      return k{}_profile;\n",
                   profile_enum(pp->id), pp->macro);
  }
  if (profiles.empty()) throw std::logic_error("emit_cpp_tables: no profiles");
  if (profiles.size() < std::size(kAllProfiles)) out += "    default:\n      break;\n";
  fmt::format_to(std::back_inserter(out),
                 "  }}\n  return k{}_profile;\n}}\n\n"
                 "const ChipTiming& chip_timing() {{ return kChipTiming; }}\n\n"
                 "}}  // namespace dpc31\n",
                 profiles.front()->macro);
  return out;
}

}  // namespace dpc31::regfmt

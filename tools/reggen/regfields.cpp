// The emitter of dpc31/reg_fields.hpp (regfmt.hpp, emit_reg_fields): a constexpr mask per
// named register field of regs/dpc31_regs.json, so that the emulator, the lockstep adapter and
// the waveform writer name a field's bits as the description does instead of typing them.
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include "regfmt.hpp"

namespace dpc31::regfmt {

namespace {

std::string cpp_identifier(std::string_view name) {
  const bool digit = !name.empty() && std::isdigit(static_cast<unsigned char>(name[0])) != 0;
  return fmt::format("{}{}", digit ? "_" : "", name);
}

struct FieldUse {
  std::string reg;
  std::string field;
  std::vector<std::pair<const ProfileDesc*, const FieldDesc*>> in;  // per profile that has it
};

void emit_field(std::string& out, const FieldDesc& f, std::size_t width) {
  fmt::format_to(std::back_inserter(out),
                 "inline constexpr std::uint16_t {:<{}} = {}u;  // {} {}\n", cpp_identifier(f.name),
                 width, hex(field_mask(f), 4), bits_str(f), field_policy(f));
}

void emit_group(std::string& out, std::string_view indent, const std::string& reg,
                std::vector<const FieldDesc*> fs) {
  std::stable_sort(fs.begin(), fs.end(),
                   [](const FieldDesc* a, const FieldDesc* b) { return a->lsb < b->lsb; });
  std::size_t width = 0;
  for (const FieldDesc* f : fs) width = std::max(width, cpp_identifier(f->name).size());
  fmt::format_to(std::back_inserter(out), "{}namespace {} {{\n", indent, reg);
  for (const FieldDesc* f : fs) {
    out += indent;
    emit_field(out, *f, width);
  }
  fmt::format_to(std::back_inserter(out), "{}}}  // namespace {}\n", indent, reg);
}

}  // namespace

std::string emit_reg_fields(Profiles profiles) {
  // Registers and fields in the order they first appear, over the profiles in order.
  std::vector<FieldUse> uses;
  for (const ProfileDesc* p : profiles) {
    for (const RegDesc& r : p->regs) {
      for (const FieldDesc* f : named_fields(r)) {
        auto it = std::find_if(uses.begin(), uses.end(), [&](const FieldUse& u) {
          return u.reg == r.name && u.field == f->name;
        });
        if (it == uses.end()) {
          // After the register's other fields: one namespace per register.
          auto last = std::find_if(uses.rbegin(), uses.rend(),
                                   [&](const FieldUse& u) { return u.reg == r.name; });
          it = uses.insert(last == uses.rend() ? uses.end() : last.base(),
                           FieldUse{std::string{r.name}, std::string{f->name}, {}});
        }
        it->in.emplace_back(p, f);
      }
    }
  }
  const auto same_everywhere = [](const FieldUse& u) {
    return std::all_of(u.in.begin(), u.in.end(), [&](const auto& e) {
      return field_mask(*e.second) == field_mask(*u.in.front().second);
    });
  };
  std::string out = fmt::format(
      "// dpc31/reg_fields.hpp -- the field masks of regs/dpc31_regs.json as C++ constants.\n"
      "// {}.\n"
      "// dpc31::fields::<Reg>::<Field>: the mask of a field every profile that has it puts on\n"
      "// the same bits; dpc31::fields::<profile>::<Reg>::<Field> where the profiles differ. A\n"
      "// name that is no C++ identifier (4kB_Mode) gets a leading underscore.\n"
      "#pragma once\n\n#include <bit>\n#include <cstdint>\n\n"
      "namespace dpc31 {{\n\n"
      "// `value` placed into the bits of the field `mask` (bits that do not fit are dropped).\n"
      "constexpr std::uint16_t field_value(std::uint16_t mask, unsigned value) {{\n"
      "  return static_cast<std::uint16_t>((value << std::countr_zero(mask)) & mask);\n"
      "}}\n"
      "// The field `mask` of `reg`, shifted down to bit 0.\n"
      "constexpr unsigned field_of(std::uint16_t reg, std::uint16_t mask) {{\n"
      "  return static_cast<unsigned>((reg & mask) >> std::countr_zero(mask));\n"
      "}}\n\n"
      "namespace fields {{\n\n",
      kGeneratedBanner);
  const auto emit_regs = [&](std::string_view indent, auto&& pick) {
    std::string reg;
    std::vector<const FieldDesc*> group;
    const auto flush = [&] {
      if (!group.empty()) emit_group(out, indent, reg, group);
      group.clear();
    };
    for (const FieldUse& u : uses) {
      const FieldDesc* f = pick(u);
      if (f == nullptr) continue;
      if (u.reg != reg) {
        flush();
        reg = u.reg;
      }
      group.push_back(f);
    }
    flush();
  };
  emit_regs("", [&](const FieldUse& u) -> const FieldDesc* {
    return same_everywhere(u) ? u.in.front().second : nullptr;
  });
  for (const ProfileDesc* p : profiles) {
    std::string body;
    std::swap(out, body);
    emit_regs("", [&](const FieldUse& u) -> const FieldDesc* {
      if (same_everywhere(u)) return nullptr;
      for (const auto& [q, f] : u.in) {
        if (q == p) return f;
      }
      return nullptr;
    });
    std::swap(out, body);
    if (body.empty()) continue;
    fmt::format_to(std::back_inserter(out),
                   "\n// Fields {} puts on other bits than another profile.\nnamespace {} {{\n{}}} "
                   " // namespace {}\n",
                   p->name, p->name, body, p->name);
  }
  out += "\n}  // namespace fields\n\n}  // namespace dpc31\n";
  return out;
}

}  // namespace dpc31::regfmt

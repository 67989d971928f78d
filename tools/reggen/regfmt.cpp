// Emitters for the register description (see regfmt.hpp). Everything here works on the compiled
// types of dpc31/regdesc.hpp; nothing reads the JSON.
#include "regfmt.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>
#include <utility>

namespace dpc31::regfmt {

// =============================================================================================
// Shared helpers
// =============================================================================================

std::string hex(std::uint32_t value, int digits) { return fmt::format("0x{:0{}X}", value, digits); }

int addr_digits(const ProfileDesc& p) { return (p.address_bits + 3) / 4; }

std::string addr_str(const ProfileDesc& p, std::int32_t addr) {
  return addr < 0 ? std::string{"-"} : hex(static_cast<std::uint32_t>(addr), addr_digits(p));
}

std::string reset_str(const RegDesc& r) {
  return r.has_reset ? hex(r.reset, r.width / 4) : std::string{"-"};
}

std::string bits_str(unsigned lsb, unsigned width) {
  return width <= 1 ? fmt::format("{}", lsb) : fmt::format("{}:{}", lsb + width - 1, lsb);
}

std::string bits_str(const FieldDesc& f) { return bits_str(f.lsb, f.width); }

std::uint16_t field_mask(const FieldDesc& f) {
  return static_cast<std::uint16_t>(((1u << f.width) - 1u) << f.lsb);
}

std::string field_policy(const FieldDesc& f) {
  return fmt::format("{}{}", access_name(f.access), f.pulse ? " pulse" : "");
}

std::vector<const FieldDesc*> named_fields(const RegDesc& r) {
  std::vector<const FieldDesc*> out;
  for (const auto& f : r.fields) {
    if (f.access != Access::RSVD && f.name != r.name) out.push_back(&f);
  }
  return out;
}

std::string_view target_name(const ProfileDesc& p, const RegDesc& r) {
  if (r.target == r.id) return r.name;
  const RegDesc* t = find_reg(p, r.target);
  return t != nullptr ? t->name : std::string_view{"?"};
}

std::string kind_label(const ProfileDesc& p, const RegDesc& r) {
  if (r.kind == Kind::port) return fmt::format("port -> {}", target_name(p, r));
  if (r.reserved) return fmt::format("{} (reserved)", kind_name(r.kind));
  return std::string{kind_name(r.kind)};
}

std::string_view origin_str(const RegDesc& r) { return r.documented ? "documented" : "modelled"; }

namespace {

const FieldDesc* field_at(const RegDesc& r, int bit) {
  for (const auto& f : r.fields) {
    if (bit >= f.lsb && bit < f.lsb + f.width) return &f;
  }
  return nullptr;
}

std::string join(const std::vector<std::string>& parts, std::string_view sep) {
  std::string out;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    if (i != 0) out += sep;
    out += parts[i];
  }
  return out;
}

// Replaces line breaks and tabs by spaces so a text fits in a one-line context.
std::string one_line(std::string_view text) {
  std::string out;
  for (char c : text) out += (c == '\n' || c == '\r' || c == '\t') ? ' ' : c;
  return out;
}

}  // namespace

std::string field_summary(const RegDesc& r) {
  std::vector<std::string> parts;
  int bit = r.width - 1;
  while (bit >= 0) {
    if (const FieldDesc* f = field_at(r, bit)) {
      std::string s = bits_str(*f);
      if (f->name != r.name) fmt::format_to(std::back_inserter(s), " {}", f->name);
      fmt::format_to(std::back_inserter(s), " {}", field_policy(*f));
      parts.push_back(std::move(s));
      bit = std::min<int>(bit, f->lsb) - 1;
      continue;
    }
    int low = bit;
    while (low > 0 && field_at(r, low - 1) == nullptr) --low;
    parts.push_back(bits_str(static_cast<unsigned>(low), static_cast<unsigned>(bit - low + 1)) +
                    " rsvd");
    bit = low - 1;
  }
  return join(parts, ", ");
}

std::string placement_str(const RegDesc& r, BusMode m) {
  if (r.width != 16) return {};
  const std::uint8_t* p = r.placement(m);
  auto byte = [](std::uint8_t i) { return i == 0 ? "lo" : "hi"; };
  return fmt::format("{},{}", byte(p[0]), byte(p[1]));
}

std::vector<AddrSide> address_sides(const RegDesc& r, std::string_view rd_suffix,
                                    std::string_view wr_suffix) {
  std::vector<AddrSide> out;
  const auto rd = static_cast<std::uint32_t>(r.read_addr);
  const auto wr = static_cast<std::uint32_t>(r.write_addr);
  if (r.read_addr >= 0 && r.write_addr >= 0) {
    if (rd == wr) {
      out.push_back({"", "read/write", rd});
    } else {
      out.push_back({rd_suffix, "read", rd});
      out.push_back({wr_suffix, "write", wr});
    }
  } else if (r.read_addr >= 0) {
    out.push_back({"", "read", rd});
  } else if (r.write_addr >= 0) {
    out.push_back({"", "write", wr});
  }
  return out;
}

std::vector<NamedMask> masks(const RegDesc& r) {
  return {{"ro", r.ro}, {"rw", r.rw},   {"w1c", r.w1c},   {"w1s", r.w1s},     {"cmd", r.cmd},
          {"wo", r.wo}, {"ign", r.ign}, {"rsvd", r.rsvd}, {"unimp", r.unimp}, {"pulse", r.pulse}};
}

// =============================================================================================
// C header and Verilog include: both are lists of macros, written by one DefineWriter
// =============================================================================================

namespace {

struct DefineStyle {
  std::string_view directive;  // "#define" / "`define"
  std::string_view line_open;  // one-line comment
  std::string_view line_close;
  std::string_view block_open;  // multi-line comment ("" = none)
  std::string_view block_line;
  std::string_view block_close;
  bool trailing_comments;  // comment after the value on a define line
};

constexpr DefineStyle kCStyle{"#define", "/* ", " */", "/*", " * ", " */", true};
constexpr DefineStyle kVerilogStyle{"`define", "// ", "", "", "// ", "", false};

class DefineWriter {
 public:
  explicit DefineWriter(const DefineStyle& style) : style_(style) {}

  void raw(std::string text) { lines_.push_back({{}, {}, std::move(text), {}}); }
  void blank() { raw({}); }

  void comment(std::string_view text) {
    raw(fmt::format("{}{}{}", style_.line_open, sanitize(text), style_.line_close));
  }

  void comment_block(const std::vector<std::string>& text) {
    if (!style_.block_open.empty()) raw(std::string{style_.block_open});
    for (const auto& l : text) {
      std::string line = fmt::format("{}{}", style_.block_line, sanitize(l));
      while (!line.empty() && line.back() == ' ') line.pop_back();
      raw(std::move(line));
    }
    if (!style_.block_close.empty()) raw(std::string{style_.block_close});
  }

  // Claims an identifier that is not a macro (enumerator) so a macro cannot reuse it.
  void reserve(const std::string& name) {
    if (!names_.insert(name).second) {
      throw std::logic_error(fmt::format("duplicate identifier '{}'", name));
    }
  }

  void define(std::string name, std::string value, std::string_view trailing = {}) {
    if (!names_.insert(name).second) {
      throw std::logic_error(fmt::format("duplicate macro name '{}'", name));
    }
    std::string c;
    if (!trailing.empty() && style_.trailing_comments) {
      c = fmt::format("{}{}{}", style_.line_open, sanitize(trailing), style_.line_close);
    }
    width_ = std::max(width_, name.size());
    lines_.push_back({std::move(name), std::move(value), {}, std::move(c)});
  }

  [[nodiscard]] std::string str() const {
    std::string out;
    for (const auto& l : lines_) {
      if (l.name.empty()) {
        out += l.text;
      } else {
        fmt::format_to(std::back_inserter(out), "{} {:<{}} {}", style_.directive, l.name, width_,
                       l.value);
        if (!l.comment.empty()) fmt::format_to(std::back_inserter(out), " {}", l.comment);
      }
      out += '\n';
    }
    return out;
  }

 private:
  struct Line {
    std::string name;  // empty: a raw line
    std::string value;
    std::string text;
    std::string comment;
  };

  // Comment text that cannot end the comment early, continue it onto the next line, or be taken
  // for a tool directive (Verilog tools read comments starting with these words).
  static std::string sanitize(std::string_view text) {
    std::string s = one_line(text);
    for (std::string_view tool : {"verilator", "synopsys", "synthesis", "pragma", "cadence",
                                  "ambit", "translate_", "lint_"}) {
      if (s.rfind(tool, 0) == 0) {
        s.insert(0, "- ");
        break;
      }
    }
    for (std::size_t p = s.find("*/"); p != std::string::npos; p = s.find("*/", p)) {
      s.replace(p, 2, "* /");
    }
    while (!s.empty() && s.back() == '\\') s.pop_back();
    return s;
  }

  const DefineStyle& style_;
  std::vector<Line> lines_;
  std::set<std::string> names_;
  std::size_t width_ = 0;
};

std::string upper_case(std::string_view s) {
  std::string out{s};
  for (char& c : out) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return out;
}

std::vector<std::string> profile_heading(const ProfileDesc& p) {
  std::vector<std::string> lines{
      fmt::format("{} (profile {}, prefix {}_)", p.title, p.name, p.macro)};
  for (auto& l : wrap(p.note, 92)) lines.push_back(std::move(l));
  return lines;
}

std::string register_comment(const ProfileDesc& p, const RegDesc& r) {
  std::string s = fmt::format("{}: {}, {} bit", r.name, kind_label(p, r), r.width);
  if (r.read_addr < 0 && r.write_addr < 0) s += ", no bus address in this profile";
  if (!r.desc.empty()) fmt::format_to(std::back_inserter(s), " -- {}", r.desc);
  return s;
}

// Address of the byte holding bits 7..0 (lo) or 15..8 (hi) of a 16-bit register.
std::uint32_t byte_addr(const RegDesc& r, BusMode m, std::uint8_t byte_index, std::uint32_t addr) {
  const std::uint8_t* p = r.placement(m);
  return addr + (p[0] == byte_index ? 0u : 1u);
}

// A profile constant; `address` selects the address notation of the output format.
struct Constant {
  std::string_view name;
  std::uint32_t value;
  bool address;
};

std::vector<Constant> profile_constants(const ProfileDesc& p) {
  std::vector<Constant> c{{"ADDRESS_BITS", p.address_bits, false},
                          {"RAM_BEGIN", p.ram_begin, true},
                          {"RAM_SIZE", p.ram_size, false}};
  if (p.ram_size_large != 0) c.push_back({"RAM_SIZE_LARGE", p.ram_size_large, false});
  c.push_back({"CELLS_BASE", p.cells_base, true});
  c.push_back({"USER_BASE", p.user_base, true});
  c.push_back({"SEGMENT_SHIFT", p.segment_shift, false});
  if (p.ram_size_large != 0) c.push_back({"SEGMENT_SHIFT_LARGE", p.segment_shift_large, false});
  return c;
}

// What differs between the C header and the Verilog include; write_defines() does the walk.
class MacroFormat {
 public:
  virtual ~MacroFormat() = default;
  virtual std::string constant(const ProfileDesc& p, const Constant& c) const = 0;
  // The macros of one address side of a register (prefix = "<P>").
  virtual void address(DefineWriter& w, const ProfileDesc& p, const RegDesc& r,
                       const AddrSide& side) const = 0;
  virtual std::string reset(const RegDesc& r) const = 0;
  // The macros of one field (reg_prefix = "<P>_<Reg>").
  virtual void field(DefineWriter& w, const std::string& reg_prefix, const RegDesc& r,
                     const FieldDesc& f) const = 0;
  // The register's per-bit access policies (reg_prefix = "<P>_<Reg>"); the C header has them in
  // its field comments.
  virtual void policies(DefineWriter& /*w*/, const std::string& /*reg_prefix*/,
                        const RegDesc& /*r*/) const {}
};

void write_defines(DefineWriter& w, Profiles profiles, const MacroFormat& format) {
  for (const ProfileDesc* pp : profiles) {
    const ProfileDesc& p = *pp;
    w.blank();
    w.comment_block(profile_heading(p));
    for (const Constant& c : profile_constants(p)) {
      w.define(fmt::format("{}_{}", p.macro, c.name), format.constant(p, c));
    }
    for (const RegDesc& r : p.regs) {
      const std::string reg_prefix = fmt::format("{}_{}", p.macro, r.name);
      w.blank();
      w.comment(register_comment(p, r));
      for (const AddrSide& side : address_sides(r, "_RD", "_WR")) format.address(w, p, r, side);
      if (r.has_reset) w.define(reg_prefix + "_RESET", format.reset(r));
      format.policies(w, reg_prefix, r);
      for (const FieldDesc* f : named_fields(r)) format.field(w, reg_prefix, r, *f);
      if (r.alias.empty()) continue;
      // The same register under its own manual's name.
      RegDesc named = r;
      named.name = r.alias;
      const std::string alias_prefix = fmt::format("{}_{}", p.macro, r.alias);
      w.comment(fmt::format("{}: the {} manual's name of {}", r.alias, p.title, r.name));
      for (const AddrSide& side : address_sides(named, "_RD", "_WR"))
        format.address(w, p, named, side);
      for (const FieldDesc* f : named_fields(r)) format.field(w, alias_prefix, r, *f);
    }
  }
}

class CFormat final : public MacroFormat {
 public:
  std::string constant(const ProfileDesc& p, const Constant& c) const override {
    return c.address ? addr(p, c.value) : fmt::format("{}u", c.value);
  }
  void address(DefineWriter& w, const ProfileDesc& p, const RegDesc& r,
               const AddrSide& side) const override {
    const std::string name = fmt::format("{}_{}{}", p.macro, r.name, side.suffix);
    w.define(name, addr(p, side.addr), side.what);
    if (r.width != 16) return;
    for (const auto& [mode, mode_name] :
         {std::pair{BusMode::intel, "INTEL"}, std::pair{BusMode::motorola, "MOTOROLA"}}) {
      w.define(fmt::format("{}_LO_{}", name, mode_name), addr(p, byte_addr(r, mode, 0, side.addr)));
      w.define(fmt::format("{}_HI_{}", name, mode_name), addr(p, byte_addr(r, mode, 1, side.addr)));
    }
  }
  std::string reset(const RegDesc& r) const override { return hex(r.reset, r.width / 4) + "u"; }
  void field(DefineWriter& w, const std::string& reg_prefix, const RegDesc& r,
             const FieldDesc& f) const override {
    const std::string name = fmt::format("{}_{}", reg_prefix, f.name);
    w.define(name + "_Pos", fmt::format("{}u", f.lsb));
    w.define(
        name + "_Msk", hex(field_mask(f), r.width / 4) + "u",
        fmt::format("{} {}{}{}", bits_str(f), field_policy(f), f.desc.empty() ? "" : ": ", f.desc));
  }

 private:
  static std::string addr(const ProfileDesc& p, std::uint32_t a) {
    return hex(a, addr_digits(p)) + "u";
  }
};

class VerilogFormat final : public MacroFormat {
 public:
  std::string constant(const ProfileDesc& /*p*/, const Constant& c) const override {
    return c.address ? addr(c.value) : fmt::format("{}", c.value);
  }
  void address(DefineWriter& w, const ProfileDesc& p, const RegDesc& r,
               const AddrSide& side) const override {
    w.define(fmt::format("{}_ADDR_{}{}", p.macro, r.name, side.suffix), addr(side.addr));
  }
  std::string reset(const RegDesc& r) const override {
    return fmt::format("{}'h{:0{}X}", r.width, r.reset, r.width / 4);
  }
  void field(DefineWriter& w, const std::string& reg_prefix, const RegDesc& /*r*/,
             const FieldDesc& f) const override {
    const std::string name = fmt::format("{}_{}", reg_prefix, f.name);
    w.define(name + "_POS", fmt::format("{}", f.lsb));
    w.define(name + "_W", fmt::format("{}", f.width));
  }
  // One mask per policy the register has (P_<Reg>_W1C, _IGN, _RSVD, ...): what an RTL needs to
  // decode a write (which bits it stores, clears, ignores) without copying it by hand.
  void policies(DefineWriter& w, const std::string& reg_prefix, const RegDesc& r) const override {
    for (const NamedMask& m : masks(r)) {
      if (m.value == 0) continue;
      w.define(fmt::format("{}_{}", reg_prefix, upper_case(m.name)),
               fmt::format("{}'h{:0{}X}", r.width, m.value, r.width / 4));
    }
  }

 private:
  // One address width for all profiles: the widest bus (DPC31, 13 bits).
  static std::string addr(std::uint32_t a) { return fmt::format("13'h{:04X}", a); }
};

}  // namespace

std::string emit_c_header(Profiles profiles) {
  DefineWriter w(kCStyle);
  w.comment_block({"dpc31_regs.h -- SPC3 / VPC3+ / DPC31 register map (C99, also valid C++).",
                   std::string{kGeneratedBanner} + ".",
                   "Per profile P: P_<Reg> = byte address of the register (one macro per side; "
                   "_RD/_WR when the",
                   "read and write side of one register differ), P_<Reg>_LO/HI_INTEL/MOTOROLA = "
                   "byte addresses of",
                   "16-bit registers, P_<Reg>_<Field>_Pos/_Msk, P_<Reg>_RESET."});
  w.raw("#ifndef DPC31_REGS_H");
  w.raw("#define DPC31_REGS_H");
  // The profile numbers (as dpc31::Profile); also keeps the header a non-empty C translation unit.
  w.blank();
  w.comment("Profiles, numbered as dpc31::Profile of the emulator.");
  w.raw("enum dpc31_profile {");
  for (std::size_t i = 0; i < profiles.size(); ++i) {
    const std::string id = "DPC31_PROFILE_" + upper_case(profiles[i]->name);
    w.reserve(id);
    w.raw(fmt::format("  {} = {}{}", id, static_cast<unsigned>(profiles[i]->id),
                      i + 1 < profiles.size() ? "," : ""));
  }
  w.raw("};");
  write_defines(w, profiles, CFormat{});
  for (const ProfileDesc* p : profiles) {
    for (const LayoutDefine& d : layout_defines(*p)) {
      if (!d.name.empty()) {
        w.define(d.name, d.value, d.comment);
      } else {
        w.blank();
        w.comment(d.comment);
      }
    }
  }
  w.blank();
  w.raw("#endif /* DPC31_REGS_H */");
  return w.str();
}

std::string emit_verilog(Profiles profiles) {
  DefineWriter w(kVerilogStyle);
  w.comment_block(
      {"dpc31_regs.vh -- SPC3 / VPC3+ / DPC31 register map (Verilog-2005 include).",
       std::string{kGeneratedBanner} + ".",
       "Per profile P: P_ADDR_<Reg> (13-bit byte address; _RD/_WR when the read and "
       "write side differ),",
       "P_<Reg>_<Field>_POS / _W (lsb, width), P_<Reg>_RESET (sized to the register),",
       "P_<Reg>_<POLICY>: the bits of each access policy the register has (RO, RW, W1C, W1S, "
       "CMD, WO, IGN,",
       "RSVD, UNIMP, PULSE; docs/registers.md), sized to the register."});
  w.raw("`ifndef DPC31_REGS_VH");
  w.raw("`define DPC31_REGS_VH");
  write_defines(w, profiles, VerilogFormat{});
  w.blank();
  w.raw("`endif // DPC31_REGS_VH");
  return w.str();
}

// =============================================================================================
// Register tables: the markdown document and the terminal text share the columns
// =============================================================================================

namespace {

enum class Col { read, write, name, kind, width, reset, fields, bytes, origin, source, desc };

constexpr std::array<std::string_view, 11> kColTitles = {"Read",
                                                         "Write",
                                                         "Name",
                                                         "Kind",
                                                         "Bits",
                                                         "Reset",
                                                         "Fields (msb..lsb)",
                                                         "Bytes Intel / Motorola",
                                                         "Origin",
                                                         "Source",
                                                         "Description"};
static_assert(kColTitles.size() == static_cast<std::size_t>(Col::desc) + 1, "a title a column");

std::string_view col_title(Col c) { return kColTitles.at(static_cast<std::size_t>(c)); }

std::string col_cell(Col c, const ProfileDesc& p, const RegDesc& r) {
  switch (c) {
    case Col::read:
      return addr_str(p, r.read_addr);
    case Col::write:
      return addr_str(p, r.write_addr);
    case Col::name:
      return r.alias.empty() ? std::string{r.name} : fmt::format("{} ({})", r.name, r.alias);
    case Col::kind:
      return kind_label(p, r);
    case Col::width:
      return fmt::format("{}", r.width);
    case Col::reset:
      return reset_str(r);
    case Col::fields:
      return field_summary(r);
    case Col::bytes:
      return r.width == 16 ? fmt::format("{} / {}", placement_str(r, BusMode::intel),
                                         placement_str(r, BusMode::motorola))
                           : std::string{};
    case Col::origin:
      return std::string{origin_str(r)};
    case Col::source:
      return std::string{r.source};
    case Col::desc:
      return std::string{r.desc};
  }
  return {};
}

using Row = std::vector<std::string>;

std::vector<Row> register_rows(const ProfileDesc& p, std::span<const Col> cols) {
  std::vector<Row> rows;
  Row head;
  for (Col c : cols) head.emplace_back(col_title(c));
  rows.push_back(std::move(head));
  for (const RegDesc& r : p.regs) {
    Row row;
    for (Col c : cols) row.push_back(one_line(col_cell(c, p, r)));
    rows.push_back(std::move(row));
  }
  return rows;
}

std::string md_escape(std::string_view text) {
  std::string out;
  for (char c : one_line(text)) {
    if (c == '|') {
      out += "\\|";
    } else if (c == '<') {
      out += "&lt;";
    } else {
      out += c;
    }
  }
  return out;
}

// rows[0] is the header. `code` marks columns shown as code spans.
std::string md_table(const std::vector<Row>& rows, const std::vector<bool>& code = {}) {
  std::string out;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    out += '|';
    for (std::size_t c = 0; c < rows[i].size(); ++c) {
      const bool as_code =
          i != 0 && c < code.size() && code[c] && !rows[i][c].empty() && rows[i][c] != "-";
      const std::string cell =
          as_code ? fmt::format("`{}`", one_line(rows[i][c])) : md_escape(rows[i][c]);
      fmt::format_to(std::back_inserter(out), " {} |", cell);
    }
    out += '\n';
    if (i == 0) {
      out += '|';
      for (std::size_t c = 0; c < rows[i].size(); ++c) out += "---|";
      out += '\n';
    }
  }
  return out;
}

std::string text_table(const std::vector<Row>& rows) {
  std::vector<std::size_t> widths;
  for (const Row& row : rows) {
    widths.resize(std::max(widths.size(), row.size()), 0);
    for (std::size_t c = 0; c < row.size(); ++c) widths[c] = std::max(widths[c], row[c].size());
  }
  std::string out;
  for (const Row& row : rows) {
    std::string line;
    for (std::size_t c = 0; c < row.size(); ++c) {
      if (c + 1 == row.size()) {
        line += row[c];
      } else {
        fmt::format_to(std::back_inserter(line), "{:<{}}  ", row[c], widths[c]);
      }
    }
    while (!line.empty() && line.back() == ' ') line.pop_back();
    out += line;
    out += '\n';
  }
  return out;
}

std::string yes_no(bool b) { return b ? "yes" : "no"; }

// Profile constants as (name, value) rows, shared by markdown and text.
std::vector<Row> constant_rows(const ProfileDesc& p) {
  const int ad = addr_digits(p);
  std::vector<Row> rows{
      {"Constant", "Value"},
      {"address bits", fmt::format("{}", p.address_bits)},
      {"RAM", fmt::format("{} bytes from {}", p.ram_size, hex(p.ram_begin, ad))},
  };
  if (p.ram_size_large != 0) {
    rows.push_back({"RAM (large mode)", fmt::format("{} bytes, segment shift {}", p.ram_size_large,
                                                    p.segment_shift_large)});
  }
  rows.push_back({"organisational cell 16h at", hex(p.cells_base, ad)});
  rows.push_back({"user area from", hex(p.user_base, ad)});
  rows.push_back({"segment shift",
                  fmt::format("{} ({}-byte segments)", p.segment_shift, 1u << p.segment_shift)});
  if (p.violation_from != 0) {
    rows.push_back({"RAM access violation",
                    fmt::format("from {}, wraps to address - {}", hex(p.violation_from, ad),
                                hex(p.violation_subtract, ad))});
  }
  rows.push_back({"release (Status_Reg 15..12)", fmt::format("{:X}h", p.release)});
  rows.push_back({"clocks per bus access", fmt::format("{}", p.bus_access_cycles)});
  return rows;
}

constexpr std::array kMarkdownCols{Col::read,   Col::write,  Col::name,   Col::kind,
                                   Col::width,  Col::reset,  Col::fields, Col::bytes,
                                   Col::origin, Col::source, Col::desc};
// The origin and the source before the fields: which address is the manual's and which ours.
constexpr std::array kTextCols{Col::read,  Col::write,  Col::name,   Col::kind,  Col::width,
                               Col::reset, Col::origin, Col::source, Col::fields};

}  // namespace

std::string emit_markdown(Profiles profiles) {
  std::string out;
  std::vector<std::string> titles;
  for (const ProfileDesc* p : profiles) titles.emplace_back(p->title);
  fmt::format_to(std::back_inserter(out), "# Registers: {}\n\n", join(titles, ", "));
  fmt::format_to(std::back_inserter(out),
                 "<!-- {} -->\n\n_Generated \u2014 do not edit; source `regs/dpc31_regs.json`. "
                 "Regenerate with `cmake --build build --target update-generated`._\n\n",
                 kGeneratedBanner);

  out += "## Legend\n\n";
  out +=
      "Addresses are physical byte addresses of the profile; a 16-bit register occupies the "
      "address and the next one. _Bytes_ gives, for Intel and Motorola bus mode, which byte "
      "(lo = bits 7..0, hi = bits 15..8) sits at address + 0 and address + 1. Bits no field "
      "covers are reserved (`rsvd`: read 0; each keeps its bit of the reset value, so a write "
      "that would change it, QEMU's guest error, is logged and ignored: Int_Mask_Reg's reserved "
      "bits are 1, and its mask-all FFFFh or a driver's `~enabled` leave them, a 0 there is "
      "logged). _Origin_: "
      "`documented` = "
      "taken from the manuals, `modelled` = our choice (see the notes below each table).\n\n";
  std::vector<Row> kinds{{"Kind", "Meaning"}};
  for (Kind k : {Kind::latch, Kind::cell, Kind::derived, Kind::port, Kind::reserved}) {
    kinds.push_back({std::string{kind_name(k)}, std::string{kind_desc(k)}});
  }
  out += md_table(kinds, {true, false});
  out += '\n';
  std::vector<Row> accesses{{"Access", "Meaning"}};
  for (Access a : {Access::RO, Access::RW, Access::W1C, Access::W1S, Access::CMD, Access::WO,
                   Access::IGN, Access::RSVD, Access::UNIMP}) {
    accesses.push_back({std::string{access_name(a)}, std::string{access_desc(a)}});
  }
  accesses.push_back({"pulse", "self-clearing: the chip clears the bit again"});
  out += md_table(accesses, {true, false});

  for (const ProfileDesc* pp : profiles) {
    const ProfileDesc& p = *pp;
    const int ad = addr_digits(p);
    fmt::format_to(std::back_inserter(out), "\n## {} (`{}`, macro prefix `{}_`)\n\n", p.title,
                   p.name, p.macro);
    if (!p.note.empty()) fmt::format_to(std::back_inserter(out), "{}\n\n", md_escape(p.note));
    out += md_table(constant_rows(p));

    out += "\n### Memory map\n\n";
    std::vector<Row> regions{{"First", "Last", "Region", "RAM", "Reserved", "Description"}};
    for (const RegionDesc& g : p.regions) {
      regions.push_back({hex(g.begin, ad), hex(g.end - 1, ad), std::string{g.name}, yes_no(g.ram),
                         yes_no(g.reserved), std::string{g.desc}});
    }
    out += md_table(regions);
    for (const LayoutDesc& l : p.layouts) {
      fmt::format_to(std::back_inserter(out), "\n### RAM layout {} ({} bytes)\n\n{} ({}).\n\n",
                     l.name, l.size, md_escape(l.desc), md_escape(l.source));
      out += md_table(layout_rows(l), {false, true});
    }

    out += "\n### Registers\n\n";
    out += md_table(register_rows(p, kMarkdownCols), {false, false, true});

    std::string notes;
    for (const RegDesc& r : p.regs) {
      if (r.note.empty()) continue;
      fmt::format_to(std::back_inserter(notes), "- `{}` ({}): {}\n", r.name, origin_str(r),
                     md_escape(r.note));
    }
    if (!notes.empty()) fmt::format_to(std::back_inserter(out), "\n### Notes\n\n{}", notes);
  }
  return out;
}

std::string emit_text(const ProfileDesc& p) {
  std::string out = fmt::format("{} ({}, macro prefix {}_)\n", p.title, p.name, p.macro);
  std::vector<std::string> consts;
  const auto rows = constant_rows(p);
  for (std::size_t i = 1; i < rows.size(); ++i) {
    consts.push_back(fmt::format("{}: {}", rows[i][0], rows[i][1]));
  }
  for (const auto& l : wrap(join(consts, "; "), 100)) out += "  " + l + "\n";
  out += '\n';
  out += text_table(register_rows(p, kTextCols));
  return out;
}

// =============================================================================================
// JSON
// =============================================================================================

std::string emit_json(const ProfileDesc& p) {
  using Json = nlohmann::ordered_json;
  auto addr_or_null = [](std::int32_t a) { return a < 0 ? Json(nullptr) : Json(a); };
  Json doc;
  doc["generated"] = kGeneratedBanner;
  doc["profile"] = {
      {"name", p.name},
      {"title", p.title},
      {"macro", p.macro},
      {"address_bits", p.address_bits},
      {"ram_begin", p.ram_begin},
      {"ram_size", p.ram_size},
      {"ram_size_large", p.ram_size_large},
      {"cells_base", p.cells_base},
      {"user_base", p.user_base},
      {"segment_shift", p.segment_shift},
      {"segment_shift_large", p.segment_shift_large},
      {"violation_from", p.violation_from},
      {"violation_subtract", p.violation_subtract},
      {"release", p.release},
      {"bus_access_cycles", p.bus_access_cycles},
      {"note", p.note},
  };
  Json regions = Json::array();
  for (const RegionDesc& g : p.regions) {
    regions.push_back({{"name", g.name},
                       {"begin", g.begin},
                       {"end", g.end},
                       {"ram", g.ram},
                       {"reserved", g.reserved},
                       {"desc", g.desc}});
  }
  doc["regions"] = std::move(regions);
  Json regs = Json::array();
  for (const RegDesc& r : p.regs) {
    Json fields = Json::array();
    for (const FieldDesc& f : r.fields) {
      fields.push_back({{"name", f.name},
                        {"bits", bits_str(f)},
                        {"lsb", f.lsb},
                        {"width", f.width},
                        {"access", access_name(f.access)},
                        {"pulse", f.pulse},
                        {"desc", f.desc}});
    }
    Json m = Json::object();
    for (const NamedMask& nm : masks(r)) m[std::string{nm.name}] = nm.value;
    Json reg = {
        {"name", r.name},
        {"kind", kind_name(r.kind)},
        {"reserved", r.reserved},
        {"block", block_name(r.block)},
        {"width", r.width},
        {"reset", r.has_reset ? Json(r.reset) : Json(nullptr)},
        {"read_addr", addr_or_null(r.read_addr)},
        {"write_addr", addr_or_null(r.write_addr)},
        {"target", target_name(p, r)},
        {"fields", std::move(fields)},
        {"masks", std::move(m)},
    };
    if (r.width == 16) {
      reg["placement"] = {{"intel", {r.intel[0], r.intel[1]}},
                          {"motorola", {r.motorola[0], r.motorola[1]}}};
    } else {
      reg["placement"] = nullptr;
    }
    reg["documented"] = r.documented;
    reg["source"] = r.source;
    reg["note"] = r.note;
    reg["desc"] = r.desc;
    reg["alias"] = r.alias.empty() ? Json(nullptr) : Json(r.alias);
    regs.push_back(std::move(reg));
  }
  doc["registers"] = std::move(regs);
  return doc.dump(2) + "\n";
}

// =============================================================================================
// C++ tables
// =============================================================================================

}  // namespace dpc31::regfmt

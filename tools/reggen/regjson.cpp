// Loader and validator of regs/dpc31_regs.json (see regjson.hpp). Every rejection is one line
// naming the file, the entry and the problem.
#include "regjson.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <utility>

#include "regfmt.hpp"
#include "regjson_keys.hpp"
#include "regjson_text.hpp"

namespace dpc31::regjson {

namespace {

using Json = nlohmann::json;
using detail::access_mask;
using detail::is_identifier;
using detail::parse_text;
using detail::plain_lanes;

constexpr std::size_t kProfileCount = std::size(kAllProfiles);
constexpr std::uint32_t kFirstCell = 0x16;
constexpr std::uint32_t kLastCell = 0x3F;

std::size_t index_of(Profile p) { return static_cast<std::size_t>(p); }

// An address in messages, with the digits of the profile ("0x015", "0x0840").
std::string hex_addr(const ProfileDesc& p, std::uint32_t addr) {
  return regfmt::hex(addr, regfmt::addr_digits(p));
}

// A field as written in the description, before it is bound to a register.
struct RawField {
  std::string name;
  unsigned lsb = 0;
  unsigned width = 1;
  std::optional<Access> access;
  bool pulse = false;
  std::string desc;

  [[nodiscard]] std::uint32_t mask() const { return ((1u << width) - 1u) << lsb; }
};

// A profile-dependent value: one for all profiles or one per profile key.
struct PerProfile {
  std::array<std::optional<std::uint32_t>, kProfileCount> value{};
};

}  // namespace

class Loader {
 public:
  Loader(RegModel& model, std::string file) : m_(model), file_(std::move(file)) {}

  void load(const Json& root) {
    ctx_ = "top level";
    expect_object(root, "the document");
    check_keys(root, kTopKeys);
    const std::uint32_t format = number(root, "format", true).value_or(0);
    if (format != 1) fail(fmt::format("unsupported format {} (expected 1)", format));
    m_.title_ = string(root, "title", false);
    m_.timing_.clock_hz = number(root, "clock_hz", true).value_or(0);
    if (m_.timing_.clock_hz == 0) fail("clock_hz must be > 0");

    load_profiles(required(root, "profiles"));
    load_fieldsets(root);
    const Json& regs = required(root, "registers");
    if (!regs.is_array()) fail("'registers' must be an array");
    for (std::size_t i = 0; i < regs.size(); ++i) load_register(regs[i], i);
    resolve_targets();
    for (const auto& [name, used] : fieldset_used_) {
      if (!used) warn(fmt::format("fieldset '{}'", name), "never used");
    }
    finish();
  }

 private:
  // ---- messages ----------------------------------------------------------------------------

  [[noreturn]] void fail(std::string_view msg) const {
    throw Error(fmt::format("{}: {}: {}", file_, ctx_, msg));
  }
  void warn(std::string_view ctx, std::string_view msg) {
    m_.warnings_.push_back(fmt::format("{}: {}: {}", file_, ctx, msg));
  }

  // ---- typed access to the JSON ------------------------------------------------------------

  void expect_object(const Json& j, std::string_view what) const {
    if (!j.is_object()) fail(fmt::format("{} must be a JSON object", what));
  }

  void check_keys(const Json& obj, std::span<const std::string_view> allowed) const {
    for (const auto& [key, value] : obj.items()) {
      if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
        fail(fmt::format("unknown key '{}'", key));
      }
    }
  }

  const Json& required(const Json& obj, const char* key) const {
    const auto it = obj.find(key);
    if (it == obj.end()) fail(fmt::format("missing key '{}'", key));
    return *it;
  }

  static const Json* optional(const Json& obj, const char* key) {
    const auto it = obj.find(key);
    return it == obj.end() ? nullptr : &*it;
  }

  std::string string(const Json& obj, const char* key, bool req) const {
    const Json* v = req ? &required(obj, key) : optional(obj, key);
    if (v == nullptr) return {};
    if (!v->is_string()) fail(fmt::format("'{}' must be a string", key));
    return v->get<std::string>();
  }

  bool boolean(const Json& obj, const char* key, bool req) const {
    const Json* v = req ? &required(obj, key) : optional(obj, key);
    if (v == nullptr) return false;
    if (!v->is_boolean()) fail(fmt::format("'{}' must be true or false", key));
    return v->get<bool>();
  }

  // An unsigned number: a JSON integer or a hex string "0x1F".
  std::uint32_t number_value(const Json& v, std::string_view what) const {
    if (v.is_number_unsigned()) {
      const auto n = v.get<std::uint64_t>();
      if (n > 0xFFFFFFFFu) fail(fmt::format("{} {} is too large", what, n));
      return static_cast<std::uint32_t>(n);
    }
    if (v.is_string()) {
      const auto s = v.get<std::string>();
      const bool hex =
          s.size() > 2 && s.size() <= 10 && (s.rfind("0x", 0) == 0 || s.rfind("0X", 0) == 0) &&
          std::all_of(s.begin() + 2, s.end(),
                      [](char c) { return std::isxdigit(static_cast<unsigned char>(c)) != 0; });
      if (hex) return static_cast<std::uint32_t>(std::stoul(s.substr(2), nullptr, 16));
      fail(fmt::format("{} '{}' is not a hex number like \"0x1F\"", what, s));
    }
    fail(fmt::format("{} must be a non-negative integer or a hex string like \"0x1F\"", what));
  }

  std::optional<std::uint32_t> number(const Json& obj, const char* key, bool req) const {
    const Json* v = req ? &required(obj, key) : optional(obj, key);
    if (v == nullptr) return std::nullopt;
    return number_value(*v, fmt::format("'{}'", key));
  }

  std::uint32_t bounded(const Json& obj, const char* key, std::uint32_t max) const {
    const std::uint32_t v = *number(obj, key, true);
    if (v > max) fail(fmt::format("'{}' = {} exceeds {}", key, v, max));
    return v;
  }

  // A value that is either the same for every profile or an object keyed by profile name.
  PerProfile per_profile(const Json& obj, const char* key,
                         const std::array<bool, kProfileCount>& applies, std::string_view what) {
    PerProfile out;
    const Json* v = optional(obj, key);
    if (v == nullptr) return out;
    if (!v->is_object()) {
      const std::uint32_t n = number_value(*v, what);
      for (auto& x : out.value) x = n;
      return out;
    }
    for (const auto& [pname, pv] : v->items()) {
      Profile p{};
      if (!parse_profile(pname, p)) fail(fmt::format("{}: unknown profile '{}'", what, pname));
      out.value[index_of(p)] = number_value(pv, fmt::format("{} of profile '{}'", what, pname));
      if (!applies[index_of(p)]) {
        warn(ctx_, fmt::format("{} given for profile '{}', which the entry does not apply to "
                               "(ignored)",
                               what, pname));
      }
    }
    return out;
  }

  std::string_view intern(std::string s) { return m_.strings_.emplace_back(std::move(s)); }

  // ---- profiles ----------------------------------------------------------------------------

  void load_profiles(const Json& list) {
    if (!list.is_array() || list.empty()) fail("'profiles' must be a non-empty array");
    std::array<bool, kProfileCount> seen{};
    for (std::size_t i = 0; i < list.size(); ++i) {
      const Json& j = list[i];
      ctx_ = fmt::format("profile #{}", i);
      expect_object(j, "a profile");
      const std::string name = string(j, "name", true);
      ctx_ = fmt::format("profile '{}'", name);
      check_keys(j, kProfileKeys);
      Profile id{};
      if (!parse_profile(name, id)) fail("unknown profile name (expected spc3, vpc3plus or dpc31)");
      if (seen[index_of(id)]) fail("profile defined twice");
      seen[index_of(id)] = true;

      ProfileDesc& p = m_.profile_store_[index_of(id)];
      p.id = id;
      p.name = intern(name);
      p.title = intern(string(j, "title", true));
      const std::string macro = string(j, "macro", true);
      if (!is_identifier(macro, false))
        fail(fmt::format("macro prefix '{}' is not an identifier", macro));
      p.macro = intern(macro);
      p.address_bits = static_cast<std::uint8_t>(bounded(j, "address_bits", 16));
      if (p.address_bits < 8) fail("'address_bits' must be 8..16");
      const std::uint32_t space = 1u << p.address_bits;
      p.ram_begin = bounded(j, "ram_begin", space - 1);
      p.ram_size = bounded(j, "ram_size", space);
      p.ram_size_large = bounded(j, "ram_size_large", space);
      if (p.ram_begin + std::max(p.ram_size, p.ram_size_large) > space) {
        fail(fmt::format("RAM 0x{:X}+0x{:X} exceeds the {}-bit address space", p.ram_begin,
                         std::max(p.ram_size, p.ram_size_large), p.address_bits));
      }
      p.cells_base = bounded(j, "cells_base", space - (kLastCell - kFirstCell + 1));
      p.user_base = bounded(j, "user_base", space - 1);
      p.segment_shift = static_cast<std::uint8_t>(bounded(j, "segment_shift", 15));
      p.segment_shift_large = static_cast<std::uint8_t>(bounded(j, "segment_shift_large", 15));
      p.violation_from = bounded(j, "violation_from", space);
      p.violation_subtract = bounded(j, "violation_subtract", space);
      p.release = static_cast<std::uint8_t>(bounded(j, "release", 15));
      p.bus_access_cycles = static_cast<std::uint8_t>(bounded(j, "bus_access_cycles", 255));
      if (p.bus_access_cycles == 0) fail("'bus_access_cycles' must be > 0");
      p.note = intern(string(j, "note", false));
      load_regions(p, required(j, "regions"));
      if (const Json* layouts = optional(j, "layouts")) load_layouts(p, *layouts);
    }
    ctx_ = "top level";
    for (Profile p : kAllProfiles) {
      if (!seen[index_of(p)]) fail(fmt::format("profile '{}' missing", profile_name(p)));
      m_.profile_ptrs_.push_back(&m_.profile_store_[index_of(p)]);
    }
  }

  void load_regions(const ProfileDesc& p, const Json& list) {
    if (!list.is_array()) fail("'regions' must be an array");
    const std::string profile_ctx = ctx_;
    const std::uint32_t space = 1u << p.address_bits;
    auto& regions = m_.regions_[index_of(p.id)];
    for (std::size_t i = 0; i < list.size(); ++i) {
      const Json& j = list[i];
      ctx_ = fmt::format("{}: region #{}", profile_ctx, i);
      expect_object(j, "a region");
      const std::string name = string(j, "name", true);
      ctx_ = fmt::format("{}: region '{}'", profile_ctx, name);
      check_keys(j, kRegionKeys);
      RegionDesc g{};
      g.name = intern(name);
      g.begin = bounded(j, "begin", space - 1);
      g.end = bounded(j, "end", space);
      if (g.end <= g.begin) fail("'end' must be above 'begin'");
      g.ram = boolean(j, "ram", true);
      g.reserved = boolean(j, "reserved", true);
      g.desc = intern(string(j, "desc", false));
      if (!regions.empty() && regions.back().end > g.begin) {
        fail(fmt::format("overlaps or precedes region '{}' (regions must be in address order)",
                         regions.back().name));
      }
      regions.push_back(g);
    }
    ctx_ = profile_ctx;
  }

  // A structure in RAM (regdesc.hpp LayoutDesc): bytes at distinct offsets below its size, each
  // with its bit masks ("bits") and codes ("values").
  void load_layouts(const ProfileDesc& p, const Json& list) {
    if (!list.is_array()) fail("'layouts' must be an array");
    const std::string profile_ctx = ctx_;
    auto& layouts = m_.layouts_[index_of(p.id)];
    for (std::size_t i = 0; i < list.size(); ++i) {
      const Json& j = list[i];
      ctx_ = fmt::format("{}: layout #{}", profile_ctx, i);
      expect_object(j, "a layout");
      const std::string name = string(j, "name", true);
      ctx_ = fmt::format("{}: layout '{}'", profile_ctx, name);
      check_keys(j, kLayoutKeys);
      if (!is_identifier(name, false)) fail("the name is not an identifier");
      LayoutDesc l{};
      l.name = intern(name);
      l.size = static_cast<std::uint8_t>(bounded(j, "size", 255));
      l.source = intern(string(j, "source", true));
      l.desc = intern(string(j, "desc", true));
      auto& bytes = m_.layout_bytes_.emplace_back();
      for (const Json& b : required(j, "bytes")) {
        expect_object(b, "a layout byte");
        check_keys(b, kLayoutByteKeys);
        LayoutByte lb{};
        lb.name = intern(string(b, "name", true));
        if (!is_identifier(lb.name, false))
          fail(fmt::format("byte name '{}' is not an identifier", lb.name));
        lb.offset = static_cast<std::uint8_t>(bounded(b, "offset", 254));
        if (lb.offset >= l.size) fail(fmt::format("byte '{}' lies beyond 'size'", lb.name));
        for (const LayoutByte& other : bytes) {
          if (other.offset == lb.offset || other.name == lb.name)
            fail(fmt::format("byte '{}' repeats offset or name of '{}'", lb.name, other.name));
        }
        lb.desc = intern(string(b, "desc", true));
        auto& values = m_.layout_values_.emplace_back();
        for (const bool mask : {true, false}) {
          const Json* vs = optional(b, mask ? "bits" : "values");
          if (vs == nullptr) continue;
          for (const Json& v : *vs) {
            expect_object(v, "a layout value");
            check_keys(v, kLayoutValueKeys);
            LayoutValue lv{};
            lv.name = intern(string(v, "name", true));
            if (!is_identifier(lv.name, false))
              fail(fmt::format("value name '{}' is not an identifier", lv.name));
            lv.value = static_cast<std::uint8_t>(bounded(v, mask ? "mask" : "value", 255));
            lv.mask = mask;
            lv.desc = intern(string(v, "desc", true));
            values.push_back(lv);
          }
        }
        lb.values = values;
        bytes.push_back(lb);
      }
      l.bytes = bytes;
      layouts.push_back(l);
    }
    ctx_ = profile_ctx;
  }

  // ---- fields ------------------------------------------------------------------------------

  RawField parse_field(const Json& j, bool access_allowed) const {
    expect_object(j, "a field");
    check_keys(j, kFieldKeys);
    RawField f;
    f.name = string(j, "name", true);
    if (!is_identifier(f.name, true)) fail(fmt::format("bad field name '{}'", f.name));
    const std::string bits = string(j, "bits", true);
    unsigned msb = 0;
    unsigned lsb = 0;
    char colon = 0;
    char extra = 0;
    std::istringstream in(bits);
    bool ok = false;
    if (bits.find(':') == std::string::npos) {
      ok = static_cast<bool>(in >> lsb) && !(in >> extra);
      msb = lsb;
    } else {
      ok = static_cast<bool>(in >> msb >> colon >> lsb) && colon == ':' && !(in >> extra);
    }
    const bool digits = !bits.empty() && std::all_of(bits.begin(), bits.end(), [](char c) {
      return std::isdigit(static_cast<unsigned char>(c)) != 0 || c == ':';
    });
    if (!ok || !digits || msb < lsb || msb > 15) {
      fail(fmt::format("field '{}': bad bits '{}' (expected \"n\" or \"msb:lsb\")", f.name, bits));
    }
    f.lsb = lsb;
    f.width = msb - lsb + 1;
    f.pulse = boolean(j, "pulse", false);
    f.desc = string(j, "desc", false);
    if (const Json* a = optional(j, "access")) {
      if (!access_allowed) {
        fail(fmt::format("field '{}': 'access' not allowed here (the register gives it)", f.name));
      }
      f.access = parse_access_value(*a, fmt::format("field '{}'", f.name));
    }
    return f;
  }

  // `what` prefixes the message ("field 'X'"); empty for the register's own access.
  Access parse_access_value(const Json& v, std::string_view what) const {
    const std::string prefix = what.empty() ? std::string{} : fmt::format("{}: ", what);
    if (!v.is_string()) fail(fmt::format("{}access must be a string", prefix));
    Access a{};
    if (!parse_access(v.get<std::string>(), a)) {
      fail(fmt::format("{}unknown access '{}'", prefix, v.get<std::string>()));
    }
    return a;
  }

  void load_fieldsets(const Json& root) {
    const Json* sets = optional(root, "fieldsets");
    if (sets == nullptr) return;
    expect_object(*sets, "'fieldsets'");
    for (const auto& [name, list] : sets->items()) {
      ctx_ = fmt::format("fieldset '{}'", name);
      if (!list.is_array() || list.empty()) fail("must be a non-empty array of fields");
      std::vector<RawField> fields;
      for (const Json& f : list) fields.push_back(parse_field(f, false));
      fieldsets_[name] = std::move(fields);
      fieldset_used_[name] = false;
    }
  }

  // The register's fields with their access, from fieldset (+ override), fields or access.
  std::vector<RawField> register_fields(const Json& j, const std::string& name, unsigned width,
                                        Kind kind) {
    const Json* set = optional(j, "fieldset");
    const Json* list = optional(j, "fields");
    const Json* access = optional(j, "access");
    const Json* overrides = optional(j, "override");
    std::vector<RawField> fields;
    if (set != nullptr && list != nullptr) fail("both 'fieldset' and 'fields'");
    if (overrides != nullptr && set == nullptr) fail("'override' without 'fieldset'");
    if (set != nullptr) {
      if (!set->is_string()) fail("'fieldset' must be a string");
      const auto it = fieldsets_.find(set->get<std::string>());
      if (it == fieldsets_.end())
        fail(fmt::format("unknown fieldset '{}'", set->get<std::string>()));
      fieldset_used_[it->first] = true;
      if (access == nullptr) fail("'fieldset' without 'access'");
      const Access a = parse_access_value(*access, {});
      fields = it->second;
      for (auto& f : fields) f.access = a;
      if (overrides != nullptr) {
        expect_object(*overrides, "'override'");
        for (const auto& [fname, fa] : overrides->items()) {
          // clang 14 (the fuzz build) cannot capture a structured binding in a lambda.
          const std::string& wanted = fname;
          auto f = std::find_if(fields.begin(), fields.end(),
                                [&](const RawField& x) { return x.name == wanted; });
          if (f == fields.end()) {
            fail(fmt::format("override of field '{}', which fieldset '{}' does not have", fname,
                             it->first));
          }
          f->access = parse_access_value(fa, fmt::format("override of '{}'", fname));
        }
      }
    } else if (list != nullptr) {
      // A register-level access is the default for fields that do not give their own.
      std::optional<Access> fallback;
      if (access != nullptr) fallback = parse_access_value(*access, {});
      if (!list->is_array() || list->empty()) fail("'fields' must be a non-empty array");
      for (const Json& f : *list) {
        RawField rf = parse_field(f, true);
        if (!rf.access) rf.access = fallback;
        if (!rf.access) fail(fmt::format("field '{}': missing key 'access'", rf.name));
        fields.push_back(std::move(rf));
      }
    } else if (access != nullptr) {
      RawField f;
      f.name = name;
      f.lsb = 0;
      f.width = width;
      f.access = parse_access_value(*access, {});
      fields.push_back(std::move(f));
    } else if (kind != Kind::reserved) {
      fail("no 'fields', 'fieldset' or 'access' (only reserved entries may have no fields)");
    }

    std::uint32_t used = 0;
    std::set<std::string> names;
    for (const RawField& f : fields) {
      if (f.lsb + f.width > width) {
        fail(fmt::format("field '{}' bits {} outside the {}-bit width", f.name,
                         f.width == 1 ? fmt::format("{}", f.lsb)
                                      : fmt::format("{}:{}", f.lsb + f.width - 1, f.lsb),
                         width));
      }
      const std::uint32_t mask = f.mask();
      if ((used & mask) != 0) {
        const auto other = std::find_if(fields.begin(), fields.end(), [&](const RawField& x) {
          return &x != &f && (x.mask() & mask) != 0;
        });
        fail(fmt::format("fields '{}' and '{}' overlap", other->name, f.name));
      }
      used |= mask;
      if (!names.insert(f.name).second) fail(fmt::format("field '{}' defined twice", f.name));
    }
    return fields;
  }

  // ---- registers ---------------------------------------------------------------------------

  template <typename E>
  E enum_value(const Json& j, const char* key, bool (*parse)(std::string_view, E&)) const {
    const std::string s = string(j, key, true);
    E e{};
    if (!parse(s, e)) fail(fmt::format("unknown {} '{}'", key, s));
    return e;
  }

  void parse_bytes(const Json& j, unsigned width, RegDesc& r) const {
    const Json* b = optional(j, "bytes");
    if (width == 8) {
      if (b != nullptr) fail("'bytes' given for an 8-bit register");
      r.intel[0] = r.intel[1] = r.motorola[0] = r.motorola[1] = 0;
      return;
    }
    if (b == nullptr) fail("16-bit register without 'bytes'");
    expect_object(*b, "'bytes'");
    for (const auto& [mode, order] : b->items()) {
      std::uint8_t* dst = nullptr;
      if (mode == "intel") {
        dst = r.intel;
      } else if (mode == "motorola") {
        dst = r.motorola;
      } else {
        fail(fmt::format("'bytes': unknown bus mode '{}' (expected intel, motorola)", mode));
      }
      const bool ok =
          order.is_array() && order.size() == 2 && order[0].is_string() && order[1].is_string() &&
          ((order[0] == "lo" && order[1] == "hi") || (order[0] == "hi" && order[1] == "lo"));
      if (!ok) fail(fmt::format("'bytes.{}' must be [\"lo\", \"hi\"] or [\"hi\", \"lo\"]", mode));
      dst[0] = order[0] == "lo" ? 0 : 1;
      dst[1] = order[1] == "lo" ? 0 : 1;
    }
    if (!b->contains("intel") || !b->contains("motorola")) {
      fail("'bytes' needs both 'intel' and 'motorola'");
    }
  }

  RegId reg_id(const std::string& name) {
    const auto it = std::find(m_.reg_names_.begin(), m_.reg_names_.end(), name);
    if (it != m_.reg_names_.end()) {
      return static_cast<RegId>(it - m_.reg_names_.begin());
    }
    m_.reg_names_.push_back(name);
    return static_cast<RegId>(m_.reg_names_.size() - 1);
  }

  // Marks the bytes [addr, addr + bytes) of one side of a profile as used by `name`.
  void claim(Profile p, bool read, std::uint32_t addr, unsigned bytes, const std::string& name) {
    auto& used = (read ? read_claims_ : write_claims_)[index_of(p)];
    for (unsigned i = 0; i < bytes; ++i) {
      const auto [it, fresh] = used.emplace(addr + i, name);
      if (!fresh) {
        fail(fmt::format(
            "{} address {} in profile '{}' already used by '{}'", read ? "read" : "write",
            hex_addr(m_.profile_store_[index_of(p)], addr + i), profile_name(p), it->second));
      }
    }
  }

  void check_in_space(const ProfileDesc& p, std::string_view side, std::uint32_t addr,
                      unsigned bytes) const {
    if (addr + bytes > (1u << p.address_bits)) {
      fail(fmt::format("{} address {} outside the {}-bit address space of profile '{}'", side,
                       hex_addr(p, addr), p.address_bits, p.name));
    }
  }

  void load_register(const Json& j, std::size_t index) {
    ctx_ = fmt::format("register #{}", index);
    expect_object(j, "a register");
    const std::string name = string(j, "name", true);
    ctx_ = fmt::format("register '{}'", name);
    if (!is_identifier(name, false)) fail("the name is not a C identifier");
    check_keys(j, kRegisterKeys);

    const Kind kind = enum_value<Kind>(j, "kind", parse_kind);
    const Block block = enum_value<Block>(j, "block", parse_block);
    const std::uint32_t width = *number(j, "width", true);
    if (width != 8 && width != 16) fail(fmt::format("width {} (must be 8 or 16)", width));
    const unsigned bytes = width / 8;

    std::array<bool, kProfileCount> applies{};
    if (const Json* list = optional(j, "profiles")) {
      if (!list->is_array() || list->empty()) fail("'profiles' must be a non-empty array");
      for (const Json& pn : *list) {
        Profile p{};
        if (!pn.is_string() || !parse_profile(pn.get<std::string>(), p)) {
          fail(fmt::format("unknown profile {}", pn.dump()));
        }
        if (applies[index_of(p)]) fail(fmt::format("profile '{}' listed twice", profile_name(p)));
        applies[index_of(p)] = true;
      }
    } else {
      applies.fill(true);
    }

    // Fields and masks (the same in every profile the entry applies to).
    const std::vector<RawField> raw = register_fields(j, name, width, kind);
    RegDesc base{};
    base.name = intern(name);
    base.id = reg_id(name);
    base.target = base.id;
    base.kind = kind;
    base.block = block;
    base.width = static_cast<std::uint8_t>(width);
    auto& fields = m_.field_lists_.emplace_back();
    std::uint16_t covered = 0;
    for (const RawField& f : raw) {
      // A bit the register ignores or reserves (an override) is never set: no pulse.
      const bool pulse = f.pulse && *f.access != Access::IGN && *f.access != Access::RSVD;
      fields.push_back(FieldDesc{.name = intern(f.name),
                                 .lsb = static_cast<std::uint8_t>(f.lsb),
                                 .width = static_cast<std::uint8_t>(f.width),
                                 .access = *f.access,
                                 .pulse = pulse,
                                 .desc = intern(f.desc)});
      const auto mask = static_cast<std::uint16_t>(f.mask());
      covered |= mask;
      access_mask(base, *f.access) |= mask;
      if (pulse) base.pulse |= mask;
    }
    base.rsvd |= static_cast<std::uint16_t>(~covered & base.mask());
    base.fields = fields;

    base.reserved = boolean(j, "reserved", false);
    if (base.reserved && kind != Kind::cell) fail("'reserved' is only for cells");
    base.plain = plain_lanes(base);
    const std::string target = string(j, "target", false);
    if (kind == Kind::port && target.empty()) fail("port without 'target'");
    if (kind != Kind::port && !target.empty()) fail("'target' on an entry that is not a port");
    parse_bytes(j, width, base);

    const std::string origin = string(j, "origin", true);
    if (origin != "documented" && origin != "modelled") {
      fail(fmt::format("unknown origin '{}' (expected documented or modelled)", origin));
    }
    base.documented = origin == "documented";
    base.source = intern(string(j, "source", false));
    base.note = intern(string(j, "note", false));
    base.desc = intern(string(j, "desc", false));

    const PerProfile reset = per_profile(j, "reset", applies, "reset");
    std::optional<std::uint32_t> cell;
    PerProfile read;
    PerProfile write;
    if (kind == Kind::cell) {
      if (j.contains("read") || j.contains("write")) {
        fail("a cell has no 'read'/'write' (its address follows from 'cell')");
      }
      cell = number(j, "cell", true);
      if (*cell < kFirstCell) fail(fmt::format("cell 0x{:02X} below 0x{:02X}", *cell, kFirstCell));
    } else {
      if (j.contains("cell")) fail("'cell' on an entry that is not a cell");
      read = per_profile(j, "read", applies, "read address");
      write = per_profile(j, "write", applies, "write address");
    }

    for (Profile p : kAllProfiles) {
      const std::size_t pi = index_of(p);
      if (!applies[pi]) continue;
      const ProfileDesc& prof = m_.profile_store_[pi];
      RegDesc r = base;
      if (std::any_of(m_.regs_[pi].begin(), m_.regs_[pi].end(),
                      [&](const RegDesc& x) { return x.name == r.name; })) {
        fail(fmt::format("defined twice for profile '{}'", prof.name));
      }
      if (j.contains("reset")) {
        if (!reset.value[pi]) fail(fmt::format("'reset' has no value for profile '{}'", prof.name));
        if (*reset.value[pi] > r.mask()) {
          fail(fmt::format("reset 0x{:X} does not fit {} bits", *reset.value[pi], width));
        }
        r.has_reset = true;
        r.reset = static_cast<std::uint16_t>(*reset.value[pi]);
      }
      std::optional<std::uint32_t> rd = read.value[pi];
      std::optional<std::uint32_t> wr = write.value[pi];
      if (cell) {
        // The SPC3's cells end at 3Fh where its user area begins; the DPC31's parameter cells
        // run on up to its user area at 08A0h.
        rd = wr = prof.cells_base + (*cell - kFirstCell);
        if (*rd + bytes > prof.user_base) {
          fail(fmt::format(
              "cell 0x{:02X} of profile '{}' at 0x{:04X} reaches the user area at 0x{:04X}", *cell,
              prof.name, *rd, prof.user_base));
        }
      }
      if (kind == Kind::port && (!wr || rd)) {
        fail(fmt::format("a port needs a write address and no read address (profile '{}')",
                         prof.name));
      }
      if (rd) {
        check_in_space(prof, "read", *rd, bytes);
        claim(p, true, *rd, bytes, name);
      }
      if (wr) {
        check_in_space(prof, "write", *wr, bytes);
        claim(p, false, *wr, bytes, name);
      }
      if (const Json* al = optional(j, "alias"); al != nullptr) {
        if (!al->is_object()) fail("'alias' must be an object: profile name -> the manual's name");
        if (al->contains(prof.name)) {
          const Json& n = (*al)[std::string(prof.name)];
          if (!n.is_string() || n.get<std::string>().empty())
            fail(fmt::format("alias of profile '{}' must be a non-empty string", prof.name));
          r.alias = intern(n.get<std::string>());
        }
      }
      for (const RegDesc& x : m_.regs_[pi]) {
        if (x.alias == r.name || (!r.alias.empty() && (r.alias == x.name || r.alias == x.alias)))
          fail(fmt::format("name or alias '{}' used twice for profile '{}'",
                           x.alias == r.name ? r.name : r.alias, prof.name));
      }
      r.read_addr = rd ? static_cast<std::int32_t>(*rd) : -1;
      r.write_addr = wr ? static_cast<std::int32_t>(*wr) : -1;
      m_.regs_[pi].push_back(r);
      if (!target.empty()) pending_targets_.push_back({p, m_.regs_[pi].size() - 1, target});
    }
  }

  void resolve_targets() {
    for (const PendingTarget& t : pending_targets_) {
      auto& regs = m_.regs_[index_of(t.profile)];
      RegDesc& port = regs[t.index];
      ctx_ = fmt::format("register '{}'", port.name);
      const auto it = std::find_if(regs.begin(), regs.end(),
                                   [&](const RegDesc& r) { return r.name == t.target; });
      if (it == regs.end()) {
        fail(fmt::format("target '{}' does not exist in profile '{}'", t.target,
                         profile_name(t.profile)));
      }
      if (it->kind == Kind::port) fail(fmt::format("target '{}' is itself a port", t.target));
      if (it->width != port.width) {
        fail(fmt::format("target '{}' is {} bits wide, the port {}", t.target, it->width,
                         port.width));
      }
      port.target = it->id;
    }
  }

  void finish() {
    for (Profile p : kAllProfiles) {
      ProfileDesc& prof = m_.profile_store_[index_of(p)];
      prof.regs = m_.regs_[index_of(p)];
      prof.regions = m_.regions_[index_of(p)];
      prof.layouts = m_.layouts_[index_of(p)];
      if (prof.regs.empty()) {
        ctx_ = fmt::format("profile '{}'", prof.name);
        fail("no register applies to this profile");
      }
    }
  }

  struct PendingTarget {
    Profile profile;
    std::size_t index;
    std::string target;
  };

  RegModel& m_;
  std::string file_;
  std::string ctx_;
  std::map<std::string, std::vector<RawField>> fieldsets_;
  std::map<std::string, bool> fieldset_used_;
  std::array<std::map<std::uint32_t, std::string>, kProfileCount> read_claims_;
  std::array<std::map<std::uint32_t, std::string>, kProfileCount> write_claims_;
  std::vector<PendingTarget> pending_targets_;
};

RegModel::RegModel() = default;
RegModel::~RegModel() = default;

const ProfileDesc& RegModel::profile(Profile p) const { return profile_store_[index_of(p)]; }

std::unique_ptr<RegModel> RegModel::parse(std::string_view text, const std::string& file) {
  const Json root = parse_text(text, file);
  std::unique_ptr<RegModel> m(new RegModel());
  Loader(*m, file).load(root);
  return m;
}

std::unique_ptr<RegModel> RegModel::load(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(fmt::format("{}: cannot open the file", path));
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw Error(fmt::format("{}: read error", path));
  return parse(text.str(), path);
}

}  // namespace dpc31::regjson

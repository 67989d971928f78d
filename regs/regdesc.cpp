// The table-independent functions declared in dpc31/regdesc.hpp: enum <-> name, the legend
// texts and the register look-ups. The tables themselves (profile_desc, chip_timing) are
// generated into reg_tables.cpp by tools/reggen.
#include "dpc31/regdesc.hpp"

#include <array>
#include <cstddef>
#include <string_view>

namespace dpc31 {
namespace {

template <typename E>
struct NameEntry {
  E value;
  std::string_view name;
  std::string_view desc;
};

// One row per enumerator, in enumerator order (checked by the static_asserts below).
constexpr std::array<NameEntry<Kind>, 5> kKinds{{
    {Kind::latch, "latch", "flip-flops inside the chip"},
    {Kind::cell, "cell", "a RAM cell with a fixed meaning (organisational parameter)"},
    {Kind::derived, "derived",
     "read side computed by the owning block (Int_Reg, Status_Reg, buffer state machines, "
     "command reads)"},
    {Kind::port, "port", "write side acting on another register (its target)"},
    {Kind::reserved, "reserved",
     "a documented gap: reads 00h, writes ignored, every access logged"},
}};

constexpr std::array<NameEntry<Access>, 9> kAccesses{{
    {Access::RO, "RO", "read only: writes have no effect"},
    {Access::RW, "RW", "read/write storage"},
    {Access::W1C, "W1C", "write 1 clears the bit of the target"},
    {Access::W1S, "W1S", "write 1 sets the bit of the target"},
    {Access::CMD, "CMD", "command on read: reading performs an action, the value is its result"},
    {Access::WO, "WO", "write-only storage: the read side of the address is another register"},
    {Access::IGN, "IGN", "documented as 'no effect when written'; a written 1 is logged"},
    {Access::RSVD, "RSVD",
     "reserved: reads 0, not writable; a write that would change it is logged"},
    {Access::UNIMP, "UNIMP",
     "exists on the chip, behaviour not modelled: stored; logged at every access of a register of "
     "nothing else, elsewhere at a write of 1 to one and at a read while one is 1"},
}};

constexpr std::array<NameEntry<Block>, 9> kBlocks{{
    {Block::irq, "irq", ""},
    {Block::mode, "mode", ""},
    {Block::status, "status", ""},
    {Block::buffers, "buffers", ""},
    {Block::dp_sm, "dp_sm", ""},
    {Block::watchdog, "watchdog", ""},
    {Block::fdl, "fdl", ""},
    {Block::ram, "ram", ""},
    {Block::requests, "requests", ""},
}};

constexpr std::array<NameEntry<Profile>, 3> kProfileNames{{
    {Profile::spc3, "spc3", ""},
    {Profile::vpc3plus, "vpc3plus", ""},
    {Profile::dpc31, "dpc31", ""},
}};

template <typename E, std::size_t N>
constexpr bool in_enum_order(const std::array<NameEntry<E>, N>& table) {
  for (std::size_t i = 0; i < N; ++i) {
    if (static_cast<std::size_t>(table[i].value) != i) return false;
  }
  return true;
}
static_assert(in_enum_order(kKinds));
static_assert(in_enum_order(kAccesses));
static_assert(in_enum_order(kBlocks));
static_assert(in_enum_order(kProfileNames));

template <typename E, std::size_t N>
const NameEntry<E>* entry(const std::array<NameEntry<E>, N>& table, E value) {
  const auto i = static_cast<std::size_t>(value);
  return i < N ? &table[i] : nullptr;
}

template <typename E, std::size_t N>
std::string_view name_of(const std::array<NameEntry<E>, N>& table, E value) {
  const auto* e = entry(table, value);
  return e != nullptr ? e->name : std::string_view{"?"};
}

template <typename E, std::size_t N>
std::string_view desc_of(const std::array<NameEntry<E>, N>& table, E value) {
  const auto* e = entry(table, value);
  return e != nullptr ? e->desc : std::string_view{};
}

template <typename E, std::size_t N>
bool parse_name(const std::array<NameEntry<E>, N>& table, std::string_view s, E& out) {
  for (const auto& e : table) {
    if (e.name == s) {
      out = e.value;
      return true;
    }
  }
  return false;
}

}  // namespace

std::string_view access_name(Access a) { return name_of(kAccesses, a); }
std::string_view kind_name(Kind k) { return name_of(kKinds, k); }
std::string_view block_name(Block b) { return name_of(kBlocks, b); }
std::string_view profile_name(Profile p) { return name_of(kProfileNames, p); }
std::string_view access_desc(Access a) { return desc_of(kAccesses, a); }
std::string_view kind_desc(Kind k) { return desc_of(kKinds, k); }

bool parse_profile(std::string_view s, Profile& out) { return parse_name(kProfileNames, s, out); }
bool parse_kind(std::string_view s, Kind& out) { return parse_name(kKinds, s, out); }
bool parse_access(std::string_view s, Access& out) { return parse_name(kAccesses, s, out); }
bool parse_block(std::string_view s, Block& out) { return parse_name(kBlocks, s, out); }

const RegDesc* find_reg(const ProfileDesc& p, RegId id) {
  for (const auto& r : p.regs) {
    if (r.id == id) return &r;
  }
  return nullptr;
}

const RegDesc* find_reg(const ProfileDesc& p, std::string_view name) {
  for (const auto& r : p.regs) {
    if (r.name == name || (!r.alias.empty() && r.alias == name)) return &r;
  }
  return nullptr;
}

}  // namespace dpc31

// Scenario files: the CPU's bus door (scenario_bus.hpp, docs/scenario-format.md "Bus accesses").
#include "scenario_bus.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <optional>

#include "dpc31/dp.hpp"
#include "dpc31/regdesc.hpp"
#include "scenario_lex.hpp"
#include "textfile.hpp"

namespace dpc31::scenario_bus {

namespace {

using scenario_lex::bytes_text;
using scenario_lex::fail;

std::uint32_t map_size(Profile p) { return std::uint32_t{1} << profile_desc(p).address_bits; }

// A register of the profile by its name (or its alias in this profile's manual).
const RegDesc* reg_named(Profile p, std::string_view name) {
  return find_reg(profile_desc(p), name);
}

bool is_name(std::string_view s) {
  return !s.empty() && ((s[0] >= 'A' && s[0] <= 'Z') || (s[0] >= 'a' && s[0] <= 'z'));
}

const RegDesc& reg_or_fail(Profile p, std::string_view name) {
  const RegDesc* r = reg_named(p, name);
  if (r == nullptr) {
    fail(fmt::format("'{}' is not a register of {} (names as in docs/registers.md)", shown(name),
                     profile_desc(p).name));
  }
  return *r;
}

std::uint32_t address(Profile p, std::string_view s, std::size_t len) {
  const std::uint32_t a =
      static_cast<std::uint32_t>(scenario_lex::number(s, "address", 0, map_size(p) - 1));
  if (a + len > map_size(p)) {
    fail(fmt::format("{} bytes from {} run past the end of the {} map ({:#x} bytes)", len, shown(s),
                     profile_desc(p).name, map_size(p)));
  }
  return a;
}

std::string hex(std::uint32_t v, unsigned width) {
  return width > 8 ? fmt::format("0x{:04X}", v) : fmt::format("0x{:02X}", v);
}

// Byte k of a register access sits at addr + k; which byte of the value it is follows the bus
// mode's placement (regs/dpc31_regs.json).
unsigned lane(const RegDesc& r, BusMode bus, unsigned k) {
  return bus == BusMode::intel ? r.intel[k] : r.motorola[k];
}

}  // namespace

bool parse_action(std::string_view cmd, std::span<const std::string_view> pos,
                  std::span<const Option> opts, Profile p, ScenarioStep& st, ReadShape& last_read) {
  if (cmd == "request") {
    if (!opts.empty()) fail(fmt::format("unknown option '{}' for request", shown(opts[0].first)));
    return parse_request(pos, p, st);
  }
  const bool write = cmd == "write";
  if (!write && cmd != "read") return false;
  st.kind = write ? StepKind::write : StepKind::read;
  const std::size_t want = write ? 2 : 1;
  std::optional<std::string_view> block;  // bytes= (write) / count= (read)
  for (const Option& o : opts) {
    if (o.first != (write ? "bytes" : "count")) {
      fail(fmt::format("unknown option '{}' for {}", shown(o.first), cmd));
    }
    block = o.second;
  }
  const std::size_t npos = block ? 1 : want;
  if (pos.size() != npos) {
    fail(write ? std::string("expected 'write REG VALUE', 'write ADDR VALUE' or 'write ADDR "
                             "bytes=BYTES'")
               : std::string("expected 'read REG', 'read ADDR' or 'read ADDR count=N'"));
  }
  last_read = {};
  if (block) {
    if (is_name(pos[0]))
      fail(fmt::format("a block access starts at an address, not at a register"));
    if (write) {
      st.bytes = scenario_lex::bytes(*block, "bytes", map_size(p));
      if (st.bytes.empty()) fail("bytes: at least one byte");
      st.addr = address(p, pos[0], st.bytes.size());
    } else {
      st.count = scenario_lex::number(*block, "count", 1, map_size(p));
      st.addr = address(p, pos[0], st.count);
      last_read = {true, true, 8};
    }
    st.has_bytes = true;
    return true;
  }
  unsigned width = 8;
  if (is_name(pos[0])) {
    const RegDesc& r = reg_or_fail(p, pos[0]);
    if ((write ? r.write_addr : r.read_addr) < 0) {
      fail(fmt::format("{} has no {} side in {}", r.name, write ? "write" : "read",
                       profile_desc(p).name));
    }
    st.reg = r.id;
    st.name = std::string(pos[0]);
    width = r.width;
  } else {
    st.addr = address(p, pos[0], 1);
  }
  if (write)
    st.value =
        static_cast<std::uint32_t>(scenario_lex::number(pos[1], "value", 0, (1u << width) - 1));
  if (!write) last_read = {true, false, width};
  return true;
}

// DPC31 p.22, Table 5.1-3 (docs/dpc31.md, "The queues").
bool parse_request(std::span<const std::string_view> pos, Profile p, ScenarioStep& st) {
  if (p != Profile::dpc31) fail("'request' is the DPC31's Instruction_Queue: needs profile dpc31");
  if (pos.empty()) fail("'request' needs a request name");
  constexpr std::pair<std::string_view, std::uint8_t> kCodes[] = {
      {"MAC_Start", request::MAC_Start},
      {"MAC_Stop", request::MAC_Stop},
      {"MAC_New_TRDY", request::MAC_New_TRDY},
      {"User_Leave_Master", request::User_Leave_Master},
      {"DPS_User_Wd", request::DPS_User_Wd}};
  const auto* c = std::find_if(std::begin(kCodes), std::end(kCodes),
                               [&](const auto& k) { return k.first == pos[0]; });
  if (c == std::end(kCodes)) {
    fail(
        fmt::format("unknown request '{}' (MAC_Start, MAC_Stop, MAC_New_TRDY N, "
                    "User_Leave_Master, DPS_User_Wd reset|enable|disable)",
                    shown(pos[0])));
  }
  st.kind = StepKind::request;
  st.name = std::string(pos[0]);
  st.value = c->second;
  if (c->second == request::MAC_New_TRDY) {
    if (pos.size() != 2) fail("expected 'request MAC_New_TRDY N' (the ready time in bit times)");
    st.value2 = static_cast<std::uint32_t>(scenario_lex::number(pos[1], "TRDY", 0, 255));
  } else if (c->second == request::DPS_User_Wd) {
    if (pos.size() != 2) fail("expected 'request DPS_User_Wd reset|enable|disable'");
    constexpr std::pair<std::string_view, std::uint8_t> kWd[] = {{"reset", request::Wd_Reset},
                                                                 {"enable", request::Wd_Enable},
                                                                 {"disable", request::Wd_Disable}};
    const auto* w = std::find_if(std::begin(kWd), std::end(kWd),
                                 [&](const auto& k) { return k.first == pos[1]; });
    if (w == std::end(kWd))
      fail(fmt::format("DPS_User_Wd '{}': reset, enable or disable", shown(pos[1])));
    st.value2 = w->second;
  } else if (pos.size() != 1) {
    fail(fmt::format("request {} takes no parameter", c->first));
  }
  return true;
}

bool parse_expect(std::span<const std::string_view> pos, Profile p, const ReadShape& last_read,
                  ScenarioStep& st) {
  const std::string_view what = pos[0];
  if (what == "indication") {
    if (p != Profile::dpc31) fail("'expect indication' needs profile dpc31");
    if (pos.size() != 3) fail("expected 'expect indication CODE EVENT'");
    st.expect = ExpectKind::indication;
    st.value = static_cast<std::uint32_t>(scenario_lex::number(pos[1], "indication code", 0, 255));
    st.value2 =
        static_cast<std::uint32_t>(scenario_lex::number(pos[2], "indication event", 0, 255));
  } else if (what == "reg") {
    if (pos.size() != 3) fail("expected 'expect reg NAME VALUE'");
    const RegDesc& r = reg_or_fail(p, pos[1]);
    st.expect = ExpectKind::reg;
    st.reg = r.id;
    st.name = std::string(pos[1]);
    st.value = static_cast<std::uint32_t>(
        scenario_lex::number(pos[2], "register value", 0, (1u << r.width) - 1));
  } else if (what == "ram") {
    if (pos.size() != 3) fail("expected 'expect ram ADDR BYTES'");
    st.expect = ExpectKind::ram;
    st.bytes = scenario_lex::bytes(pos[2], "ram", map_size(p));
    if (st.bytes.empty()) fail("ram: at least one byte");
    st.addr = address(p, pos[1], st.bytes.size());
  } else if (what == "read") {
    if (pos.size() != 2) fail("expected 'expect read VALUE' (or BYTES after a block read)");
    if (!last_read.seen) fail("'expect read' needs a 'read' before it");
    st.expect = ExpectKind::read;
    if (last_read.block) {
      st.bytes = scenario_lex::bytes(pos[1], "read", map_size(p));
      st.has_bytes = true;
    } else {
      st.value = static_cast<std::uint32_t>(
          scenario_lex::number(pos[1], "read value", 0, (1u << last_read.width) - 1));
      st.value2 = last_read.width;
    }
  } else {
    return false;
  }
  return true;
}

std::string act(Chip& chip, const ScenarioStep& st, LastRead& last) {
  const BusMode bus = chip.bus_mode();
  if (st.kind == StepKind::request) {
    // As a driver hands over a request: the entry (code, parameter), then InstQ_Wr one on.
    const std::optional<Chip::RequestSlot> slot = chip.next_request_slot();
    if (!slot) return "";
    chip.write(slot->entry, static_cast<std::uint8_t>(st.value));
    chip.write(slot->entry + 1, static_cast<std::uint8_t>(st.value2));
    chip.write(static_cast<std::uint32_t>(chip.addr_of(RegId::InstQ_Wr)), slot->next_wr);
    return fmt::format("request {} {:02X}h {:02X}h", st.name, st.value, st.value2);
  }
  if (st.has_bytes) {  // a block: one access per byte, in address order
    if (st.kind == StepKind::write) {
      chip.write_block(st.addr, st.bytes);
      return fmt::format("write {:#06x} <- {}", st.addr, bytes_text(st.bytes));
    }
    last = {true, true, 8, 0, std::vector<std::uint8_t>(st.count)};
    chip.read_block(st.addr, last.bytes);
    return fmt::format("read {:#06x} = {}", st.addr, bytes_text(last.bytes));
  }
  if (!st.reg) {
    if (st.kind == StepKind::write) {
      chip.write(st.addr, static_cast<std::uint8_t>(st.value));
      return fmt::format("write {:#06x} <- {}", st.addr, hex(st.value, 8));
    }
    last = {true, false, 8, chip.read(st.addr), {}};
    return fmt::format("read {:#06x} = {}", st.addr, hex(last.value, 8));
  }
  const RegDesc& r = *find_reg(chip.profile(), *st.reg);
  const unsigned n = r.width / 8;
  if (st.kind == StepKind::write) {
    for (unsigned k = 0; k < n; ++k) {
      chip.write(static_cast<std::uint32_t>(r.write_addr) + k,
                 static_cast<std::uint8_t>(st.value >> (8 * lane(r, bus, k))));
    }
    return fmt::format("write {} <- {}", st.name, hex(st.value, r.width));
  }
  std::uint32_t v = 0;
  for (unsigned k = 0; k < n; ++k) {
    v |= std::uint32_t{chip.read(static_cast<std::uint32_t>(r.read_addr) + k)}
         << (8 * lane(r, bus, k));
  }
  last = {true, false, r.width, v, {}};
  return fmt::format("read {} = {}", st.name, hex(v, r.width));
}

Check check(const Chip& chip, const ScenarioStep& st, const LastRead& last) {
  Check c;
  switch (st.expect) {
    case ExpectKind::indication: {
      // The entry before IndQ_Wr: the newest the chip wrote (docs/dpc31.md, "The queues").
      const auto cell = [&](RegId id) {
        return chip.peek(static_cast<std::uint32_t>(chip.addr_of(id)));
      };
      const unsigned len = cell(RegId::IndQ_Len);
      c.what = "indication";
      c.want = fmt::format("{:02X}h {:02X}h", st.value, st.value2);
      if (len == 0) {
        c.got = "no Indication_Queue (IndQ_Len 0)";
        break;
      }
      const std::uint32_t at =
          (std::uint32_t{cell(RegId::IndQ_Base)} << chip.profile().segment_shift) +
          ((cell(RegId::IndQ_Wr) + len - 1) % len) * request::kEntryBytes;
      c.got = fmt::format("{:02X}h {:02X}h", chip.peek(at), chip.peek(at + 1));
      break;
    }
    case ExpectKind::reg: {
      const RegDesc& r = *find_reg(chip.profile(), *st.reg);
      c.what = "reg " + st.name;
      c.want = hex(st.value, r.width);
      c.got = hex(chip.peek_reg(*st.reg), r.width);
      break;
    }
    case ExpectKind::ram: {
      c.what = fmt::format("ram {:#06x}", st.addr);
      std::vector<std::uint8_t> now(st.bytes.size());
      for (std::size_t i = 0; i < now.size(); ++i) {
        now[i] = chip.peek(st.addr + static_cast<std::uint32_t>(i));
      }
      c.want = bytes_text(st.bytes);
      c.got = bytes_text(now);
      break;
    }
    default:  // ExpectKind::read
      c.what = "read";
      if (st.has_bytes) {
        c.want = bytes_text(st.bytes);
        c.got = bytes_text(last.bytes);
      } else {
        c.want = hex(st.value, st.value2);
        c.got = hex(last.value, last.width);
      }
      break;
  }
  return c;
}

void when(const ScenarioStep& st, std::uint64_t since, std::uint64_t base, std::string& want,
          std::string& got) {
  const bool at = st.when == ScenarioStep::When::at;
  want += fmt::format(" {} {}", at ? "at" : "after", st.when_cycle);
  if (at) {
    got += fmt::format(" at {}", since);
  } else if (since < base) {
    got += fmt::format(" since cycle {}, before the last action began (cycle {})", since, base);
  } else {
    got += fmt::format(" after {}", since - base);
  }
}

}  // namespace dpc31::scenario_bus

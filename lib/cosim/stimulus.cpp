// The lockstep's stimulus vocabulary, once: every input event of docs/golden-model.md with its
// trace token, the block event of the chip session that drives it and the Inputs member it sets.
// The trace writer (Inputs::describe), the trace parser and the chip-session recorder all read
// this one table.
#include <fmt/format.h>

#include <array>
#include <charconv>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>

#include "block_event.hpp"
#include "dut.hpp"
#include "textfile.hpp"

namespace dpc31::cosim {

namespace {

using K = BlockEvent::Kind;

// What an event carries besides its strobe, and how a trace line spells it.
enum class Arg : std::uint8_t {
  none,       // ev_dout
  irq_mask,   // ev_irq(0010): the mask is the strobe
  gc_cmd,     // ev_gc(08)
  stat_diag,  // ev_diag_end(stat=1)
  dis_bits,   // ev_dis(3)
  bus_read,   // rd 0008
  bus_write,  // wr 0008<-02
  sap_ind,    // ev_sap_ind(0200,0c): the entry's address, the data length
  sap_entry,  // ev_sap_srd(0200)
};

struct EventInput {
  std::string_view name;
  K kind;
  bool Inputs::*strobe;  // nullptr: ev_irq
  Arg arg;
  // The one profile whose chip has this input (the dpc31's request interface, the vpc3plus's
  // SAP list), or none: every profile's.
  std::optional<Profile> only = std::nullopt;
};

// In the order a trace line names them (Inputs::describe).
constexpr std::array<EventInput, 23> kEventInputs = {{
    {"ev_dx", K::dx, &Inputs::ev_dx, Arg::none},
    {"rd", K::read, &Inputs::bus_rd, Arg::bus_read},
    {"wr", K::write, &Inputs::bus_wr, Arg::bus_write},
    {"ev_irq", K::irq, nullptr, Arg::irq_mask},
    {"ev_leave_master", K::leave_master, &Inputs::ev_leave_master, Arg::none},
    {"ev_wd_expired", K::wd_expired, &Inputs::ev_wd_expired, Arg::none},
    {"ev_prm_fault", K::prm_fault, &Inputs::ev_prm_fault, Arg::none},
    {"ev_gc", K::gc, &Inputs::ev_gc, Arg::gc_cmd},
    {"ev_dout", K::dout, &Inputs::ev_dout, Arg::none},
    {"ev_failsafe", K::failsafe, &Inputs::ev_failsafe, Arg::none},
    {"ev_din", K::din, &Inputs::ev_din, Arg::none},
    {"ev_diag_begin", K::diag_begin, &Inputs::ev_diag_begin, Arg::none},
    {"ev_diag_end", K::diag_end, &Inputs::ev_diag_end, Arg::stat_diag},
    {"ev_prm", K::prm, &Inputs::ev_prm, Arg::none},
    {"ev_cfg", K::cfg, &Inputs::ev_cfg, Arg::none},
    {"ev_ssa", K::ssa, &Inputs::ev_ssa, Arg::none},
    {"ev_dis", K::dis, &Inputs::ev_dis, Arg::dis_bits},
    {"ev_mac_stop", K::mac_stop, &Inputs::ev_mac_stop, Arg::none},
    {"ev_mac_start", K::mac_start, &Inputs::ev_mac_start, Arg::none, Profile::dpc31},
    {"ev_ext_prm", K::ext_prm, &Inputs::ev_ext_prm, Arg::none, Profile::vpc3plus},
    {"ev_sap_sent", K::sap_sent, &Inputs::ev_sap_sent, Arg::none, Profile::vpc3plus},
    {"ev_sap_ind", K::sap_ind, &Inputs::ev_sap_ind, Arg::sap_ind, Profile::vpc3plus},
    {"ev_sap_srd", K::sap_srd, &Inputs::ev_sap_srd, Arg::sap_entry, Profile::vpc3plus},
}};
static_assert(kEventInputs.size() == static_cast<std::size_t>(K::write) + 1,
              "a new BlockEvent::Kind: add its input here");

bool active(const Inputs& in, const EventInput& e) {
  return e.strobe != nullptr ? in.*e.strobe : in.ev_irq != 0;
}

std::string token(const Inputs& in, const EventInput& e) {
  switch (e.arg) {
    case Arg::none:
      return std::string(e.name);
    case Arg::irq_mask:
      return fmt::format("{}({:04x})", e.name, in.ev_irq);
    case Arg::gc_cmd:
      return fmt::format("{}({:02x})", e.name, in.gc_cmd);
    case Arg::stat_diag:
      return fmt::format("{}(stat={})", e.name, in.stat_diag ? 1 : 0);
    case Arg::dis_bits:
      return fmt::format("{}({:x})", e.name, in.dis_bits);
    case Arg::bus_read:
      return fmt::format("{} {:04x}", e.name, in.bus_addr);
    case Arg::bus_write:
      return fmt::format("{} {:04x}<-{:02x}", e.name, in.bus_addr, in.bus_wdata);
    case Arg::sap_ind:
      return fmt::format("{}({:04x},{:02x})", e.name, in.sap_entry, in.sap_len);
    case Arg::sap_entry:
      return fmt::format("{}({:04x})", e.name, in.sap_entry);
  }
  return {};
}

// The event with its value (irq mask, gc command, stat_diag, dis bits, bus address) and data
// (bus write data).
void set(Inputs& in, const EventInput& e, std::uint32_t value, std::uint8_t data) {
  if (e.strobe != nullptr) in.*e.strobe = true;
  switch (e.arg) {
    case Arg::none:
      break;
    case Arg::irq_mask:
      in.ev_irq = static_cast<std::uint16_t>(in.ev_irq | value);
      break;
    case Arg::gc_cmd:
      in.gc_cmd = static_cast<std::uint8_t>(value);
      break;
    case Arg::stat_diag:
      in.stat_diag = value != 0;
      break;
    case Arg::dis_bits:
      in.dis_bits = static_cast<std::uint8_t>(value);
      break;
    case Arg::bus_read:
      in.bus_addr = static_cast<std::uint16_t>(value);
      break;
    case Arg::bus_write:
      in.bus_addr = static_cast<std::uint16_t>(value);
      in.bus_wdata = data;
      break;
    case Arg::sap_ind:
      in.sap_entry = static_cast<std::uint16_t>(value);
      in.sap_len = data;
      break;
    case Arg::sap_entry:
      in.sap_entry = static_cast<std::uint16_t>(value);
      break;
  }
}

// bus_addr and sap_entry are 13-bit ports: a wider address would reach the C++ side whole and
// the RTL cut to 13 bits.
constexpr std::uint32_t kAddrMax = 0x1FFF;

// Up to 4 hex digits, either case (the writer writes lower case; a hand-edited line may not).
bool parse_hex(std::string_view t, std::uint32_t max, std::uint32_t& v) {
  if (t.empty() || t.size() > 4) return false;
  const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v, 16);
  return ec == std::errc() && end == t.data() + t.size() && v <= max;
}

// How a trace line spells an event's operand, for the message when it does not (hex, written in
// lower case).
std::string_view operand_syntax(Arg a) {
  switch (a) {
    case Arg::none:
      return "no operand";
    case Arg::irq_mask:
      return "(MASK), hex 1..ffff";
    case Arg::gc_cmd:
      return "(CMD), hex 0..ff";
    case Arg::stat_diag:
      return "(stat=0) or (stat=1)";
    case Arg::dis_bits:
      return "(BITS), 0..3";
    case Arg::bus_read:
      return "ADDR, hex 0..1fff";
    case Arg::bus_write:
      return "ADDR<-DATA, hex ADDR 0..1fff, DATA 0..ff";
    case Arg::sap_ind:
      return "(ENTRY,LEN), hex ENTRY 0..1fff, LEN 0..ff";
    case Arg::sap_entry:
      return "(ENTRY), hex 0..1fff";
  }
  return "";
}

// other: not this event's name; again: an event the line has already, or a second bus access
enum class Parsed : std::uint8_t { other, ok, bad, again };

// `tok` as this event's token (the bus accesses take their operand from `rest`).
Parsed parse(const EventInput& e, const std::string& tok, std::istringstream& rest, Inputs& in) {
  const std::string_view t(tok);
  // The event's name alone or followed by "(": its operand, missing or not, is judged below.
  if (!t.starts_with(e.name) || (t.size() > e.name.size() && t[e.name.size()] != '(')) {
    return Parsed::other;
  }
  const bool bare = e.arg == Arg::none || e.arg == Arg::bus_read || e.arg == Arg::bus_write;
  if (bare != (t.size() == e.name.size())) return Parsed::bad;
  std::uint32_t v = 0;
  std::uint32_t d = 0;
  // "name(hex)" with a value of at most `max`.
  auto arg = [&](std::uint32_t max) {
    return t.size() > e.name.size() + 2 && t.back() == ')' &&
           parse_hex(t.substr(e.name.size() + 1, t.size() - e.name.size() - 2), max, v);
  };
  bool good = true;
  switch (e.arg) {
    case Arg::none:
      break;
    case Arg::irq_mask:
      good = arg(0xFFFF) && v != 0;
      break;
    case Arg::gc_cmd:
      good = arg(0xFF);
      break;
    case Arg::stat_diag:
      good = t.substr(e.name.size()) == "(stat=0)" || t.substr(e.name.size()) == "(stat=1)";
      v = tok[tok.size() - 2] == '1' ? 1 : 0;
      break;
    case Arg::dis_bits:
      good = arg(3);
      break;
    case Arg::sap_ind: {  // name(EEEE,LL)
      const auto comma = t.find(',');
      good = comma != std::string_view::npos && t.size() >= comma + 3 && t.back() == ')' &&
             parse_hex(t.substr(e.name.size() + 1, comma - e.name.size() - 1), kAddrMax, v) &&
             parse_hex(t.substr(comma + 1, t.size() - comma - 2), 0xFF, d);
      break;
    }
    case Arg::sap_entry:
      good = arg(kAddrMax);
      break;
    case Arg::bus_read: {
      std::string a;
      good = (rest >> a) && parse_hex(a, kAddrMax, v);
      break;
    }
    case Arg::bus_write: {
      std::string a;
      good = static_cast<bool>(rest >> a);
      const auto arrow = a.find("<-");
      good = good && arrow != std::string::npos && parse_hex(a.substr(0, arrow), kAddrMax, v) &&
             parse_hex(a.substr(arrow + 2), 0xFF, d);
      break;
    }
  }
  if (!good) return Parsed::bad;
  // One cycle has one value per input: a second token would overwrite the first one's operand
  // (the bus address, the command) without a word.
  const bool bus = e.arg == Arg::bus_read || e.arg == Arg::bus_write;
  if (active(in, e) || (bus && (in.bus_rd || in.bus_wr))) return Parsed::again;
  set(in, e, v, static_cast<std::uint8_t>(d));
  return Parsed::ok;
}

}  // namespace

std::string Inputs::describe() const {
  std::string s = rst ? "rst" : "";
  for (const EventInput& e : kEventInputs) {
    if (!active(*this, e)) continue;
    if (!s.empty()) s += ' ';
    s += token(*this, e);
  }
  return s;
}

std::string parse_input_token(const std::string& tok, std::istringstream& rest, Inputs& in) {
  if (tok == "rst") {
    if (in.rst) return "'rst' twice in one cycle";
    in.rst = true;
    return {};
  }
  for (const EventInput& e : kEventInputs) {
    switch (parse(e, tok, rest, in)) {
      case Parsed::ok:
        return {};
      case Parsed::bad:
        return fmt::format("bad operand of '{}': {} expected", e.name, operand_syntax(e.arg));
      case Parsed::again:
        return e.arg == Arg::bus_read || e.arg == Arg::bus_write
                   ? fmt::format("a second bus access '{}' in one cycle (at most one: rd or wr)",
                                 e.name)
                   : fmt::format("'{}' twice in one cycle", e.name);
      case Parsed::other:
        break;
    }
  }
  return fmt::format("unknown stimulus '{}'", shown(tok));
}

std::string input_not_on(const Inputs& in, Profile p) {
  for (const EventInput& e : kEventInputs) {
    if (e.only && *e.only != p && active(in, e)) {
      return fmt::format("'{}' is an input of profile {} only, not of {}", e.name,
                         profile_desc(*e.only).name, profile_desc(p).name);
    }
  }
  return {};
}

void apply_block_event(Inputs& in, const BlockEvent& ev) {
  for (const EventInput& e : kEventInputs) {
    if (e.kind == ev.kind) set(in, e, ev.value, ev.data);
  }
}

}  // namespace dpc31::cosim

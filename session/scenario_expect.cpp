// The state expects' values (scenario_expect.hpp).
#include "scenario_expect.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "dpc31/regdesc.hpp"
#include "scenario_lex.hpp"
#include "scenario_send.hpp"
#include "textfile.hpp"
#include "vocabulary.hpp"

namespace dpc31::scenario_expect {

using scenario_lex::bytes_text;
using scenario_lex::fail;
using scenario_send::answer_is;
using scenario_send::answer_kind;

bool is_bus(ExpectKind k) {
  return k == ExpectKind::reg || k == ExpectKind::ram || k == ExpectKind::read ||
         k == ExpectKind::indication;
}

namespace {

const RegDesc& int_req_reg(Profile profile) {
  return *find_reg(profile_desc(profile), RegId::Int_Req_Reg);
}

bool is_irq_field(const FieldDesc& f) { return f.width == 1 && f.access != Access::RSVD; }

// The activations as "at 1234 (FDL_Ind)" (`after`: cycles since the action began).
std::string rises_text(const Seen& seen, bool after) {
  if (seen.irq_rises.empty()) return "no X/INT activation in the last action";
  std::string s;
  for (const auto& [cycle, ir] : seen.irq_rises) {
    std::string causes;
    for (const FieldDesc& f : int_req_reg(seen.chip.profile().id).fields) {
      if (is_irq_field(f) && ((ir >> f.lsb) & 1U) != 0)
        causes += fmt::format("{}{}", causes.empty() ? "" : "+", f.name);
    }
    s += fmt::format("{}{} {} ({})", s.empty() ? "" : ", ", after ? "after" : "at",
                     after ? cycle - seen.base_cycle : cycle, causes);
  }
  if (seen.irq_count > seen.irq_rises.size())
    s += fmt::format(", and {} more", seen.irq_count - seen.irq_rises.size());
  return s;
}

}  // namespace

std::uint32_t irq_bit(Profile profile, std::string_view name) {
  for (const FieldDesc& f : int_req_reg(profile).fields) {
    if (f.name == name && is_irq_field(f)) return f.lsb;
  }
  fail(fmt::format(
      "'{}' is not an interrupt of {} (Int_Req_Reg: DX_Out, New_Prm_Data, WD_DP_Control_Timeout, "
      "...)",
      shown(name), profile_desc(profile).name));
}

void parse_irq(std::span<const std::string_view> pos, Profile profile, ScenarioStep& st) {
  st.expect = ExpectKind::irq;
  if (pos.size() == 3 && pos[1] == "count") {
    if (st.when != ScenarioStep::When::any) fail("'expect irq count N' takes no 'at' / 'after'");
    st.name = "count";
    st.value = static_cast<std::uint32_t>(scenario_lex::number(pos[2], "count", 0, 0xFFFF'FFFF));
    return;
  }
  if (pos.size() != 2 || pos[1] == "count")
    fail("expected 'expect irq NAME at CYCLE|after N' or 'expect irq count N'");
  st.name = std::string(pos[1]);
  st.value2 = irq_bit(profile, pos[1]);
  if (st.when == ScenarioStep::When::any)
    fail(fmt::format("'expect irq {}' needs 'at CYCLE' or 'after N': the cycle X/INT went active",
                     shown(pos[1])));
}

std::string port_text(std::uint32_t v) {
  return v <= 0xF ? fmt::format("0x{:X} ({:04b})", v, v) : fmt::format("0x{:X}", v);
}

scenario_bus::Check check(const ScenarioStep& st, const Seen& seen) {
  std::string what;
  std::string want;
  std::string got;
  const std::vector<Responder::Output>& outs = seen.outputs;
  switch (st.expect) {
    case ExpectKind::dp_state:
      what = "dp_state";
      want = dp_state_name(static_cast<DpState>(st.value));
      got = dp_state_name(seen.chip.dp_state());
      break;
    case ExpectKind::wd_state:
      what = "wd_state";
      want = wd_state_name(static_cast<WdState>(st.value));
      got = wd_state_name(seen.chip.wd_state());
      break;
    case ExpectKind::outputs:
      what = "outputs";
      want = st.value != 0 ? "none" : bytes_text(st.bytes);
      got = outs.empty() ? "none" : bytes_text(outs.back().data);
      break;
    case ExpectKind::cleared:
      what = "cleared";
      want = std::to_string(st.value);
      got = outs.empty() ? "no outputs fetched" : outs.back().cleared ? "1" : "0";
      break;
    case ExpectKind::inputs:
      what = "inputs";
      want = bytes_text(st.bytes);
      got = seen.last_inputs ? bytes_text(*seen.last_inputs) : "no inputs received";
      break;
    case ExpectKind::counter: {
      what = "counter " + st.name;
      const auto fields = fdl_counter_fields();
      const auto f = std::find_if(fields.begin(), fields.end(),
                                  [&](const CounterField& c) { return c.name == st.name; });
      const std::uint32_t now = seen.chip.fdl_counters().*(f->member);
      if (st.value2 != 0) {
        want = fmt::format("+{}", st.value);
        got = fmt::format("+{}", now - seen.base_counters.*(f->member));
        if (got != want) got += fmt::format(" (now {})", now);
      } else {
        want = std::to_string(st.value);
        got = std::to_string(now);
      }
      break;
    }
    case ExpectKind::irr_bit: {
      what = "irr_bit " + st.name;
      want = std::to_string(st.value);
      got = ((seen.irr >> st.value2) & 1) != 0 ? "1" : "0";
      break;
    }
    case ExpectKind::answer: {
      what = "answer";
      const std::optional<fdl::Frame>& last = seen.last_answer;
      if (st.has_bytes) {  // the whole answer telegram
        want = bytes_text(st.bytes);
        got = last ? bytes_text(fdl::encode(*last)) : "none";
      } else {
        want = st.name;
        got = answer_is(last, st.name) ? st.name : answer_kind(last);
      }
      break;
    }
    case ExpectKind::station:
      what = "station";
      want = std::to_string(st.value);
      got = std::to_string(seen.chip.station_address());
      break;
    case ExpectKind::diag_byte:
      what = fmt::format("diag_byte {}", st.value2);
      want = fmt::format("0x{:02X}", st.value);
      got = !seen.last_diag ? std::string("no diagnosis received")
            : st.value2 >= seen.last_diag->size()
                ? fmt::format("{} bytes", seen.last_diag->size())
                : fmt::format("0x{:02X}", (*seen.last_diag)[st.value2]);
      break;
    case ExpectKind::baud:
      what = "baud";
      want = std::to_string(st.value);
      got = std::to_string(seen.baud);
      break;
    case ExpectKind::pb3:
      what = "pb3";
      want = std::to_string(st.value);
      got = seen.pb3 ? "1" : "0";
      break;
    case ExpectKind::port:
      what = "port " + st.name;
      want = port_text(st.value);
      got = port_text(seen.port(st.name));
      break;
    case ExpectKind::reg:
    case ExpectKind::ram:
    case ExpectKind::read:
    case ExpectKind::indication:
      break;  // scenario_bus::check
    case ExpectKind::dpv1:
      break;  // scenario_dpv1::check
    case ExpectKind::irq: {
      const bool after = st.when == ScenarioStep::When::after;
      if (st.name == "count") {
        what = "irq count";
        want = std::to_string(st.value);
        got = std::to_string(seen.irq_count);
        if (got != want) got += fmt::format(": {}", rises_text(seen, true));
        break;
      }
      what = "irq " + st.name;
      want = fmt::format("{} {}", after ? "after" : "at", st.when_cycle);
      const std::uint64_t cycle = after ? seen.base_cycle + st.when_cycle : st.when_cycle;
      const bool seen_then =
          std::any_of(seen.irq_rises.begin(), seen.irq_rises.end(), [&](const IrqRise& r) {
            return r.first == cycle && ((r.second >> st.value2) & 1U) != 0;
          });
      got = seen_then ? want : rises_text(seen, after);
      break;
    }
  }
  return {std::move(what), std::move(want), std::move(got)};
}

}  // namespace dpc31::scenario_expect

// The state expects' values (scenario_expect.hpp).
#include "scenario_expect.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "scenario_lex.hpp"
#include "scenario_send.hpp"
#include "vocabulary.hpp"

namespace dpc31::scenario_expect {

using scenario_lex::bytes_text;
using scenario_send::answer_is;
using scenario_send::answer_kind;

bool is_bus(ExpectKind k) {
  return k == ExpectKind::reg || k == ExpectKind::ram || k == ExpectKind::read ||
         k == ExpectKind::indication;
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
  }
  return {std::move(what), std::move(want), std::move(got)};
}

}  // namespace dpc31::scenario_expect

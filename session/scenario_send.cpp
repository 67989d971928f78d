// Scenario files: telegrams as given (scenario_send.hpp).
#include "scenario_send.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "dpc31/dp.hpp"
#include "dpc31/hex.hpp"
#include "scenario_lex.hpp"
#include "textfile.hpp"
#include "vocabulary.hpp"

namespace dpc31::scenario_send {

using scenario_lex::fail;
using scenario_lex::number;

void parse(std::span<const std::string_view> pos, std::span<const Option> opts, ScenarioStep& st) {
  st.kind = StepKind::send;
  if (opts.empty()) {
    if (pos.size() > 1) scenario_lex::spaced_bytes("send", pos[1]);
    if (pos.empty()) fail("expected 'send BYTES' or 'send from=SA fc=N ...'");
    st.bytes = scenario_lex::bytes(pos[0], "telegram", fdl::kMaxFrameLength);
    if (st.bytes.empty()) fail("send: at least one byte");
    return;
  }
  if (!pos.empty()) {
    fail(fmt::format("send with fields takes options only; unexpected '{}'", shown(pos[0])));
  }
  bool fc = false;
  for (const auto& [k, v] : opts) {
    if (k == "fc") {
      st.value = static_cast<std::uint32_t>(number(v, "fc", 0, 255));
      fc = true;
    } else if (k == "to") {
      st.to = static_cast<std::uint8_t>(number(v, "to", 0, 127));
    } else if (k == "dsap" || k == "ssap") {
      (k == "dsap" ? st.dsap : st.ssap) = static_cast<std::uint8_t>(number(v, k, 0, 63));
    } else if (k == "du") {
      st.bytes = scenario_lex::bytes(v, "du");
    } else if (k == "from") {
      st.from = static_cast<std::uint8_t>(number(v, "from", 0, 126));
    } else {
      fail(fmt::format("unknown option '{}' for send", shown(k)));
    }
  }
  if (!st.from || !fc) fail("send with fields needs from=SA and fc=N");
  if (st.dsap.has_value() != st.ssap.has_value()) fail("send: dsap= and ssap= go together");
  st.has_bytes = true;  // fields: `bytes` is the data unit
}

std::vector<std::uint8_t> telegram(const ScenarioStep& st, std::uint8_t slave) {
  if (!st.has_bytes) return st.bytes;
  return fdl::encode(fdl::make_frame(st.to.value_or(slave), *st.from,
                                     static_cast<std::uint8_t>(st.value), st.bytes, st.dsap,
                                     st.ssap));
}

fdl::Frame from_other_master(const ScenarioStep& st, std::uint8_t da, std::uint8_t dsap,
                             std::vector<std::uint8_t> du) {
  const fdl::Function f = da == fdl::kBroadcast ? fdl::Function::SDN_high : fdl::Function::SRD_high;
  return fdl::make_frame(da, *st.from, fdl::make_request_fc(f, false, false), std::move(du), dsap,
                         sap::Master);
}

std::string answer_text(const std::optional<fdl::Frame>& a) {
  if (!a) return "no answer";
  if (a->sd == fdl::SC) return "SC";
  std::string s(response_name(fdl::response_code(a->fc)));
  // Not " " + a temporary: GCC 12 at -O3 warns -Wrestrict there (a false positive).
  if (!a->du.empty()) s += fmt::format(" {}", hex_bytes(a->du, " ", 32));
  return s;
}

std::string answer_kind(const std::optional<fdl::Frame>& a) {
  if (!a) return "none";
  if (a->sd == fdl::SC) return "sc";
  std::string s(response_name(fdl::response_code(a->fc)));
  std::transform(s.begin(), s.end(), s.begin(), [](char c) { return static_cast<char>(c | 0x20); });
  if (!a->du.empty()) s += fmt::format(" with {} data bytes", a->du.size());
  return s;
}

bool answer_is(const std::optional<fdl::Frame>& a, std::string_view kind) {
  if (kind == "none" || !a) return kind == "none" && !a;
  if (kind == "sc" || a->sd == fdl::SC) return kind == "sc" && a->sd == fdl::SC;
  if (kind == "data") return !a->du.empty();
  return answer_kind(a).starts_with(kind) &&
         (answer_kind(a).size() == kind.size() || answer_kind(a)[kind.size()] == ' ');
}

}  // namespace dpc31::scenario_send

// Scenario files: DPV1 (scenario_dpv1.hpp).
#include "scenario_dpv1.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <string>
#include <vector>

#include "dpc31/dp.hpp"
#include "scenario_lex.hpp"
#include "textfile.hpp"

namespace dpc31::scenario_dpv1 {

using scenario_lex::bytes;
using scenario_lex::bytes_text;
using scenario_lex::fail;
using scenario_lex::number;

namespace {

// A record's data (the PDU's 4-byte head + 240 = 244).
constexpr auto kMaxRecord = static_cast<std::size_t>(kRecordLength.max);
// An outcome as a scenario word: its name (docs/dpv1.md) with '_' for ' '.
std::string outcome_word(Dpv1Answer::Outcome o) {
  std::string w = outcome_name(o);
  std::replace(w.begin(), w.end(), ' ', '_');
  return w;
}

// Every outcome's word, and `sc`: positive without a data unit, the Abort's SC.
std::vector<std::string> outcome_words() {
  std::vector<std::string> w;
  for (auto o = std::uint8_t{0}; o <= static_cast<std::uint8_t>(Dpv1Answer::Outcome::aborted); ++o)
    w.push_back(outcome_word(static_cast<Dpv1Answer::Outcome>(o)));
  w.emplace_back("sc");
  return w;
}

[[noreturn]] void unknown(std::string_view k, std::string_view cmd) {
  fail(fmt::format("unknown option '{}' for {}", shown(k), cmd));
}

void no_positional(std::span<const std::string_view> pos, std::string_view cmd) {
  if (!pos.empty()) fail(fmt::format("{} takes options only; unexpected '{}'", cmd, shown(pos[0])));
}

// slot=N (0..254) into st.value, or `second`=N (min..max) into st.value2, each noted in its
// flag; false for any other key.
bool slot_or(std::string_view k, std::string_view v, const ValueRange& second, ScenarioStep& st,
             bool& has_slot, bool& has_second) {
  if (k == "slot") {
    st.value = static_cast<std::uint32_t>(number(v, kRecordSlot));
    has_slot = true;
  } else if (k == second.what) {
    st.value2 = static_cast<std::uint32_t>(number(v, second));
    has_second = true;
  } else {
    return false;
  }
  return true;
}

// slot= index= and one of length= (reads) or data= (writes); all required.
void record_options(std::span<const Option> opts, std::string_view cmd, bool read,
                    ScenarioStep& st) {
  bool slot = false, index = false, third = false;
  for (const auto& [k, v] : opts) {
    if (slot_or(k, v, kRecordIndex, st, slot, index)) continue;
    if (read && k == "length") {
      st.count = number(v, kRecordLength);
      third = true;
    } else if (!read && k == "data") {
      st.bytes = bytes(v, k, kMaxRecord);
      third = true;
    } else {
      unknown(k, cmd);
    }
  }
  if (!slot || !index || !third)
    fail(fmt::format("{} needs slot=N index=N {}", cmd, read ? "length=N" : "data=BYTES"));
}

// A DPV1 action or check on another profile: a parse error, never a run that cannot pass.
void needs_vpc3plus(std::string_view what, const Scenario& s) {
  if (s.chip.profile != Profile::vpc3plus)
    fail(fmt::format("'{}' needs 'profile vpc3plus': {}", what, kDpv1OnVpc3plusOnly));
}

}  // namespace

std::string user_side_only(std::string_view what) {
  return fmt::format(
      "'{}' is the built-in user side's; a firmware answers DPV1 itself (the master's 'dpv1 "
      "c1_timeout=' and 'c2_ssap=' are allowed)",
      what);
}

bool parse_header(std::string_view cmd, std::span<const std::string_view> pos,
                  std::span<const Option> opts, Scenario& s) {
  if (cmd != "record" && cmd != "dpv1") return false;
  no_positional(pos, cmd);
  if (s.chip.profile != Profile::vpc3plus)
    fail(fmt::format("'{}' needs 'profile vpc3plus' before it: {}", cmd, kDpv1OnVpc3plusOnly));
  // `record` and `dpv1 work=` are the built-in user side's; `c1_timeout=` and `c2_ssap=` the
  // master's, which talks to a firmware as well.
  const auto users = [&](std::string_view what) {
    if (!s.firmware.empty() || s.cpu) fail(user_side_only(what));
  };
  if (cmd == "record") {
    users(cmd);
    ScenarioStep st;
    record_options(opts, cmd, false, st);
    for (const Dpv1Record& r : s.user.dpv1.records) {
      if (r.slot == st.value && r.index == st.value2)
        fail(fmt::format("record slot={} index={} given twice", st.value, st.value2));
    }
    s.user.dpv1.records.push_back(
        {static_cast<std::uint8_t>(st.value), static_cast<std::uint8_t>(st.value2), st.bytes});
    return true;
  }
  for (const auto& [k, v] : opts) {
    if (k == "work") {
      users("dpv1 work=");
      s.user.dpv1.work_cycles = number(v, kWorkCycles);
    } else if (k == "c1_timeout") {
      s.dpv1.c1_response_timeout = static_cast<std::uint16_t>(number(v, kC1Timeout));
    } else if (k == "c2_ssap") {
      s.dpv1.c2_ssap = static_cast<std::uint8_t>(number(v, kC2Ssap));
    } else {
      unknown(k, cmd);
    }
  }
  return true;
}

bool parse_action(std::string_view cmd, std::span<const std::string_view> pos,
                  std::span<const Option> opts, const Scenario& s, ScenarioStep& st) {
  if (std::find(kActions.begin(), kActions.end(), cmd) == kActions.end()) return false;
  needs_vpc3plus(cmd, s);
  no_positional(pos, cmd);
  st.kind = StepKind::dpv1;
  st.name = std::string(cmd);
  if (cmd == "dpv1_read" || cmd == "c2_read") {
    record_options(opts, cmd, true, st);
  } else if (cmd == "dpv1_write" || cmd == "c2_write" || cmd == "c2_transport") {
    record_options(opts, cmd, false, st);
  } else if (cmd == "alarm_ack") {
    // Specifier: Seq_Nr bits 7..3, Add_Ack bit 2, the specifier bits 1..0 (pdu::Dpv1DiagBlock).
    bool slot = false, type = false, seq = false;
    std::uint32_t spec = 0;
    st.count = 0;
    for (const auto& [k, v] : opts) {
      if (slot_or(k, v, kAlarmType, st, slot, type)) continue;
      if (k == "seq") {
        st.count |= number(v, k, 0, 31) << 3;
        seq = true;
      } else if (k == "spec") {
        spec = static_cast<std::uint32_t>(number(v, kAlarmSpec));
      } else if (k == "add_ack") {
        if (scenario_lex::flag(v, k)) st.count |= 0x04;
      } else if (k == "sap") {
        st.dsap = static_cast<std::uint8_t>(number(v, kAlarmSap));
      } else {
        unknown(k, cmd);
      }
    }
    if (!slot || !type || !seq) fail("alarm_ack needs slot=N type=N seq=N");
    st.count |= spec;
  } else if (cmd == "c2_initiate") {
    st.initiate = pdu::initiate_request(100);  // Send_Timeout 1 s unless given
    for (const auto& [k, v] : opts) {
      if (k == "send_timeout") {
        st.initiate.send_timeout = static_cast<std::uint16_t>(number(v, kSendTimeout));
      } else if (k == "s_type" || k == "d_type") {
        (k == "s_type" ? st.initiate.s_type : st.initiate.d_type) =
            static_cast<std::uint8_t>(number(v, k, kAddrType.min, kAddrType.max));
      } else if (k == "s_addr" || k == "d_addr") {
        (k == "s_addr" ? st.initiate.s_addr : st.initiate.d_addr) = bytes(v, k, kAddrMax);
      } else {
        unknown(k, cmd);
      }
    }
    if (const std::string why =
            addresses_too_long(st.initiate.s_addr.size(), st.initiate.d_addr.size());
        !why.empty()) {
      fail(why);
    }
  } else if (cmd == "c2_abort") {
    st.value = 0x02;  // instance: the user (0 FDL, 1 MSAC_C2, 2 user)
    for (const auto& [k, v] : opts) {
      if (k == "reason") {
        st.value2 = static_cast<std::uint32_t>(number(v, kAbortReason));
      } else if (k == "instance") {
        st.value = static_cast<std::uint32_t>(number(v, kAbortInstance));
      } else {
        unknown(k, cmd);
      }
    }
  } else if (!opts.empty()) {  // c2_idle
    unknown(opts[0].first, cmd);
  }
  return true;
}

void parse_expect(std::span<const std::string_view> pos, const Scenario& s, ScenarioStep& st) {
  needs_vpc3plus("expect dpv1", s);
  st.expect = ExpectKind::dpv1;
  const std::vector<std::string> words = outcome_words();
  const std::string listed = fmt::format("{}", fmt::join(words, "|"));
  const auto form = [&] {
    fail(fmt::format(
        "expected 'expect dpv1 BYTES', 'expect dpv1 error DECODE,CODE1,CODE2', 'expect dpv1 "
        "polls N' or 'expect dpv1 {}'",
        listed));
  };
  if (pos.size() == 2) {
    if (std::find(words.begin(), words.end(), pos[1]) != words.end()) {
      st.name = std::string(pos[1]);
      return;
    }
    if (pos[1] == "error" || pos[1] == "polls") form();  // without its value
    // A byte list has hex digits, 0x, commas and '-' only: any other word is a misspelt outcome.
    if (pos[1].find_first_not_of("0123456789abcdefABCDEFxX,-") != std::string_view::npos) {
      fail(fmt::format("unknown DPV1 outcome '{}': {}, or the response's hex bytes", shown(pos[1]),
                       listed));
    }
    st.name = "data";
    st.bytes = bytes(pos[1], "dpv1 response", scenario_lex::kMaxDu);
    if (st.bytes.empty()) fail("expect dpv1: a response has at least one byte");
    return;
  }
  if (pos.size() != 3) form();
  if (pos[1] == "error") {
    st.name = "error";
    st.bytes = bytes(pos[2], "dpv1 error", 3);
    if (st.bytes.size() != 3)
      fail("expect dpv1 error: three bytes, Error_Decode,Error_Code_1,Error_Code_2");
  } else if (pos[1] == "polls") {
    st.name = "polls";
    st.value = static_cast<std::uint32_t>(number(pos[2], "polls", 0, 0xFFFF'FFFF));
  } else {
    form();
  }
}

Dpv1Answer act(Dpv1Master& m, const ScenarioStep& st) {
  const auto slot = static_cast<std::uint8_t>(st.value);
  const auto index = static_cast<std::uint8_t>(st.value2);
  const auto length = static_cast<std::uint8_t>(st.count);
  const std::string_view c = st.name;
  if (c == "dpv1_read") return m.read(slot, index, length);
  if (c == "dpv1_write") return m.write(slot, index, st.bytes);
  if (c == "alarm_ack")
    return m.alarm_ack({slot, index, length}, st.dsap.value_or(sap::MSAC_C1_Alarm));
  if (c == "c2_initiate") return m.initiate(st.initiate);
  if (c == "c2_read") return m.c2_read(slot, index, length);
  if (c == "c2_write") return m.c2_write(slot, index, st.bytes);
  if (c == "c2_transport") return m.c2_transport(slot, index, st.bytes);
  if (c == "c2_idle") return m.c2_idle();
  return m.c2_abort(
      {0, static_cast<std::uint8_t>(st.value), static_cast<std::uint8_t>(st.value2), 0});
}

// "expected WHAT WANT, got GOT" as every expect's line: WHAT names the check once (`dpv1
// response`, `dpv1 error`, `dpv1 polls`, `dpv1` for an outcome), WANT the line's value.
Check check(const ScenarioStep& st, const std::optional<Dpv1Answer>& last) {
  const bool outcome = st.name != "data" && st.name != "error" && st.name != "polls";
  Check c{outcome ? std::string("dpv1") : "dpv1 " + (st.name == "data" ? "response" : st.name), "",
          ""};
  c.want = outcome ? st.name : st.name == "polls" ? std::to_string(st.value) : bytes_text(st.bytes);
  if (!last) {
    c.got = "no DPV1 exchange yet";
    return c;
  }
  const std::string got = answer_summary(*last);
  if (st.name == "polls") {
    c.got = std::to_string(last->polls);
  } else if (st.name == "data") {
    // The slave's Abort PDU is data too: `expect dpv1 58,00,12,00` checks its reason.
    const bool data = last->outcome == Dpv1Answer::Outcome::positive ||
                      last->outcome == Dpv1Answer::Outcome::aborted;
    c.got = data ? bytes_text(last->du) : got;
  } else if (st.name == "error") {
    c.got = last->error ? fmt::format("{:02X} {:02X} {:02X}", last->error->error_decode,
                                      last->error->error_code_1, last->error->error_code_2)
                        : got;
  } else if (st.name == "sc") {
    c.got = last->outcome == Dpv1Answer::Outcome::positive && last->du.empty() ? "sc" : got;
  } else {
    c.got = outcome_word(last->outcome) == st.name ? st.name : got;  // "no answer": no_answer
  }
  return c;
}

}  // namespace dpc31::scenario_dpv1

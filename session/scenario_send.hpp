// Scenario files: telegrams as given — `send` (raw bytes, or fields from any station) and the
// `from=` another master puts on set_prm / chk_cfg / gc (docs/scenario-format.md, "Telegrams as
// given"). Internal to the scenario parser and runner.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "dpc31/fdl.hpp"
#include "scenario.hpp"

namespace dpc31::scenario_send {

using Option = std::pair<std::string_view, std::string_view>;

// `send BYTES` | `send from=SA fc=N [to=DA] [dsap=N ssap=N] [du=BYTES]` into `st` (throws
// scenario_lex::ParseFail).
void parse(std::span<const std::string_view> pos, std::span<const Option> opts, ScenarioStep& st);

// The bytes a `send` step puts on the line; `slave` is the default destination.
std::vector<std::uint8_t> telegram(const ScenarioStep& st, std::uint8_t slave);

// A request of the master st.from: SRD to `da` (SDN when `da` is the broadcast address) with
// FCV = 0 (a master that keeps no frame count with this slave: the FCB is not evaluated), the
// service's DSAP and SSAP 62 (docs/decisions.md).
fdl::Frame from_other_master(const ScenarioStep& st, std::uint8_t da, std::uint8_t dsap,
                             std::vector<std::uint8_t> du);

// The last answer as the walk shows it ("SC", "DL 01 02", "no answer").
std::string answer_text(const std::optional<fdl::Frame>& a);
// Its kind as `expect answer` names it, lower case ("none", "sc", "dl with 4 data bytes").
std::string answer_kind(const std::optional<fdl::Frame>& a);
// Whether it is of `kind` (none, sc, data, ok, ue, rr, rs, dl, nr, dh).
bool answer_is(const std::optional<fdl::Frame>& a, std::string_view kind);

}  // namespace dpc31::scenario_send

// Scenario files: DPV1 (docs/scenario-format.md, "DPV1") — the header lines `record` and `dpv1`
// (the built-in user side's records, the master's rules), the actions `dpv1_read`, `dpv1_write`,
// `alarm_ack` (MSAC_C1) and `c2_initiate`, `c2_read`, `c2_write`, `c2_transport`, `c2_idle`,
// `c2_abort` (MSAC_C2), and `expect dpv1 ...`: how they parse and what they do. Internal to the
// scenario parser and runner.
#pragma once

#include <array>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>

#include "dpv1_master.hpp"
#include "scenario.hpp"
#include "scenario_bus.hpp"

namespace dpc31::scenario_dpv1 {

using Option = std::pair<std::string_view, std::string_view>;

// The DPV1 actions (parse_action).
inline constexpr std::array<std::string_view, 9> kActions = {
    "dpv1_read", "dpv1_write", "alarm_ack",    "c2_initiate", "c2_read",
    "c2_write",  "c2_idle",    "c2_transport", "c2_abort"};

// `record slot=N index=N data=BYTES`, `dpv1 work=N c1_timeout=N c2_ssap=N` into `s`; false if
// `cmd` is neither (throws scenario_lex::ParseFail).
bool parse_header(std::string_view cmd, std::span<const std::string_view> pos,
                  std::span<const Option> opts, Scenario& s);
// The refusal of `what` (`record`, `dpv1 work=`) in a scenario with a firmware or a CPU.
std::string user_side_only(std::string_view what);
// The DPV1 actions into `st`; false if `cmd` is none of them.
bool parse_action(std::string_view cmd, std::span<const std::string_view> pos,
                  std::span<const Option> opts, const Scenario& s, ScenarioStep& st);
// `expect dpv1 BYTES|error D,C1,C2|polls N|refused|timeout|no_answer|no_connection|sc` (pos[0] ==
// "dpv1"): only after `profile vpc3plus`, as the DPV1 actions.
void parse_expect(std::span<const std::string_view> pos, const Scenario& s, ScenarioStep& st);

// Performs the step on the master.
Dpv1Answer act(Dpv1Master& m, const ScenarioStep& st);

// What `expect dpv1` compares (the runner's one check record).
using Check = scenario_bus::Check;
Check check(const ScenarioStep& st, const std::optional<Dpv1Answer>& last);

}  // namespace dpc31::scenario_dpv1

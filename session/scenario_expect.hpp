// Scenario files: what the state expects compare (`expect dp_state`, `outputs`, `counter`,
// `irr_bit`, `answer`, `port`, ...; docs/scenario-format.md, "Expects"): the expected and the
// observed value as the walk prints them. The bus expects (`reg`, `ram`, `read`, `indication`)
// are scenario_bus.hpp's. Internal to the scenario runner (scenario_run.cpp).
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "dpc31/chip.hpp"
#include "dpc31/fdl.hpp"
#include "dpc31/fdl_counters.hpp"
#include "responder.hpp"
#include "scenario.hpp"
#include "scenario_bus.hpp"

namespace dpc31::scenario_expect {

// An X/INT activation: its cycle and Int_Reg at that cycle (the interrupt's causes).
using IrqRise = std::pair<std::uint64_t, std::uint16_t>;
// The X/INT activations of an action a failed `expect irq` lists (the rest counted).
inline constexpr std::size_t kIrqRisesShown = 16;

// What the run has seen when an expect is checked.
struct Seen {
  const Chip& chip;
  const std::vector<Responder::Output>& outputs;                // the user side's fetched outputs
  const std::optional<std::vector<std::uint8_t>>& last_inputs;  // of the last Data_Exchange
  const std::optional<std::vector<std::uint8_t>>& last_diag;    // of the last Slave_Diag
  const FdlCounters& base_counters;                             // at the last action's start
  std::uint16_t irr;  // Int_Req_Reg now, with what the ISR saw during the last action
  std::optional<fdl::Frame> last_answer;  // the master's last answer
  std::uint32_t baud;                     // the chip's baud rate (0: searching)
  bool pb3;                               // PB3 high now or risen during the last action
  std::function<std::uint32_t(const std::string&)> port;  // a firmware port's value
  // X/INT activations in the last action: the first kIrqRisesShown and any an expect names, of
  // irq_count in all.
  std::span<const IrqRise> irq_rises;
  std::size_t irq_count = 0;
  std::uint64_t base_cycle = 0;  // when the last action began
};

// The bit of interrupt `name`: a one-bit Int_Req_Reg field of `profile` (throws
// scenario_lex::ParseFail naming a few).
std::uint32_t irq_bit(Profile profile, std::string_view name);
// `expect irq NAME` (with `at` / `after`, which the caller has taken into `st.when`) and
// `expect irq count N` (pos[0] == "irq").
void parse_irq(std::span<const std::string_view> pos, Profile profile, ScenarioStep& st);

// `expect reg|ram|read|indication`: scenario_bus::check.
bool is_bus(ExpectKind k);
// Any other expect: what it checks, the expected and the observed value.
scenario_bus::Check check(const ScenarioStep& st, const Seen& seen);
// A port value as the walk shows it: "0x5 (0101)" up to 0xF, else "0x1F".
std::string port_text(std::uint32_t v);

}  // namespace dpc31::scenario_expect

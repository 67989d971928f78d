// Scenario files: the exact-cycle checks, and the CPU's bus door — `write`, `read`, `expect reg`,
// `expect ram`, `expect read` (docs/scenario-format.md, "Bus accesses"): how they parse and what
// they do on the chip. Internal to the scenario parser and runner.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "dpc31/chip.hpp"
#include "scenario.hpp"

namespace dpc31::scenario_bus {

using Option = std::pair<std::string_view, std::string_view>;

// The shape of the last `read` before a line, so `expect read` knows what it compares.
struct ReadShape {
  bool seen = false;
  bool block = false;  // count=N: a byte list; else one value
  unsigned width = 8;  // bits of that value
};

// `write` / `read` into `st` (throws scenario_lex::ParseFail); false if `cmd` is neither.
bool parse_action(std::string_view cmd, std::span<const std::string_view> pos,
                  std::span<const Option> opts, Profile profile, ScenarioStep& st,
                  ReadShape& last_read);
// `request NAME [PARAM]` (DPC31) into `st`.
bool parse_request(std::span<const std::string_view> pos, Profile profile, ScenarioStep& st);
// `expect reg|ram|read|indication ...` (pos[0] is what) into `st`; false if `pos[0]` is none of
// them.
bool parse_expect(std::span<const std::string_view> pos, Profile profile,
                  const ReadShape& last_read, ScenarioStep& st);

// What the last `read` returned.
struct LastRead {
  bool seen = false;
  bool block = false;
  unsigned width = 8;
  std::uint32_t value = 0;
  std::vector<std::uint8_t> bytes;
};

// Performs a `write` / `read` step through the chip's front door (Chip::write / read, each access
// bus_access_cycles() clocks); returns the walk's text for it.
std::string act(Chip& chip, const ScenarioStep& st, LastRead& last);

struct Check {
  std::string what, want, got;
};
Check check(const Chip& chip, const ScenarioStep& st, const LastRead& last);

// `expect dp_state|wd_state ... at CYCLE|after N` (docs/scenario-format.md, "Exact cycles"): the
// state, entered at `since` as the walk shows it, against `st`; the last action began at `base`.
// Appends the cycle parts to `want` and `got`.
void when(const ScenarioStep& st, std::uint64_t since, std::uint64_t base, std::string& want,
          std::string& got);

}  // namespace dpc31::scenario_bus

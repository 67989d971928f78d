// Scenario files: the lexical pieces every command's parser shares (numbers, byte lists, flags)
// and the parse failure they throw. Internal to the scenario parser (scenario_parse.cpp,
// scenario_actions.cpp); the format is docs/scenario-format.md.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "dpc31/fdl.hpp"
#include "vocabulary.hpp"

namespace dpc31::scenario_lex {

// Simulated time one `silence` may take: bounds the run time of a typo like `silence 10000s`.
inline constexpr std::uint64_t kMaxSeconds = 3600;

// At most this many data bytes in one telegram's data unit (DP).
inline constexpr std::size_t kMaxDu = fdl::kMaxDpData;

struct ParseFail {
  int line = 0;  // 0: the line being parsed
  std::string message;
};

[[noreturn]] void fail(std::string msg);

// Decimal or 0x hex, the whole of `s`.
bool parse_u64(std::string_view s, std::uint64_t& v);
std::vector<std::string_view> split(std::string_view s, char sep);
// A number in min..max, or ParseFail naming `what`.
std::uint64_t number(std::string_view s, std::string_view what, std::uint64_t min,
                     std::uint64_t max);
// The same for a value the Python module takes too (vocabulary.hpp).
inline std::uint64_t number(std::string_view s, const ValueRange& r) {
  return number(s, r.what, r.min, r.max);
}
bool flag(std::string_view s, std::string_view what);
// `text` without the UTF-8 BOM an editor may put before it.
std::string_view without_bom(std::string_view text);
// A baud rate: one of the 10 PROFIBUS rates, the only ones the chips' baud search finds.
std::uint32_t profibus_baud(std::string_view s);
// Hex bytes "13,23" ("0x13" also accepted); "-" is the empty list.
std::vector<std::uint8_t> bytes(std::string_view s, std::string_view what,
                                std::size_t max = kMaxDu);
// A `send` whose bytes came as words (the walk prints a telegram with spaces): refused, naming
// the commas and the second word.
[[noreturn]] void spaced_bytes(std::string_view command, std::string_view second);

// Cycles (a plain number, decimal or 0x hex), or a decimal number with a unit: us, ms, s, or bits
// (of `bit_cycles` clocks); rounded up to whole cycles like every minimum time (docs/timing.md).
std::uint64_t duration(std::string_view s, std::uint64_t clock_hz, std::uint64_t bit_cycles);

// A Global_Control command: names (sync, unsync, freeze, unfreeze, clear, operate) joined by
// commas, or a number 0..255.
std::uint32_t gc_command(std::string_view s);

// A path a scenario file names (a plug-in, an Intel HEX image): a relative one is relative to the
// directory of `scenario_file`'s real file (links resolved), as an #include's is to its file's,
// not to the directory of a link that leads to it.
std::string beside_file(const std::string& scenario_file, const std::string& path);

// Bytes as the walk and the checks show them: "01 02 A3", or "-" for none.
std::string bytes_text(std::span<const std::uint8_t> b);

// Index of `name` in a NULL-terminated list of names, -1 if absent; the list as "a, b, c"
// ("none" when empty).
int name_index(const char* const* names, std::string_view name);
std::string name_list(const char* const* names);

}  // namespace dpc31::scenario_lex

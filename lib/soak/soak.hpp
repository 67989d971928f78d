// `dpc31 soak` (docs/soak.md): a long run of Data_Exchange between the built-in DP master and one
// chip with the built-in user side, with faults injected periodically (noise on the line, a
// damaged request, a pulled cable that lets the DP watchdog expire, a master restart). At the
// end every error counter of the chip and of the master must equal exactly what was injected.
#pragma once

#include <CLI/CLI.hpp>
#include <array>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "chip_choice.hpp"

namespace dpc31::soak {

// The kinds of injected fault, in the order of the report.
enum class Fault : std::uint8_t {
  noise,       // random bytes after TSYN idle, the first no start delimiter: bad_sd
  noise_sync,  // a token to another station, then random bytes without TSYN: no_sync
  glitch,      // a low pulse shorter than half a bit after TSYN idle: start_bit
  parity,      // one character of a Data_Exchange request with its parity inverted: parity
  stop,        // one character of a Data_Exchange request with a 0 stop bit: stop_bit
  cable,       // the bus silent for longer than TWD: the DP watchdog expires
  restart,     // the master starts over (shorter silence than TWD) with Set_Prm and Chk_Cfg
};
inline constexpr std::size_t kFaultKinds = 7;
[[nodiscard]] const char* fault_name(Fault f);

struct Options {
  std::uint64_t cycles = 1'000'000'000;  // run at least this many chip cycles
  std::string profile = "dpc31";
  cli::ChipChoice chip;  // --variant, --irq-controller
  std::uint32_t baud = 1'500'000;
  std::uint64_t fault_period = 2'000'000;  // cycles of undisturbed exchange between two faults
  std::uint64_t seed = 1;
  // Not given and given empty differ: an empty name is refused (as a file or a firmware name
  // no one can have meant), not taken as "none".
  std::optional<std::string> json;  // write the result here (none: no file)
  // A firmware (built-in name or plug-in path) instead of the built-in responder: the master is
  // configured from its GSD defaults, and only the chip's and the master's counters are checked
  // (its own bookkeeping and its data are the firmware's). None: the responder.
  std::optional<std::string> firmware;
  // For the check's own test: one fault of this kind is injected without being accounted for,
  // so the counters must not match (empty: none).
  std::string unaccounted;
};

struct Row {
  std::string name;  // "chip.parity", "master.no_answer", ...
  std::uint64_t expected = 0;
  std::uint64_t actual = 0;
  [[nodiscard]] bool ok() const { return expected == actual; }
};

struct Result {
  std::uint64_t first_cycle = 0;  // after the first start-up: the counters' baseline
  std::uint64_t cycles = 0;       // the chip's cycle counter at the end
  std::uint32_t clock_hz = 0;
  std::uint32_t twd_ms = 0;         // the DP watchdog time the master parameterised
  double wall_s = 0;                // the whole run, the start-up included
  std::uint64_t rss_start_kib = 0;  // VmRSS after the first start-up
  std::uint64_t rss_end_kib = 0;
  std::uint64_t exchanges = 0;  // Data_Exchange requests answered with data
  std::array<std::uint64_t, kFaultKinds> injected{};
  std::vector<Row> rows;
  // The chip's warnings and errors (log_line), the first kKeptLog of them, and how many more:
  // printed on stderr after the report, so that a run that ends in its one line of exit 2 (a
  // firmware that hangs) has nothing else there (docs/bad-input.md).
  std::vector<std::string> log;
  std::uint64_t log_left_out = 0;
  [[nodiscard]] bool ok() const;
};
inline constexpr std::size_t kKeptLog = 100;

// Runs the soak; throws std::runtime_error if the first start-up fails.
Result run(const Options& o);

// VmRSS of this process from /proc/self/status in KiB (0 if it cannot be read).
std::uint64_t resident_kib();

// Adds the subcommand with its options to `app`.
CLI::App* add_subcommand(CLI::App& app, Options& o);
// Runs it: the report to `out`, exit code 0 (every counter as expected), 1 (a mismatch) or 2.
int run_cli(const Options& o, std::FILE* out, std::FILE* err);

}  // namespace dpc31::soak

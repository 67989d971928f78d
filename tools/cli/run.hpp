#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "scenario.hpp"
#include "scenario_segment.hpp"
#include "waveform.hpp"

namespace dpc31::cli {

struct RunOptions {
  std::string scenario;  // path of the .scn file ("" for the demo's own session)
  bool quiet = false;    // no state walk; failures are still reported
  std::string json;      // write a JSON summary here ("" = none)
  std::string record;    // write a golden trace of the run here ("" = none, docs/trace-format.md)
  std::string vcd;       // waveform of the run (docs/waveforms.md)
  std::string fst;
  std::string la_vcd;  // the logic-analyser form as a second VCD ("" = none): 1-bit, one scope
  std::vector<std::string> signals;   // waveform signal globs ("" = all)
  std::optional<std::uint64_t> from;  // waveform window, cycles (none: from 0)
  std::optional<std::uint64_t> to;    // (none: to the end)
  std::optional<std::string>
      timescale;                  // none: 1ps, 10ns for the logic-analyser form (docs/waveforms.md)
  bool flat = false;              // --vcd / --fst in the logic-analyser form
  std::string gtkw;               // a GTKWave save file for --vcd (or else --fst)
  std::string pvs;                // a PulseView session for --la-vcd (or else --vcd --flat)
  std::string pcap;               // the chip's telegrams as pcapng (docs/capture.md)
  Engine engine = Engine::event;  // how time advances (docs/engine.md)
};

// A waveform time unit, "1ps", "10ns", "100us", ... up to "1s", as an exponent of 10 (-12, -8,
// ...).
bool parse_timescale(const std::string& t, int& exp);
// The units a waveform of `run` and `demo` takes: parse_timescale() reads 1, 10 or 100 of fs ...
// ms and 1s, and the recorder refuses a unit longer than a clock cycle (docs/waveforms.md), at
// the 48 MHz every scenario and the demo run at. The help and the error name these, no others.
inline constexpr std::string_view kTimescaleUnits = "1, 10 or 100 fs or ps, or 1 or 10 ns";
// The one line for a unit parse_timescale() refuses (without the command's name).
std::string timescale_error(const std::string& t);
// The waveform options' checks, one chip's and a segment's: each needs a waveform to act on (no
// silent options), then the unit, the window, the save file. "" or the line (without the
// command's name).
std::string waveform_options_error(const RunOptions& opt);

// The waveforms `opt` asks for (--vcd, --fst, --la-vcd), each with its window, signals, form,
// time unit, the GTKWave save file on the first of --vcd / --fst and the PulseView session on
// --la-vcd (or else a flat --vcd), whose UART decoder reads the bus at `baud`; the same for one
// chip and for a segment. The time unit is checked before (parse_timescale).
std::vector<wave::Options> wave_options(const RunOptions& opt, std::uint32_t baud);

// `dpc31 run`: plays a scenario file (docs/scenario-format.md), printing the state walk to `out`
// and failures to `err`. Returns the exit code: 0 every expect held, 1 one failed, 2 bad input.
// With `record`, the run is also written as a trace (for exit codes 0 and 1).
int run_scenario_command(const RunOptions& opt, std::FILE* out, std::FILE* err);

// A parsed scenario of one chip with the outputs `opt` asks for (waveforms, capture, trace, JSON;
// opt.scenario only names it). open() checks the options, opens every file and matches the
// waveforms' signals: bad input is found before anything is printed (`dpc31 demo` opens before
// its register session). run() plays the scenario with them watching and writes them once it
// completes. A failure is one line on `err`, "COMMAND: what" ("dpc31 run", "dpc31 demo").
class ChipRun {
 public:
  ChipRun(const RunOptions& opt, std::string command, std::FILE* err);
  ~ChipRun();  // what was opened and not written is removed
  ChipRun(const ChipRun&) = delete;
  ChipRun& operator=(const ChipRun&) = delete;

  // 0, or 2 with its line written. `baud`: the scenario's, for a PulseView session (--pvs).
  int open(std::uint32_t baud);
  // After open(): 0, 1 or 2 like the command. `text` is the scenario's (its leading comments head
  // the --record trace).
  int run(const Scenario& s, std::string_view text, const LineSink& walk, const LineSink& errors,
          ScenarioOutcome& o);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The comment block at the top of a scenario's text: it heads the recorded traces.
std::vector<std::string> leading_comments(std::string_view text);

// A segment's scenario, parsed from `text`, with the outputs `opt` asks for (run_segment.cpp,
// docs/segment.md "Outputs"). Returns 0, 1 or 2 like the command.
int run_segment_command(const RunOptions& opt, const SegmentScenario& s, std::string_view text,
                        const LineSink& walk, const LineSink& errors, std::FILE* err);
// The trace of a station of a segment whose scope is `scope` (station_scope,
// lib/segment_outputs): FILE.trace -> FILE.station5_spc3.trace.
std::string station_trace_path(const std::string& record, const std::string& scope);

}  // namespace dpc31::cli

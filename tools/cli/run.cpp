#include "run.hpp"

#include <fmt/core.h>

#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

#include "board.hpp"
#include "firmware_host.hpp"
#include "outfile.hpp"
#include "pcapng.hpp"
#include "waveform.hpp"

// The scenario runner lives with the emulator (emu/ is not on this target's include path).
#include "scenario.hpp"
#include "trace.hpp"
#include "vocabulary.hpp"

namespace dpc31::cli {

namespace {

nlohmann::json summary(const Scenario& s, const ScenarioOutcome& o) {
  nlohmann::json counters = nlohmann::json::object();
  for (const CounterField& f : fdl_counter_fields()) {
    counters[std::string(f.name)] = o.counters.*(f.member);
  }
  return {
      {"scenario", s.file},
      {"profile", std::string(profile_name(s.chip.profile))},
      {"bus", s.chip.bus == BusMode::intel ? "intel" : "motorola"},
      {"baud", s.master.baud},
      {"final_cycle", o.final_cycle},
      {"dp_state", std::string(dp_state_name(o.dp))},
      {"wd_state", std::string(wd_state_name(o.wd))},
      {"counters", counters},
      {"expects", {{"passed", o.passed}, {"failed", o.failed}}},
      {"failures", o.failures},
      {"ok", o.ok()},
  };
}

// The run of the parsed `s` with everything asked for watching it: a trace recorder (--record), a
// waveform (--vcd / --fst) and a telegram capture (--pcap). Nothing is written unless the run
// completes.
int run_with_outputs(const RunOptions& opt, std::string_view text, const LineSink& walk,
                     const LineSink& errors, Scenario& s, std::FILE* err) {
  const std::vector<outfile::Named> outputs = {
      {"--json", opt.json},     {"--record", opt.record}, {"--vcd", opt.vcd},   {"--fst", opt.fst},
      {"--la-vcd", opt.la_vcd}, {"--pcap", opt.pcap},     {"--gtkw", opt.gtkw}, {"--pvs", opt.pvs}};
  std::vector<outfile::Named> inputs = scenario_inputs(s);
  inputs.insert(inputs.begin(), {"the scenario", opt.scenario});
  if (const std::string same = outfile::distinct(inputs, outputs); !same.empty()) {
    fmt::print(err, "dpc31 run: {}\n", same);
    return 2;
  }
  s.chip.engine = opt.engine;
  ChipRun run(opt, "dpc31 run", err);
  if (const int rc = run.open(s.master.baud); rc != 0) return rc;
  ScenarioOutcome o;
  return run.run(s, text, walk, errors, o);
}

}  // namespace

// Its description, and for golden traces what was checked by hand.
std::vector<std::string> leading_comments(std::string_view text) {
  std::vector<std::string> out;
  std::istringstream f{std::string(text)};
  std::string line;
  bool first = true;
  while (std::getline(f, line)) {
    if (first && line.starts_with("\xEF\xBB\xBF")) line.erase(0, 3);
    first = false;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (!line.starts_with('#')) break;
    line.erase(0, line.starts_with("# ") ? 2 : 1);
    out.push_back(line);
  }
  return out;
}

bool parse_timescale(const std::string& t, int& exp) {
  static const std::pair<const char*, int> kUnits[] = {{"fs", -15}, {"ps", -12}, {"ns", -9},
                                                       {"us", -6},  {"ms", -3},  {"s", 0}};
  for (const auto& [unit, e] : kUnits) {
    for (const auto& [mult, add] : {std::pair{"100", 2}, std::pair{"10", 1}, std::pair{"1", 0}}) {
      if (t == std::string(mult) + unit && e + add <= 0) {
        exp = e + add;
        return true;
      }
    }
  }
  return false;
}

std::string timescale_error(const std::string& t) {
  return fmt::format("--timescale '{}': use {}", t, kTimescaleUnits);
}

std::string waveform_options_error(const RunOptions& opt) {
  // --la-vcd takes the window, the signals and the unit too; it is always the flat form.
  if (opt.vcd.empty() && opt.fst.empty()) {
    const auto needs = [](const std::string& option, std::string_view waveforms) {
      return fmt::format("{}: a waveform option needs {}", option, waveforms);
    };
    if (opt.flat) return needs("--flat", "--vcd or --fst");
    if (!opt.gtkw.empty())
      return fmt::format("--gtkw {}: a save file needs --vcd or --fst", opt.gtkw);
    if (opt.la_vcd.empty()) {
      constexpr std::string_view kAny = "--vcd, --fst or --la-vcd";
      if (!opt.signals.empty()) {
        std::string globs;
        for (const std::string& g : opt.signals) globs += (globs.empty() ? "" : ",") + g;
        return needs("--signals " + globs, kAny);
      }
      if (opt.from) return needs(fmt::format("--from {}", *opt.from), kAny);
      if (opt.to) return needs(fmt::format("--to {}", *opt.to), kAny);
      if (opt.timescale) {
        return needs(fmt::format("--timescale {}", opt.timescale->empty() ? "''" : *opt.timescale),
                     kAny);
      }
    }
  }
  // PulseView reads VCD only (libsigrok's input), and our logic-analyser form of it.
  if (!opt.pvs.empty() && opt.la_vcd.empty() && (opt.vcd.empty() || !opt.flat))
    return fmt::format("--pvs {}: a PulseView session needs --la-vcd (or --vcd with --flat)",
                       opt.pvs);
  int unit_exp = 0;
  if (opt.timescale && !parse_timescale(*opt.timescale, unit_exp))
    return timescale_error(*opt.timescale);
  if (opt.to.value_or(UINT64_MAX) <= opt.from.value_or(0)) {
    return fmt::format("--to {} is not after --from {}: an empty waveform window",
                       opt.to.value_or(UINT64_MAX), opt.from.value_or(0));
  }
  return {};
}

std::vector<wave::Options> wave_options(const RunOptions& opt, std::uint32_t baud) {
  std::vector<wave::Options> out;
  for (const auto& [path, fst, flat] :
       {std::tuple{opt.vcd, false, opt.flat}, std::tuple{opt.fst, true, opt.flat},
        std::tuple{opt.la_vcd, false, true}}) {
    if (path.empty()) continue;
    wave::Options w;
    w.path = path;
    w.fst = fst;
    w.signals = opt.signals;
    w.from = opt.from.value_or(0);
    w.to = opt.to.value_or(UINT64_MAX);
    w.flat = flat;
    // The save file opens --vcd, or --fst without it.
    if (path == (opt.vcd.empty() ? opt.fst : opt.vcd)) w.gtkw = opt.gtkw;
    // The PulseView session: --la-vcd, or a flat --vcd without it.
    if (path == (opt.la_vcd.empty() ? opt.vcd : opt.la_vcd) && !fst) {
      w.pvs = opt.pvs;
      w.baud = baud;
    }
    // The logic-analyser form's default: 10 ns, the sample period of a 100 MHz analyser (sigrok
    // makes one sample per unit; 8.3 per bit at 12 Mbaud). The full form's: 1 ps.
    parse_timescale(opt.timescale.value_or(flat ? "10ns" : "1ps"), w.timescale_exp);
    out.push_back(w);
  }
  return out;
}

struct ChipRun::Impl {
  RunOptions opt;
  std::string command;
  std::FILE* err = nullptr;
  outfile::OutFile rec_out;
  outfile::OutFile json_out;
  std::vector<std::unique_ptr<wave::Recorder>> waves;
  capture::PcapngWriter pcap;

  int fail(const std::string& line) const {
    fmt::print(err, "{}: {}\n", command, line);
    return 2;
  }
};

ChipRun::ChipRun(const RunOptions& opt, std::string command, std::FILE* err)
    : impl_(std::make_unique<Impl>()) {
  impl_->opt = opt;
  impl_->command = std::move(command);
  impl_->err = err;
}

ChipRun::~ChipRun() = default;

int ChipRun::open(std::uint32_t baud) {
  Impl& m = *impl_;
  const RunOptions& opt = m.opt;
  // Every output is opened now: a bad path is found before the run, before any is written.
  for (auto [path, out] : {std::pair{&opt.record, &m.rec_out}, std::pair{&opt.json, &m.json_out}}) {
    if (!path->empty() && !out->open(*path)) return m.fail(out->error());
  }
  // The trace is written as the run goes: a device or a descriptor gets it from a scratch file
  // in TMPDIR, as large as the trace, at the end, after the walk.
  if (!opt.record.empty() && !m.rec_out.spool()) return m.fail(m.rec_out.error());
  if (const std::string e = waveform_options_error(opt); !e.empty()) return m.fail(e);
  std::string error;
  for (const wave::Options& w : wave_options(opt, baud)) {
    auto& rec = m.waves.emplace_back(std::make_unique<wave::Recorder>(w));
    if (!(rec->check_signals(error) && rec->open(error))) return m.fail(error);
  }
  if (!opt.pcap.empty() && !m.pcap.open(opt.pcap)) return m.fail(m.pcap.error());
  return 0;
}

int ChipRun::run(const Scenario& s, std::string_view text, const LineSink& walk,
                 const LineSink& errors, ScenarioOutcome& o) {
  Impl& m = *impl_;
  const RunOptions& opt = m.opt;
  std::unique_ptr<TraceRecorder> rec;
  ScenarioHooks hooks;
  if (!opt.record.empty()) {
    std::vector<std::string> notes = leading_comments(text);
    if (!notes.empty()) notes.emplace_back();
    notes.push_back(
        fmt::format("recorded by `dpc31 run --record` from {} (docs/trace-format.md)", s.file));
    rec = std::make_unique<TraceRecorder>(s.master.baud, std::move(notes));
    // Written as it goes (spooled since open()): a long run holds no trace in memory. Its bytes
    // are on disk: a regular FILE's temporary, else a scratch file in TMPDIR as large as the trace.
    rec->write_to([&out = m.rec_out](std::string_view bytes) { out.write(bytes); });
    hooks = rec->scenario_hooks();
  }
  std::string attach_error;
  std::uint64_t end_cycle = 0;
  hooks.at_start = [&, inner = hooks.at_start](Chip& chip) {
    if (inner) inner(chip);
    for (auto& w : m.waves) {
      if (attach_error.empty()) w->attach(chip, attach_error);
    }
    if (m.pcap.is_open()) m.pcap.attach(chip);
  };
  hooks.at_end = [&, inner = hooks.at_end](Chip& chip) {
    if (inner) inner(chip);
    end_cycle = chip.cycle();
  };
  // The plug-in a scenario names is loaded now, after every other check (docs/security.md).
  Scenario bound = s;
  ScenarioError berr;
  if (!bind_plugin(bound, berr)) {
    errors(berr.text());
    return 2;
  }
  // The 80C32 image too: a bad one is exit 2 with nothing printed or written (docs/cpu.md).
  if (std::string why; !check_cpu_image(bound, why)) {
    errors(why);
    return 2;
  }
  // A firmware's fault or hang is at the scenario's `firmware` line while its init runs, then at
  // the step it runs in; the demo's own session has no file.
  FirmwarePlace where;
  if (!opt.scenario.empty()) {
    where = FirmwarePlace(s.file, s.firmware_line);
    hooks.at_step = [&where](const ScenarioStep& st) { where.enter(st.line, st.text); };
  }
  try {
    // A firmware stuck in a loop without a bus access cannot be stopped from this thread: the
    // guard ends the process with one line.
    if (bound.firmware_desc != nullptr) board::guard_hangs(m.command, bound.firmware_desc->name);
    const board::HangPlace place(where.text());
    o = run_scenario(bound, walk, errors, hooks);
  } catch (const FirmwareError& e) {
    return m.fail(where.message(e.what()));
  }
  if (!attach_error.empty()) return m.fail(attach_error);
  const int rc = o.ok() ? 0 : 1;
  if (rec && !rec->error().empty())
    return m.fail(fmt::format("cannot record {}: {}", opt.scenario, rec->error()));
  if (rec && !m.rec_out.commit()) return m.fail(m.rec_out.error());
  std::string error;
  for (auto& w : m.waves) {
    if (!w->finish(end_cycle, error)) return m.fail(error);
  }
  if (m.pcap.is_open() && !m.pcap.close()) return m.fail(m.pcap.error());
  if (m.json_out.is_open() &&
      !(m.json_out.write(summary(s, o).dump(2) + '\n') && m.json_out.commit()))
    return m.fail(m.json_out.error());
  return rc;
}

int run_scenario_command(const RunOptions& opt, std::FILE* out, std::FILE* err) {
  LineSink walk;
  if (!opt.quiet) walk = [out](const std::string& line) { fmt::print(out, "{}\n", line); };
  const LineSink errors = [err](const std::string& line) { fmt::print(err, "{}\n", line); };
  // Read once: a pipe or a FIFO gives its text only once, and the text heads a --record trace. A
  // segment's scenario (docs/segment.md) has a runner of its own (run_segment.cpp).
  std::string text;
  std::string untrusted;
  SegmentScenario seg;
  Scenario s;
  ScenarioError serr;
  if (!read_scenario_file(opt.scenario, text, untrusted, serr)) {
    errors(serr.text());
    return 2;
  }
  switch (parse_segment_file(text, opt.scenario, untrusted, seg, s, serr)) {
    case SegmentLoad::error:
      errors(serr.text());
      return 2;
    case SegmentLoad::ok:
      return run_segment_command(opt, seg, text, walk, errors, err);
    case SegmentLoad::not_segment:
      break;
  }
  return run_with_outputs(opt, text, walk, errors, s, err);
}

}  // namespace dpc31::cli

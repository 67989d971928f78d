// dpc31 cosim: the C++ blocks against the Verilated RTL, cycle by cycle, over seeded random
// stimulus (or a replayed trace). Exit 0 no divergence, 1 divergence, 2 bad input.
#include "cosim.hpp"

#include <fmt/core.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <tuple>

#include "chip_choice.hpp"
#include "cosim_summary.hpp"
#include "cosim_trace.hpp"
#include "lockstep.hpp"
#include "outfile.hpp"
#include "rtl_library.hpp"
#include "scenario.hpp"
#include "session.hpp"
#include "textfile.hpp"
#include "whole_number.hpp"

namespace dpc31::cli {

namespace {

// The variant the run's chip has: the VPC3+'s is its ASIC type, VPC3+C where none was given
// (docs/golden-model.md); the other profiles have none.
std::optional<Vpc3Variant> variant_run(const cosim::DutOptions& d) {
  if (d.profile != Profile::vpc3plus) return std::nullopt;
  return static_cast<Vpc3Variant>(d.asic_type());
}

// Its name (b, c, s; "" for none), as --variant and a trace's `# variant` give it.
std::string variant_run_name(const cosim::DutOptions& d) {
  const std::optional<Vpc3Variant> v = variant_run(d);
  return v ? std::string(vpc3_variant_name(*v)) : "";
}

// The summary's `variant`: the ASIC type as a number (12 for C), null for none.
nlohmann::json variant_json(const cosim::DutOptions& d) {
  const std::optional<Vpc3Variant> v = variant_run(d);
  return v ? nlohmann::json(static_cast<int>(*v)) : nlohmann::json();
}

// True if `dir` is a directory or can be made one: the nearest part of it that exists is a
// directory.
bool can_be_directory(const std::filesystem::path& dir, std::string& why) {
  std::error_code ec;
  for (std::filesystem::path p = dir; !p.empty(); p = p.parent_path()) {
    const auto st = std::filesystem::status(p, ec);
    if (std::filesystem::exists(st)) {
      if (std::filesystem::is_directory(st)) return true;
      why = p == dir ? "not a directory" : fmt::format("{} is not a directory", p.string());
      return false;
    }
    if (p == p.parent_path()) break;
  }
  return true;  // a relative path below the working directory
}

// The files a waveform window (--vcd, --dump) writes into its directory.
const char* const kWindowFiles[] = {"emu.vcd", "rtl.vcd", "rtl_internal.fst"};

// Every file a run may write, for outfile::distinct: --junit, the windows' files in --vcd and
// --dump, and a shrunk trace in --out, whose name (cosim-PROFILE-seedN.trace, -session-...) is
// known only at its divergence: a --junit there named like one is taken for it.
std::vector<outfile::Named> run_outputs(const CosimOptions& o) {
  std::vector<outfile::Named> out = {{"--junit", o.junit}};
  for (const auto& [opt, dir] : {std::pair{"--vcd", o.vcd_dir}, std::pair{"--dump", o.dump_dir}}) {
    if (dir.empty()) continue;
    for (const char* name : kWindowFiles)
      out.push_back({opt, (std::filesystem::path(dir) / name).string(), false});  // DIR's files
  }
  const std::string name = std::filesystem::path(o.junit).filename().string();
  if (name.starts_with("cosim-") && name.ends_with(".trace")) {
    out.push_back({"--out",
                   (std::filesystem::path(o.out_dir.empty() ? "." : o.out_dir) / name).string(),
                   false});
  }
  return out;
}

// "" if each of the window's files in `dir` can be written (opened, then discarded), else the
// one-line reason: checked before the seeds run, not found after them.
std::string window_unwritable(const std::string& dir) {
  for (const char* name : kWindowFiles) {
    outfile::OutFile out;
    if (!out.open((std::filesystem::path(dir) / name).string())) return out.error();
  }
  return "";
}

// The shrinker's budgets: a seed's stimulus is thousands of cycles, a session's millions, and
// each run replays it up to the divergence (a session stops shrinking sooner; what it has is
// still a trace that fails).
constexpr int kSeedShrinkRuns = 3000;
constexpr int kSessionShrinkRuns = 50;

// What a divergence of `s` leaves: its stimulus shrunk (in at most `max_runs` lockstep runs) into
// --out as `name` (the header names the run's model and `origin`, a seed or a session) and the
// waveform window in --vcd (the directories made go to `made`); `entry` gets their paths, a file
// not written goes to `output_failed`.
void write_divergence(const CosimOptions& o, const cosim::Stimulus& s, const cosim::RunResult& r,
                      const cosim::DutOptions& dut, const std::string& name,
                      const std::string& origin, int max_runs, nlohmann::json& entry,
                      outfile::MadeDirs& made,
                      const std::function<void(const std::string&)>& output_failed) {
  using namespace dpc31::cosim;
  entry["signals"] = r.signals;
  const Stimulus small = shrink(s, dut, o.mutant, max_runs);
  const std::string dir = o.out_dir.empty() ? "." : o.out_dir;
  std::error_code ec;
  made.make(dir, ec);  // checked up front; a failure shows below
  // A replay shrinks its trace again under a name of its own: a seed run's trace, which the
  // replayed one may be or come from, is never written over, nor the replayed trace itself.
  const std::string trace = (std::filesystem::path(dir) / name).string();
  const bool replayed = !o.replay.empty() && std::filesystem::equivalent(trace, o.replay, ec);
  std::string error;
  const auto events = [](const Stimulus& x) { return x.event_count(); };
  Stimulus before = s;
  before.resize(static_cast<std::uint64_t>(r.divergence) + 1);
  const std::string variant = variant_run_name(dut);  // the VPC3+'s default C named too
  const std::string header = fmt::format(
      "profile {}\nbus {}\nvariant {}\n{}\nmutant {}\n{}shrunk from {} to {} stimulus "
      "events ({} cycles)",
      o.profile_name, o.bus == BusMode::intel ? "intel" : "motorola",
      variant.empty() ? "-" : variant, origin, o.mutant.empty() ? "-" : o.mutant, rtl_header(o),
      events(before), events(small), small.size());
  if (replayed) {
    if (!o.quiet) {
      fmt::print(stderr,
                 "  shrunk to {} stimulus events: not written over {}, the trace "
                 "replayed\n",
                 events(small), trace);
    }
  } else if (outfile::write_file(trace, write_trace(small, header), error)) {
    entry["trace"] = trace;
    if (!o.quiet) {
      // The shrinker keeps any stimulus that still fails: idled, it may fail sooner, and its
      // replay reports that cycle.
      const std::int64_t own = run_lockstep(small, dut, o.mutant).divergence;
      fmt::print(stderr, "  shrunk to {} stimulus events{}: {}\n", events(small),
                 own == r.divergence
                     ? ""
                     : fmt::format(", which diverge at cycle {} (replay it there)", own),
                 trace);
    }
  } else {
    output_failed(error);
  }
  if (!o.vcd_dir.empty()) {
    // Drawn over the run that failed, not the shrunk stimulus cut at the divergence: the
    // --window cycles after it too, idle where the stimulus has ended.
    const auto d = static_cast<std::uint64_t>(r.divergence);
    const std::uint64_t from = d > o.window ? d - o.window : 0;
    Stimulus around = s;
    around.resize(d + o.window + 1);
    // Joined as paths: `--vcd win/` names win/emu.vcd, not win//emu.vcd.
    const auto in_vcd = [&](const char* name) {
      return (std::filesystem::path(o.vcd_dir) / name).string();
    };
    made.make(o.vcd_dir, ec);  // as --out's
    if (write_window(around, dut, o.mutant, from, around.size(), o.vcd_dir, error)) {
      entry["vcd"] = {in_vcd("emu.vcd"), in_vcd("rtl.vcd")};
    } else {
      output_failed(error);
    }
    const cosim::RtlFst fst =
        write_rtl_fst(around, dut, o.mutant, from, in_vcd("rtl_internal.fst"), error);
    if (fst == cosim::RtlFst::written) {
      entry["fst"] = in_vcd("rtl_internal.fst");
    } else if (fst == cosim::RtlFst::failed) {
      output_failed(error);
    } else if (!o.quiet) {
      fmt::print(stderr, "  {}\n", error);
    }
  }
}

// --dump: the whole run of `s`, both sides, for wavediff or GTKWave.
void write_dump(const CosimOptions& o, const cosim::Stimulus& s, const cosim::DutOptions& dut,
                const std::function<void(const std::string&)>& output_failed) {
  std::string error;
  if (!write_window(s, dut, o.mutant, 0, s.size(), o.dump_dir, error)) output_failed(error);
  const cosim::RtlFst fst =
      write_rtl_fst(s, dut, o.mutant, 0,
                    (std::filesystem::path(o.dump_dir) / "rtl_internal.fst").string(), error);
  if (fst == cosim::RtlFst::failed) {
    output_failed(error);
  } else if (fst == cosim::RtlFst::not_traced && !o.quiet) {
    fmt::print(stderr, "{}\n", error);
  }
}

// The waveform windows' files, checked before the run (false: the line printed, exit 2).
bool windows_ready(const CosimOptions& o, outfile::MadeDirs& made) {
  // One that cannot be written was found only after the run. --dump always writes its directory,
  // made now; --vcd's is made at a divergence, its files are checked now if it is there: first,
  // so that a refusal leaves no --dump directory behind.
  for (const auto& [opt, dir, make] :
       {std::tuple{"--vcd", o.vcd_dir, false}, std::tuple{"--dump", o.dump_dir, true}}) {
    if (dir.empty()) continue;
    std::error_code ec;
    if (make && !made.make(dir, ec)) {
      fmt::print(stderr, "dpc31 cosim: {} {}: cannot create the directory: {}\n", opt, dir,
                 ec.message());
      return false;
    }
    if (!std::filesystem::is_directory(dir, ec)) continue;
    if (const std::string why = window_unwritable(dir); !why.empty()) {
      fmt::print(stderr, "dpc31 cosim: {}\n", why);
      return false;
    }
  }
  return true;
}

// Standard output carries the JSON summary alone (and the progress bar on a terminal): while the
// models run, descriptor 1 points at standard error, so that what an RTL prints there ($display,
// $write, Verilator's $finish and $stop lines, on every run of a shrink) cannot corrupt it.
class ModelTextToStderr {
 public:
  ModelTextToStderr() : tty_(::isatty(STDOUT_FILENO) != 0) {
    std::fflush(stdout);
    saved_ = ::dup(STDOUT_FILENO);
    if (saved_ >= 0 && ::dup2(STDERR_FILENO, STDOUT_FILENO) < 0) end();
  }
  ~ModelTextToStderr() { end(); }
  ModelTextToStderr(const ModelTextToStderr&) = delete;
  ModelTextToStderr& operator=(const ModelTextToStderr&) = delete;

  [[nodiscard]] bool tty() const { return tty_; }
  // A progress line on the real standard output, the model's text before it to standard error.
  void progress(const std::string& text) const {
    std::fflush(stdout);
    if (saved_ < 0 || ::write(saved_, text.data(), text.size()) < 0) return;  // best effort
  }
  // Standard output back, the model's text flushed to standard error first.
  void end() {
    if (saved_ < 0) return;
    std::fflush(stdout);
    ::dup2(saved_, STDOUT_FILENO);
    ::close(saved_);
    saved_ = -1;
  }

 private:
  bool tty_;
  int saved_ = -1;
};

// The end of a run: the JSON summary, the JUnit of its `results`, then the first output that
// failed. Exit 0 clean, 1 a divergence, 2 an output not written.
int finish(const CosimOptions& o, const nlohmann::json& summary, const nlohmann::json& results,
           outfile::OutFile& junit_out, const std::string& failed_output,
           ModelTextToStderr& model_text) {
  model_text.end();
  fmt::print("{}\n", summary.dump(2));
  if (!o.junit.empty() &&
      !(junit_out.write(junit(o.profile_name, results)) && junit_out.commit())) {
    fmt::print(stderr, "dpc31 cosim: {}\n", junit_out.error());
    return 2;
  }
  if (!failed_output.empty()) {
    fmt::print(stderr, "dpc31 cosim: {}\n", failed_output);
    return 2;
  }
  const bool diverged = std::any_of(results.begin(), results.end(), [](const nlohmann::json& r) {
    return r["diverged"].get<bool>();
  });
  return diverged ? 1 : 0;
}

// "" or why the built-in --mutant NAME does not run on the run's profile: the built-in mutants
// live in a model of one profile (the SAP header machine's: vpc3plus).
std::string mutant_not_on_profile(const CosimOptions& o) {
  const auto p = cosim::rtl_mutant_profile(o.mutant);
  if (!p || *p == o.profile) return "";
  return fmt::format("mutant '{}' is built for profile {}, not {} (--profile {})", o.mutant,
                     profile_name(*p), o.profile_name, profile_name(*p));
}

// Whether the run's RTL side can be made (the built-in model of its profile, or --mutant's); else
// false with the line printed (exit 2): a mutant of another profile, or no such mutant.
bool rtl_dut_ready(const CosimOptions& o, const cosim::DutOptions& dut) {
  if (cosim::make_rtl_dut(dut, o.mutant)) return true;
  if (const std::string why = mutant_not_on_profile(o); !why.empty()) {
    fmt::print(stderr, "dpc31 cosim: {}\n", why);
  } else {
    fmt::print(stderr, "dpc31 cosim: no RTL model for profile {} mutant '{}' (no such mutant)\n",
               o.profile_name, o.mutant);
  }
  return false;
}

// The model the run uses in place of the built-in ones: --rtl (built into the cache, or taken
// from it) or --rtl-model. False with the line already printed (exit 2).
// `id` names the model in the JSON summary the same on every machine: the cache key for --rtl,
// the file name for --rtl-model, "" for the built-in models.
bool load_rtl(const CosimOptions& o, cosim::DutOptions& dut, std::string& id) {
  using namespace dpc31::cosim;
  const auto fail = [](const std::string& why) {
    fmt::print(stderr, "dpc31 cosim: {}\n", why);
    return false;
  };
  if (o.rtl_sources.empty() && o.rtl_host_code) return fail("--rtl-host-code is for --rtl");
  if (o.rtl_sources.empty() && o.rtl_model.empty()) {
    if (!o.top.empty() || !o.defines.empty())
      return fail(fmt::format("--{} is for --rtl", o.top.empty() ? "define" : "top"));
    return true;
  }
  if (!o.rtl_sources.empty() && !o.rtl_model.empty())
    return fail("--rtl and --rtl-model: one model at a time");
  std::string path = o.rtl_model;
  std::string error;
  // The note that a build starts (minutes) only on a terminal, as the progress bar: in a log,
  // stderr is the report alone.
  std::FILE* progress = o.quiet || isatty(STDERR_FILENO) == 0 ? nullptr : stderr;
  if (!o.rtl_sources.empty() &&
      !build_rtl_model({o.rtl_sources, o.top, o.defines, o.profile, o.rtl_host_code}, path, error,
                       progress)) {
    return fail(error);
  }
  if (o.rtl_sources.empty() && (!o.top.empty() || !o.defines.empty()))
    return fail("--top and --define are for --rtl (a --rtl-model is built already)");
  dut.rtl = RtlLibrary::load(path, error);
  if (!dut.rtl) return fail(error);
  // Its PROFILE is fixed when it is built: on another profile every seed would "diverge".
  if (dut.rtl->profile() != o.profile) {
    return fail(fmt::format(
        "{}: the model is built for profile {}, not {}: run it with --profile {} (a session: a "
        "scenario of that profile), or build it with PROFILE {}",
        path, profile_name(dut.rtl->profile()), o.profile_name, profile_name(dut.rtl->profile()),
        o.profile_name));
  }
  const std::filesystem::path p(path);
  id = (o.rtl_model.empty() ? p.parent_path().filename() : p.filename()).string();
  if (!o.mutant.empty()) {
    if (!mutant_sel(o.mutant))
      return fail(fmt::format(
          "--mutant {}: with --rtl, a mutant of rtl/dpc31_blocks.v by name or a number 1..15 "
          "for the mutant_sel input",
          o.mutant));
    if (!dut.rtl->has_mutant_sel())
      return fail(
          fmt::format("--mutant {}: module {} has no mutant_sel input (rtl/dpc31_blocks.v "
                      "has it with --define MUTANTS)",
                      o.mutant, dut.rtl->top()));
    // A mutant of rtl/dpc31_blocks.v by name runs where the built-in one does.
    if (const std::string why = mutant_not_on_profile(o); !why.empty()) return fail(why);
  }
  if (!make_rtl_dut(dut, o.mutant))
    return fail(path + ": its create() returned NULL: no model to run (out of memory?)");
  return true;
}

}  // namespace

namespace {

// The scenario names the chip it runs on: a --profile, --bus or --variant that says otherwise
// would be dropped without a word. "" or why not.
std::string session_chip_mismatch(const CosimOptions& o, const dpc31::cosim::DutOptions& d) {
  const auto bus_name = [](BusMode b) { return b == BusMode::intel ? "intel" : "motorola"; };
  const std::string_view profile = profile_desc(d.profile).name;
  const std::string variant = variant_run_name(d);
  if (o.profile_given && o.profile != d.profile) {
    return fmt::format("{}: the scenario runs profile {}, not --profile {}", o.session, profile,
                       o.profile_name);
  }
  if (o.bus_given && o.bus != d.bus) {
    return fmt::format("{}: the scenario runs bus {}, not --bus {}", o.session, bus_name(d.bus),
                       bus_name(o.bus));
  }
  if (!o.variant_name.empty() && o.variant_name != variant) {
    return fmt::format("{}: the scenario runs profile {}{}, not --variant {}", o.session, profile,
                       variant.empty() ? " (no variant)" : " variant " + variant, o.variant_name);
  }
  return {};
}

int run_session_mode(const CosimOptions& given, outfile::OutFile& junit_out,
                     ModelTextToStderr& model_text) {
  using namespace dpc31::cosim;
  Session s;
  std::string error;
  const auto t0 = std::chrono::steady_clock::now();
  if (!record_session(given.session, s, error)) {
    fmt::print(stderr, "{}\n", error);
    return 2;
  }
  if (const std::string why = session_chip_mismatch(given, s.options); !why.empty()) {
    fmt::print(stderr, "dpc31 cosim: {}\n", why);
    return 2;
  }
  // The scenario's chip is the run's: the RTL is built for its profile, and a trace's header
  // names it.
  CosimOptions o = given;
  o.profile = s.options.profile;
  o.profile_name = profile_desc(s.options.profile).name;
  o.bus = s.options.bus;
  std::string rtl_id;
  // What it makes for its outputs and leaves empty is removed again (a signal, a failed write).
  outfile::MadeDirs made;
  if (!load_rtl(o, s.options, rtl_id) || !rtl_dut_ready(o, s.options) || !windows_ready(o, made))
    return 2;
  // A chip that did not do what its scenario says: its lines, as `dpc31 run` prints them, and
  // exit 1 whatever the lockstep finds.
  for (const std::string& line : s.scenario_failures) fmt::print(stderr, "{}\n", line);
  const RunResult r = run_session(s, o.mutant);  // s.options carries a --rtl model
  if (!o.quiet) {
    for (const std::string& line : r.report) fmt::print(stderr, "{}\n", line);
  }
  std::string failed_output;
  const auto output_failed = [&failed_output](const std::string& why) {
    if (failed_output.empty()) failed_output = why;
  };
  const std::string stem = std::filesystem::path(o.session).stem().string();
  nlohmann::json entry = {{"session", stem},
                          {"diverged", r.divergence >= 0},
                          {"cycle", r.divergence},
                          {"scenario_expects_passed", s.scenario_failures.empty()}};
  const Stimulus stimulus = session_stimulus(s);
  if (r.divergence >= 0 && static_cast<std::uint64_t>(r.divergence) < s.cycles) {
    write_divergence(o, stimulus, r, s.options,
                     fmt::format("cosim-{}-session-{}.trace", o.profile_name, stem),
                     "session " + std::filesystem::absolute(o.session).string(), kSessionShrinkRuns,
                     entry, made, output_failed);
  } else if (r.divergence >= 0 && !o.quiet) {
    // Only the live chip saw the other end: a trace replays the blocks, not the chip.
    fmt::print(stderr, "  no trace or waveform window: a replay has no live chip to differ from\n");
  }
  if (!o.dump_dir.empty()) write_dump(o, stimulus, s.options, output_failed);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  nlohmann::json summary = {{"session", o.session},
                            {"profile", o.profile_name},
                            {"bus", s.options.bus == BusMode::intel ? "intel" : "motorola"},
                            {"variant", variant_json(s.options)},
                            {"mutant", o.mutant},
                            {"rtl", rtl_id},
                            {"cycles", s.cycles},
                            {"block_events", s.events.size()},
                            {"scenario_expects_passed", s.scenario_failures.empty()},
                            {"diverged", r.divergence >= 0},
                            {"cycle", r.divergence},
                            {"signals", r.signals},
                            {"seconds", secs}};
  for (const char* k : {"trace", "vcd", "fst"}) {
    if (entry.contains(k)) summary[k] = entry[k];
  }
  const int rc =
      finish(o, summary, nlohmann::json::array({entry}), junit_out, failed_output, model_text);
  return rc == 0 && !s.scenario_failures.empty() ? 1 : rc;
}

}  // namespace

int run_cosim(const CosimOptions& given) {
  using namespace dpc31::cosim;
  CosimOptions o = given;
  std::vector<outfile::Named> inputs = {
      {"--replay", o.replay}, {"--session", o.session}, {"--rtl-model", o.rtl_model}};
  for (const std::string& v : o.rtl_sources) inputs.push_back({"--rtl", v});
  // What the scenario reads (a plug-in, a `cpu` image): a scenario that does not load is said
  // by the session's recording, with its line; a pipe is read once, by the recording.
  if (Scenario sc; std::filesystem::is_regular_file(o.session)) {
    if (ScenarioError ignored; load_scenario(o.session, sc, ignored)) {
      for (outfile::Named& n : scenario_inputs(sc)) inputs.push_back(std::move(n));
    }
  }
  std::string same = outfile::distinct(inputs, run_outputs(o));
  // A directory is no file of distinct()'s, but --junit must not be one of them either.
  for (const auto& [opt, dir] : {std::pair{"--out", o.out_dir}, std::pair{"--vcd", o.vcd_dir},
                                 std::pair{"--dump", o.dump_dir}}) {
    if (same.empty()) same = outfile::distinct({}, {{opt, dir}, {"--junit", o.junit}});
  }
  if (!same.empty()) {
    fmt::print(stderr, "dpc31 cosim: {}\n", same);
    return 2;
  }
  // The summary's "to" is one past the last seed (base + seeds), a 64-bit number like every
  // seed: a range that wrapped to 0 ran seeds of another run and summed to a summary merge
  // refuses. So the last seed a run can have is 2^64 - 2, and the message says that, not that
  // the seeds themselves overflow (seed 2^64 - 1 alone would fit, its "to" would not).
  if (o.replay.empty() && o.seeds > std::numeric_limits<std::uint64_t>::max() - o.seed_base) {
    fmt::print(stderr,
               "dpc31 cosim: --seed-base {} with --seeds {}: the summary's \"to\" (one past the "
               "last seed) would pass {}, the last 64-bit number: the last seed a run can have "
               "is {}\n",
               o.seed_base, o.seeds, std::numeric_limits<std::uint64_t>::max(),
               std::numeric_limits<std::uint64_t>::max() - 1);
    return 2;
  }
  // Opened before the seeds run: a bad path is one line up front, not after minutes.
  outfile::OutFile junit_out;
  if (!o.junit.empty() && !junit_out.open(o.junit)) {
    fmt::print(stderr, "dpc31 cosim: {}\n", junit_out.error());
    return 2;
  }
  // The directories are made only when something goes into them, but checked now.
  for (const auto& [opt, dir] : {std::pair{"--out", o.out_dir}, std::pair{"--vcd", o.vcd_dir},
                                 std::pair{"--dump", o.dump_dir}}) {
    if (std::string why; !dir.empty() && !can_be_directory(dir, why)) {
      fmt::print(stderr, "dpc31 cosim: {} {}: {}\n", opt, dir, why);
      return 2;
    }
  }
  ModelTextToStderr model_text;
  if (!o.session.empty()) return run_session_mode(o, junit_out, model_text);
  // A replayed trace first: its header names the model to build.
  std::vector<std::pair<std::uint64_t, Stimulus>> runs;
  if (!o.replay.empty()) {
    Stimulus s;
    std::uint64_t seed = 0;
    std::string error;
    if (!read_stimulus(o.replay, s, o, seed, error)) {
      fmt::print(stderr, "{}\n", error);
      return 2;
    }
    // The RTL the header names is an input as --rtl is: --junit must not replace it.
    std::vector<outfile::Named> named;
    for (const std::string& v : o.rtl_sources) named.push_back({"the trace's rtl", v});
    if (!o.rtl_model.empty()) named.push_back({"the trace's rtl-model", o.rtl_model});
    if (const std::string same = outfile::distinct(named, {{"--junit", o.junit}}); !same.empty()) {
      fmt::print(stderr, "dpc31 cosim: {}\n", same);
      return 2;
    }
    ChipOptions chip{o.profile};
    if (const std::string why = apply_variant(o.variant_name, chip); !why.empty()) {
      fmt::print(stderr, "dpc31 cosim: {}\n", why);
      return 2;
    }
    o.variant = chip.variant;
    runs.emplace_back(seed, std::move(s));
  }
  DutOptions dut{o.profile, o.bus, o.variant};
  std::string rtl_id;
  if (!load_rtl(o, dut, rtl_id)) return 2;
  // What it makes for its outputs and leaves empty is removed again (a signal, a failed write).
  outfile::MadeDirs made;
  if (!rtl_dut_ready(o, dut) || !windows_ready(o, made)) return 2;
  // A model that does not trace (the built-in mutants', a --rtl-model whose trace_to returns 0)
  // writes no rtl_internal.fst: a note. Any other output that fails in the run is exit 2, after
  // the summary and the JUnit, which record the seeds that ran; the first failure is the one line.
  std::string failed_output;
  const auto output_failed = [&failed_output](const std::string& error) {
    if (failed_output.empty()) failed_output = error;
  };
  // Seeds of this shard: a contiguous part of [seed_base, seed_base + seeds).
  const std::uint64_t lo = o.seed_base + o.seeds * (o.shard - 1) / o.shards;
  const std::uint64_t hi = o.seed_base + o.seeds * o.shard / o.shards;
  const bool tty = model_text.tty() && !o.quiet;
  nlohmann::json results = nlohmann::json::array();
  std::uint64_t diverged = 0;
  std::uint64_t cycles = 0;
  const auto t0 = std::chrono::steady_clock::now();
  const std::uint64_t total = runs.empty() ? hi - lo : 1;
  for (std::uint64_t i = 0; i < total; ++i) {
    const std::uint64_t seed = runs.empty() ? lo + i : runs[0].first;
    const Stimulus s = runs.empty() ? random_stimulus({o.profile, seed, o.cycles}) : runs[0].second;
    const RunResult r = run_lockstep(s, dut, o.mutant);
    cycles += r.divergence >= 0 ? static_cast<std::uint64_t>(r.divergence) + 1 : s.size();
    nlohmann::json entry = {
        {"seed", seed}, {"diverged", r.divergence >= 0}, {"cycle", r.divergence}};
    if (r.divergence >= 0) {
      ++diverged;
      if (!o.quiet) {
        fmt::print(stderr, "{}seed {}: ", tty ? "\n" : "", seed);
        for (const std::string& line : r.report) fmt::print(stderr, "{}\n", line);
      }
      write_divergence(o, s, r, dut,
                       fmt::format("cosim-{}-seed{}{}.trace", o.profile_name, seed,
                                   o.replay.empty() ? "" : "-replay"),
                       fmt::format("seed {}", seed), kSeedShrinkRuns, entry, made, output_failed);
    }
    results.push_back(entry);
    if (tty) {
      const std::size_t width = 40;
      const std::size_t done = (i + 1) * width / total;
      model_text.progress(fmt::format("\r[{}{}] {}/{} seeds, {} divergent", std::string(done, '#'),
                                      std::string(width - done, '.'), i + 1, total, diverged));
    }
    if (diverged > 0 && !o.keep_going) break;
  }
  if (tty) model_text.progress("\n");
  if (!o.dump_dir.empty()) {
    // The whole run of the first stimulus.
    write_dump(o, runs.empty() ? random_stimulus({o.profile, lo, o.cycles}) : runs[0].second, dut,
               output_failed);
  }
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  nlohmann::json run = {{"profile", o.profile_name},
                        {"bus", o.bus == BusMode::motorola ? "motorola" : "intel"},
                        {"variant", variant_json(dut)},
                        {"mutant", o.mutant},
                        {"rtl", rtl_id}};
  nlohmann::json summary;
  if (!runs.empty()) {
    // A replay is one trace, not a range of seeds: the summary names it and its length.
    run["replay"] = o.replay;
    run["trace_cycles"] = runs[0].second.size();
    run["cycles"] = cycles;
    run["seconds"] = secs;
    run["divergent_seeds"] = diverged;
    run["results"] = results;
    summary = std::move(run);
  } else {
    run["cycles_per_seed"] = o.cycles;
    run["keep_going"] = o.keep_going;
    const nlohmann::json shard = {{"index", o.shard},
                                  {"count", o.shards},
                                  {"of", {{"from", o.seed_base}, {"to", o.seed_base + o.seeds}}}};
    summary = summary_json(run, shard, lo, hi, cycles, secs, results);
  }
  return finish(o, summary, results, junit_out, failed_output, model_text);
}

}  // namespace dpc31::cli

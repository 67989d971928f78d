// dpc31: the command-line front end. Exit codes: 0 ok, 1 difference or test failure, 2 bad input.
#include <fmt/core.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "bench.hpp"
#include "bridge.hpp"
#include "chip_choice.hpp"
#include "cleanup.hpp"
#include "cosim.hpp"
#include "demo.hpp"
#include "dpc31/chip.hpp"
#include "dpc31/dpc31_version.h"
#include "numbers.hpp"
#include "path_option.hpp"
#include "regfmt.hpp"
#include "replay.hpp"
#include "run.hpp"
#include "serve.hpp"
#include "soak.hpp"
#include "textfile.hpp"
#include "wavediff_cli.hpp"

namespace {

// All `n` bytes to `fd` (a cookie stream's write, EINTR retried): the count written, -1 for none;
// `why` is the failure's errno (EIO for a write of 0 bytes), left alone when all were written.
ssize_t write_all(int fd, const char* buf, std::size_t n, int& why) {
  std::size_t done = 0;
  while (done < n) {
    const ssize_t w = ::write(fd, buf + done, n - done);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) {
      why = w < 0 ? errno : EIO;
      return done > 0 ? static_cast<ssize_t>(done) : -1;
    }
    done += static_cast<std::size_t>(w);
  }
  return static_cast<ssize_t>(n);
}

// `stream` (stdout or stderr) replaced by one writing through `write` with `mode` buffering; left
// as it is where the stream cannot be made.
void replace_stream(std::FILE*& stream, cookie_write_function_t* write, int mode) {
  cookie_io_functions_t io{};
  io.write = write;
  std::FILE* f = ::fopencookie(nullptr, "w", io);
  if (f == nullptr) return;
  std::setvbuf(f, nullptr, mode, mode == _IONBF ? 0 : BUFSIZ);
  stream = f;
}

// The standard output through a stream that remembers why its first write failed: stdio keeps
// only an error flag, and by the end errno says something else.
int g_stdout_errno = 0;

ssize_t write_stdout(void* /*cookie*/, const char* buf, std::size_t n) {
  int why = 0;
  const ssize_t w = write_all(STDOUT_FILENO, buf, n, why);
  if (why != 0 && g_stdout_errno == 0) g_stdout_errno = why;
  return w;
}

// The standard error through a stream that first writes what the standard output holds: with both
// on one file or pipe (`2>&1`) an error line lands between two walk lines, in their order, not
// inside a line the buffered walk had half written. Unbuffered, as stdio's stderr.
ssize_t write_stderr(void* /*cookie*/, const char* buf, std::size_t n) {
  std::fflush(stdout);  // a failure is stdout's own, said at the end (g_stdout_errno)
  int why = 0;
  return write_all(STDERR_FILENO, buf, n, why);
}

void replace_std_streams() {
  // stdout as stdio would buffer it: line-buffered on a terminal (progress lines), fully
  // otherwise; without the cookie stream failures still show, without the reason (and stderr's
  // lines maybe out of order).
  replace_stream(stdout, write_stdout, ::isatty(STDOUT_FILENO) != 0 ? _IOLBF : _IOFBF);
  replace_stream(stderr, write_stderr, _IONBF);
}

// The units a waveform of `run` and `demo` takes, and why the coarser ones are refused.
const std::string kTimescales = std::string(dpc31::cli::kTimescaleUnits) +
                                " (a unit longer than a 48 MHz clock cycle, 20.8 ns, is refused)";

dpc31::Profile to_profile(const std::string& s) {
  dpc31::Profile p{};
  dpc31::parse_profile(s, p);  // CLI11's check already refused unknown names
  return p;
}

}  // namespace

int main(int argc, char** argv) {
  dpc31::cleanup::install();  // temporaries and children go when a signal ends the process
  // A file-size limit (ulimit -f) then fails the write with EFBIG, and a pipe whose reader left
  // (`| head -1`) with EPIPE, which every output reports with its one line, exit 2, and its
  // temporaries removed; SIGXFSZ and SIGPIPE ended the process silently.
  std::signal(SIGXFSZ, SIG_IGN);
  std::signal(SIGPIPE, SIG_IGN);
  replace_std_streams();
  using dpc31::numbers::whole;
  using dpc31::outfile::named;
  using dpc31::outfile::Use;
  CLI::App app{"dpc31emu: cycle-accurate emulator of the Siemens DPC31, SPC3 and VPC3+"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "dpc31 " DPC31EMU_VERSION_STRING, "print the version and exit");
  const std::vector<std::string> profiles = {"spc3", "vpc3plus", "dpc31"};

  std::string demo_profile = "dpc31";
  std::string demo_bus = "intel";
  auto* demo = app.add_subcommand(
      "demo",
      "a register-level session (start, interrupts, EOI), then a DP session: the built-in master "
      "and DO4 (or --firmware), the cable pulled past the DP watchdog; waveforms and pcapng");
  demo->add_option("--profile", demo_profile, "chip profile")->check(CLI::IsMember(profiles));
  std::string demo_out;  // "": a fresh private directory TMPDIR/dpc31-demo-XXXXXX (mkdtemp)
  demo->add_option("--out-dir", demo_out,
                   "where the DP session's waveform and capture go (default: a new directory "
                   "TMPDIR/dpc31-demo-XXXXXX)")
      ->transform(named(Use::place));
  demo->add_option("--bus", demo_bus, "bus byte order")
      ->check(CLI::IsMember({"intel", "motorola"}));
  dpc31::cli::ChipChoice demo_chip;
  dpc31::cli::add_chip_options(demo, demo_chip);
  std::optional<std::string> demo_timescale;  // none: each waveform's default
  demo->add_option("--timescale", demo_timescale,
                   "time unit of both waveforms: " + kTimescales +
                       "; default 1ps for the full VCD, 10ns for the logic analysers' VCD");
  std::optional<std::string> demo_firmware;  // none: DO4 with its OSP story
  demo->add_option("--firmware", demo_firmware,
                   "the DP session's firmware instead of DO4: a built-in name or a plug-in "
                   "./libmine.so (docs/bring-up.md)");

  std::string regs_profile = "dpc31";
  std::string regs_format = "text";
  auto* regs =
      app.add_subcommand("regs", "print the register map of a profile from the description");
  std::vector<std::string> with_all = profiles;
  with_all.emplace_back("all");
  regs->add_option("--profile", regs_profile, "chip profile, or all (c, verilog, markdown)")
      ->check(CLI::IsMember(with_all));
  regs->add_option("--format", regs_format, "output format")
      ->check(CLI::IsMember({"text", "json", "c", "verilog", "markdown"}));

  dpc31::cli::RunOptions run_opt;
  auto* run = app.add_subcommand("run", "play a scenario file and print the state walk");
  run->add_option("scenario", run_opt.scenario, "scenario file (docs/scenario-format.md)")
      ->required()
      ->transform(named(Use::read));
  run->add_flag("--quiet", run_opt.quiet, "print no state walk, only failures");
  run->add_option("--json", run_opt.json, "write a JSON summary to this file")
      ->transform(named(Use::write));
  run->add_option("--record", run_opt.record,
                  "write a golden trace of the run to this file (docs/trace-format.md)")
      ->transform(named(Use::write));
  run->add_option("--vcd", run_opt.vcd, "write the run as a VCD waveform (docs/waveforms.md)")
      ->transform(named(Use::write));
  run->add_option("--fst", run_opt.fst, "write the run as an FST waveform")
      ->transform(named(Use::write));
  // One value a time (GLOB,GLOB or the option again): more took the scenario after it.
  run->add_option("--signals", run_opt.signals, "waveform signals (globs, e.g. pins.*)")
      ->delimiter(',')
      ->allow_extra_args(false);
  // Numbers: dpc31::numbers (no NaN, no "-1" taken as 2^64 - 1, nothing that does not fit).
  run->add_option("--from", run_opt.from, "waveform window: first cycle")->transform(whole(0));
  run->add_option("--to", run_opt.to, "waveform window: one past the last cycle")
      ->transform(whole(0));
  run->add_option("--la-vcd", run_opt.la_vcd,
                  "also write the run as a VCD for logic-analyser tools (sigrok, PulseView): "
                  "1-bit signals, one scope")
      ->transform(named(Use::write));
  run->add_option(
      "--timescale", run_opt.timescale,
      "waveform time unit: " + kTimescales + "; default 1ps, 10ns with --flat and --la-vcd");
  run->add_flag("--flat", run_opt.flat,
                "--vcd / --fst for logic-analyser tools: 1-bit signals, one scope");
  run->add_option("--gtkw", run_opt.gtkw,
                  "also write a GTKWave save file for --vcd (or --fst): signals by block, states "
                  "by name, markers at the state changes (docs/waveforms.md)")
      ->transform(named(Use::write));
  run->add_option("--pvs", run_opt.pvs,
                  "also write a PulseView session for --la-vcd (or --vcd --flat): the UART and "
                  "PROFIBUS DP decoders on RxD and TxD; PulseView opens NAME.pvs beside NAME.vcd "
                  "by itself (docs/waveforms.md)")
      ->transform(named(Use::write));
  run->add_option_function<std::string>(
         "--engine",
         [&run_opt](const std::string& name) {
           run_opt.engine = name == "event" ? dpc31::Engine::event : dpc31::Engine::per_cycle;
         },
         "how time advances: event (deadline to deadline) or per-cycle (every clock, the "
         "reference; docs/engine.md)")
      // The names only: a mapped enum also took its numbers (--engine 1) and showed them.
      ->check(CLI::IsMember({"event", "per-cycle"}))
      ->default_str("event");
  run->add_option("--pcap", run_opt.pcap, "write the telegrams as pcapng (docs/capture.md)")
      ->transform(named(Use::write));

  dpc31::cli::ReplayOptions replay_opt;
  auto* replay = app.add_subcommand(
      "replay", "replay a golden trace on a fresh chip and check every expected value");
  replay->add_option("trace", replay_opt.trace, "trace file (docs/trace-format.md)")
      ->required()
      ->transform(named(Use::read));
  replay->add_flag("--quiet", replay_opt.quiet, "print nothing on success");

  dpc31::cli::CosimOptions cos;
  std::string cos_shard = "1/1";
  std::string cos_bus = "intel";
  auto* cosim = app.add_subcommand(
      "cosim", "lockstep: the C++ blocks against the Verilated RTL, every cycle");
  cosim->add_option("--profile", cos.profile_name, "chip profile")->check(CLI::IsMember(profiles));
  cosim->add_option("--bus", cos_bus, "bus byte order")
      ->check(CLI::IsMember({"intel", "motorola"}));
  std::string cos_variant;
  dpc31::cli::add_variant_option(cosim, cos_variant);
  // The options of random seeds, which mean nothing to a --replay (refused beside it).
  const std::vector<CLI::Option*> cos_random = {
      cosim->add_option("--seeds", cos.seeds, "number of random seeds")
          ->transform(whole(1, 100'000'000)),
      cosim->add_option("--seed-base", cos.seed_base, "first seed")->transform(whole(0)),
      cosim->add_option("--cycles", cos.cycles, "cycles per seed")
          ->transform(whole(1, 100'000'000)),
      cosim->add_option("--shard", cos_shard,
                        "K/N: run the K-th of N equal parts of the seed range (K from 1, or from "
                        "0 with --shard-base 0; docs/regression.md)")};
  unsigned cos_shard_base = 1;
  auto* cos_shard_base_opt =
      cosim->add_option("--shard-base", cos_shard_base, "the first K of --shard: 1 (default) or 0")
          ->check(CLI::IsMember({0, 1}));
  cos_shard_base_opt->needs(cos_random.back());  // alone it blamed a --shard 1/1 never given
  // A run's outputs: a session writes them too (its divergence's trace and window, its dump).
  cosim->add_option("--junit", cos.junit, "write JUnit XML results to this file")
      ->transform(named(Use::write));
  cosim->add_option("--vcd", cos.vcd_dir, "on divergence, write emu.vcd and rtl.vcd around it here")
      ->transform(named(Use::place));
  cosim
      ->add_option("--window", cos.window,
                   "cycles before and after the divergence in the VCD window")
      ->transform(whole(0, 100'000'000));
  cosim->add_option("--out", cos.out_dir, "where shrunk stimulus traces go (default .)")
      ->transform(named(Use::place));
  cosim
      ->add_option("--dump", cos.dump_dir,
                   "write emu.vcd, rtl.vcd (ports) and rtl_internal.fst of the first run (or the "
                   "session) here")
      ->transform(named(Use::place));
  // What a --session run never reads (refused beside it, with cos_random).
  std::vector<CLI::Option*> cos_not_session;
  auto* cos_replay =
      cosim
          ->add_option("--replay", cos.replay,
                       "replay a stimulus trace instead of random seeds (with the profile and "
                       "mutant its header names)")
          ->transform(named(Use::read));
  for (CLI::Option* opt : cos_random) cos_replay->excludes(opt);
  cos_replay->excludes(cos_shard_base_opt);
  cos_not_session.insert(cos_not_session.end(), cos_random.begin(), cos_random.end());
  cos_not_session.insert(cos_not_session.end(), {cos_shard_base_opt, cos_replay});
  cosim->add_option("--mutant", cos.mutant,
                    "use an RTL mutant (to see the check fail); with --rtl: the value of the "
                    "model's mutant_sel input, by name or 1..15");
  cosim
      ->add_option("--rtl", cos.rtl_sources,
                   "your Verilog sources in place of the built-in model: Verilated and built "
                   "into the cache on first use (docs/golden-model.md)")
      ->expected(1, -1)
      ->transform(named(Use::read));
  cosim->add_option("--top", cos.top, "with --rtl: the top module");
  cosim->add_option("--define", cos.defines, "with --rtl: a Verilog define NAME or NAME=VALUE")
      ->take_all();
  cosim->add_flag("--rtl-host-code", cos.rtl_host_code,
                  "with --rtl: build sources that use $system, $c, `systemc_ or DPI imports, "
                  "which run shell commands and C/C++ inside dpc31 with your rights (refused "
                  "without it)");
  cosim
      ->add_option("--rtl-model", cos.rtl_model,
                   "a model built by dpc31emu_verilate_model() (a .so) in place of the built-in")
      ->transform(named(Use::read));
  // dpc31 cosim merge: the shards' JSON summaries into the whole run's (docs/regression.md).
  dpc31::cli::MergeOptions merge_opt;
  auto* merge = cosim->add_subcommand(
      "merge", "merge the JSON summaries of the shards of one run into its summary and JUnit");
  merge->add_option("summaries", merge_opt.inputs, "the shards' JSON summaries")
      ->required()
      ->transform(named(Use::read));
  merge->add_option("--junit", merge_opt.junit, "write the whole run's JUnit XML to this file")
      ->transform(named(Use::write));
  auto* cos_session =
      cosim
          ->add_option(
              "--session", cos.session,
              "chip-session mode: run this scenario on the full chip, drive the RTL with its "
              "block events")
          ->transform(named(Use::read));
  cos_not_session.push_back(
      cosim->add_flag("--keep-going", cos.keep_going, "do not stop at the first divergent seed"));
  cos_replay->excludes(cos_not_session.back());
  // The scenario is one run of its own chip: the options of seeds and their outputs act on
  // nothing (docs/decisions.md, "No silent options"); --profile, --bus, --variant are checked
  // against the scenario's chip (cosim.cpp).
  for (CLI::Option* opt : cos_not_session) cos_session->excludes(opt);
  cosim->add_flag("--quiet", cos.quiet, "no report text, only the JSON summary");

  // dpc31 wavediff A B [options]: waveform comparison (docs/wavediff.md).
  dpc31::wavediff::CliArgs wavediff_args;
  auto* wavediff = dpc31::wavediff::add_subcommand(app, wavediff_args);

  // dpc31 serve: the chip behind a socket (docs/protocol.md).
  dpc31::cli::ServeArgs serve_args;
  auto* serve = dpc31::cli::add_serve_subcommand(app, serve_args);
  // dpc31 bridge: the slave's RS-485 side as a pseudo-terminal (docs/bridge.md).
  dpc31::cli::BridgeOptions bridge_opt;
  auto* bridge = dpc31::cli::add_bridge_subcommand(app, bridge_opt);

  // dpc31 bench: the benchmarks against the targets (docs/performance.md).
  dpc31::cli::BenchArgs bench_args;
  auto* bench = dpc31::cli::add_bench_subcommand(app, bench_args);

  // dpc31 soak: a long run with injected faults, counters checked exactly (docs/soak.md).
  dpc31::soak::Options soak_opt;
  auto* soak = dpc31::soak::add_subcommand(app, soak_opt);

  // Bad input is one line, "dpc31 SUBCOMMAND: what", and exit 2 (docs/bad-input.md). The
  // subcommand as typed, nested ones included: `dpc31 cosim merge: ...`.
  const auto refuse = [&app](std::string what) {
    std::string where = "dpc31";
    for (const CLI::App* at = &app; !at->get_subcommands().empty();) {
      at = at->get_subcommands().front();
      where += " " + at->get_name();
    }
    std::replace(what.begin(), what.end(), '\n', ' ');
    while (!what.empty() && what.back() == ' ') what.pop_back();
    fmt::print(stderr, "{}: {}\n", where, what);
    return 2;
  };

  // What went to the standard output is part of the result: a write that failed (a full disk,
  // /dev/full) is exit 2, whatever the command found.
  const auto stdout_failed = [&refuse] {
    return refuse(fmt::format("cannot write the standard output: {}",
                              std::strerror(g_stdout_errno != 0 ? g_stdout_errno : EIO)));
  };

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) {  // --help, --help-all, --version: through the checked stdout
      std::ostringstream text;
      app.exit(e, text, text);
      std::fputs(text.str().c_str(), stdout);
      return std::fflush(stdout) != 0 || std::ferror(stdout) != 0 ? stdout_failed() : 0;
    }
    // A first word that names no subcommand: CLI11 says only that one is required.
    if (app.get_subcommands().empty() && argc > 1 && argv[1][0] != '-') {
      std::string known;
      for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
        known += (known.empty() ? "" : ", ") + sub->get_name();
      }
      return refuse(fmt::format("unknown subcommand '{}' ({})", dpc31::shown(argv[1]), known));
    }
    return refuse(e.what());  // CLI11's own exit() would add a second line
  }

  const auto dispatch = [&]() -> int {
    if (soak->parsed()) return dpc31::soak::run_cli(soak_opt, stdout, stderr);
    if (bench->parsed()) return dpc31::cli::run_bench(bench_args, stdout, stderr);
    if (serve->parsed()) return dpc31::cli::run_serve(serve_args, stdout, stderr);
    if (bridge->parsed()) return dpc31::cli::run_bridge(bridge_opt, stdout, stderr);
    if (wavediff->parsed()) return dpc31::wavediff::run_cli(wavediff_args, stdout, stderr);
    if (run->parsed()) return dpc31::cli::run_scenario_command(run_opt, stdout, stderr);
    if (replay->parsed()) return dpc31::cli::run_replay_command(replay_opt, stdout, stderr);
    if (merge->parsed()) {
      // cosim's options act on seeds that merge does not run (docs/decisions.md, "No silent
      // options"): `cosim --junit F merge ...` wrote no F.
      for (const CLI::Option* opt : cosim->get_options()) {
        if (opt->count() > 0) {
          return refuse(fmt::format(
              "{} before merge: an option of cosim's seeds, which merge does not run; merge's "
              "own options go after it",
              opt->get_name()));
        }
      }
      return dpc31::cli::run_cosim_merge(merge_opt);
    }
    if (cosim->parsed()) {
      if (cosim->count("--window") > 0 && cos.vcd_dir.empty()) {
        return refuse(fmt::format("--window {}: the divergence's window needs --vcd", cos.window));
      }
      dpc31::parse_profile(cos.profile_name, cos.profile);
      cos.profile_given = cosim->count("--profile") > 0;
      cos.mutant_given = cosim->count("--mutant") > 0;
      cos.bus_given = cosim->count("--bus") > 0;
      cos.bus = cos_bus == "intel" ? dpc31::BusMode::intel : dpc31::BusMode::motorola;
      cos.variant_name = cos_variant;
      // A replay's profile may come from its trace's header, a session's from its scenario.
      if (cos.replay.empty() && cos.session.empty()) {
        dpc31::ChipOptions chip{cos.profile};
        if (std::string why = dpc31::cli::apply_variant(cos_variant, chip); !why.empty()) {
          return refuse(why);
        }
        cos.variant = chip.variant;
      }
      // K and N as every number of the CLI (dpc31::numbers::parse_whole).
      std::uint64_t k = 0;
      std::uint64_t n = 0;
      const std::size_t slash = cos_shard.find('/');
      if (slash == std::string::npos ||
          dpc31::numbers::parse_whole(std::string_view(cos_shard).substr(0, slash), k) !=
              std::errc{} ||
          dpc31::numbers::parse_whole(std::string_view(cos_shard).substr(slash + 1), n) !=
              std::errc{} ||
          n == 0 || n > std::numeric_limits<unsigned>::max() || k < cos_shard_base ||
          k - cos_shard_base >= n) {
        fmt::print(stderr, "dpc31 cosim: --shard must be K/N with {} <= K <= N{}, not '{}'\n",
                   cos_shard_base, cos_shard_base == 0 ? " - 1" : "", cos_shard);
        return 2;
      }
      cos.shard = k + 1 - cos_shard_base;
      cos.shards = n;
      return dpc31::cli::run_cosim(cos);
    }
    if (demo->parsed()) {
      dpc31::ChipOptions opt;
      opt.profile = to_profile(demo_profile);
      opt.bus = demo_bus == "intel" ? dpc31::BusMode::intel : dpc31::BusMode::motorola;
      if (std::string why = dpc31::cli::apply_chip_choice(demo_chip, opt); !why.empty()) {
        return refuse(why);
      }
      return dpc31::cli::run_demo(opt, demo_out, demo_firmware, demo_timescale, stdout);
    }
    if (regs->parsed()) {
      std::vector<const dpc31::ProfileDesc*> sel;
      for (dpc31::Profile p : dpc31::kAllProfiles) {
        if (regs_profile == "all" || dpc31::profile_desc(p).name == regs_profile) {
          sel.push_back(&dpc31::profile_desc(p));
        }
      }
      if (sel.size() != 1 && (regs_format == "text" || regs_format == "json")) {
        fmt::print(stderr, "dpc31 regs: --format {} needs one profile, not all\n", regs_format);
        return 2;
      }
      namespace rf = dpc31::regfmt;
      std::string out;
      if (regs_format == "text") out = rf::emit_text(*sel[0]);
      if (regs_format == "json") out = rf::emit_json(*sel[0]);
      if (regs_format == "c") out = rf::emit_c_header(sel);
      if (regs_format == "verilog") out = rf::emit_verilog(sel);
      if (regs_format == "markdown") out = rf::emit_markdown(sel);
      std::fwrite(out.data(), 1, out.size(), stdout);
      return 0;
    }
    return 2;
  };
  int rc = 2;
  try {
    rc = dispatch();
  } catch (const std::exception& e) {
    // fmt::print throws when a write fails: once the buffer of a long output went to a full
    // standard output, that is what failed, not "cannot write to file".
    if (std::ferror(stdout) != 0) return stdout_failed();
    // Nothing else is meant to get here; if something does, it is one line, not std::terminate's.
    return refuse(e.what());
  }
  // A command that ended with exit 2 has said why in its one line (the bridge: its log on the
  // standard output failed): none is added.
  if ((std::fflush(stdout) != 0 || std::ferror(stdout) != 0) && rc != 2) return stdout_failed();
  return rc;
}

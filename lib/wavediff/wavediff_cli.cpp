#include "wavediff_cli.hpp"

#include <fmt/core.h>

#include <limits>

#include "numbers.hpp"
#include "path_option.hpp"

namespace dpc31::wavediff {

CLI::App* add_subcommand(CLI::App& app, CliArgs& a) {
  Options& o = a.opt;
  auto* c = app.add_subcommand(
      "wavediff", "compare two waveforms (VCD or FST) by signal name; exit 0 same, 1 different");
  c->add_option("A", o.file_a, "first waveform (VCD or FST)")
      ->required()
      ->transform(outfile::named(outfile::Use::read));
  c->add_option("B", o.file_b, "second waveform (VCD or FST)")
      ->required()
      ->transform(outfile::named(outfile::Use::read));
  c->add_option("--strip-a", o.strip_a, "remove this top scope from A's names (e.g. TOP.tb)");
  c->add_option("--strip-b", o.strip_b, "remove this top scope from B's names");
  c->add_option("--strip", a.strip, "auto: strip the common top scopes that match most names")
      ->check(CLI::IsMember({"auto"}));
  c->add_option("--map", o.map_file, "renames: lines 'nameA = nameB', '#' comments")
      ->transform(outfile::named(outfile::Use::read));
  auto* clock = c->add_option("--clock", o.clock_a,
                              "clock-sampled mode: sample at the edges of this A signal");
  c->add_option("--clock-b", o.clock_b, "the clock in B (default: the B signal matched to --clock)")
      ->needs(clock);
  c->add_option("--edge", a.edge, "clock edges sampled")
      ->check(CLI::IsMember({"rising", "falling", "both"}))
      ->needs(clock);  // event mode has no edges: it was an event-mode run without a word
  c->add_option("--start", a.start, "compare from this time (100ns, 2us) or cycle (c123)");
  c->add_option("--end", a.end, "compare up to this time or cycle (inclusive)");
  c->add_option("--tolerance", a.tolerance,
                "event mode: ignore differences that last at most this long (5ns)");
  // NonNegativeNumber: CLI11 would read "-1" into an unsigned as 2^64 - 1.
  c->add_option("--tolerance-cycles", o.tolerance_cycles,
                "clock mode: ignore differences that last at most N cycles")
      ->transform(numbers::whole(0))
      ->needs(clock);
  c->add_option("--xz", a.xz,
                "X/Z policy: strict (must match), wildcard (matches anything), "
                "zero (read as 0)")
      ->check(CLI::IsMember({"strict", "wildcard", "zero"}));
  // One glob a time: more took A and B after it (repeat the option instead).
  c->add_option("--include", o.include, "compare only names matching this glob (* ?); repeatable")
      ->allow_extra_args(false);
  c->add_option("--exclude", o.exclude, "do not compare names matching this glob; repeatable")
      ->allow_extra_args(false);
  c->add_flag("--ignore-missing", o.ignore_missing,
              "signals on one side only are listed but are not a difference");
  c->add_option("--json", o.json_file, "write the report as JSON to this file")
      ->transform(outfile::named(outfile::Use::write));
  c->add_option("--diff-vcd", o.diff_vcd,
                "write a VCD with scopes a/, b/ and diff/ (1 = values differ) for GTKWave")
      ->transform(outfile::named(outfile::Use::write));
  c->add_option("--merge", o.merge,
                "write A's and B's signals (scopes a, b) with a diff signal for each, as one "
                "VCD or FST (by the extension) and a GTKWave save file beside it (.gtkw)")
      ->transform(outfile::named(outfile::Use::write));
  auto* wavedrom = c->add_option("--wavedrom", o.wavedrom,
                                 "write WaveJSON of the window around the first divergence")
                       ->transform(outfile::named(outfile::Use::write));
  c->add_option("--wavedrom-window", o.wavedrom_window,
                "events or cycles shown before and after the first divergence (default 8)")
      ->transform(numbers::whole(1, 1000))
      ->needs(wavedrom);
  c->add_option("--max-signals", o.max_signals, "signals listed in the text report (default 20)")
      ->transform(numbers::whole(0, std::numeric_limits<unsigned>::max()));
  return c;
}

int run_cli(CliArgs a, std::FILE* out, std::FILE* err) {
  Options& o = a.opt;
  auto bad = [&](const std::string& what) {
    fmt::print(err, "dpc31 wavediff: {}\n", what);
    return 2;
  };
  o.strip_auto = a.strip == "auto";
  o.xz = a.xz == "wildcard" ? XzPolicy::wildcard
         : a.xz == "zero"   ? XzPolicy::zero
                            : XzPolicy::strict;
  o.edge = a.edge == "falling" ? Edge::falling : a.edge == "both" ? Edge::both : Edge::rising;
  if (const std::string why = take_window(a.start, a.end, a.tolerance, o); !why.empty())
    return bad(why);
  std::string text;
  std::string errors;
  const int rc = run(o, text, errors);
  std::fputs(text.c_str(), out);
  std::fputs(errors.c_str(), err);
  return rc;
}

}  // namespace dpc31::wavediff

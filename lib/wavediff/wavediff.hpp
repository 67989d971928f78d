// dpc31 wavediff: compares two waveforms (VCD or FST, in any mix) signal by signal, in event mode
// (every time either side changes) or clock-sampled mode (edge N of A against edge N of B).
// docs/wavediff.md describes the options, the report and the decisions (sampling point, streaming
// bound, diff-VCD layout).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "wave_reader.hpp"

namespace dpc31::wavediff {

enum class XzPolicy { strict, wildcard, zero };
enum class Edge { rising, falling, both };

// A --start/--end value: a time in femtoseconds, or a cycle number ("c123", clock mode).
struct Bound {
  bool cycles = false;
  std::uint64_t value = 0;
};
// "100ns", "2us", "1.5ns", "0", "c12". False with a reason if malformed.
bool parse_bound(std::string_view text, Bound& out, std::string& error);
// A duration in femtoseconds: "5ns", "250ps", "0".
bool parse_duration(std::string_view text, std::uint64_t& fs, std::string& error);

struct Options {
  std::string file_a;
  std::string file_b;
  std::string strip_a;  // top scope(s) removed from A's names, e.g. "TOP" or "tb.dut"
  std::string strip_b;
  bool strip_auto = false;  // choose the strip depths that match the most names
  std::string map_file;     // lines "nameA = nameB", '#' comments
  std::string clock_a;      // clock-sampled mode when set
  std::string clock_b;      // default: the B signal matched to clock_a
  Edge edge = Edge::rising;
  std::optional<Bound> start;
  std::optional<Bound> end;
  std::uint64_t tolerance_fs = 0;      // event mode
  std::uint64_t tolerance_cycles = 0;  // clock mode
  XzPolicy xz = XzPolicy::strict;
  std::vector<std::string> include;  // globs (* and ?) on the matched names
  std::vector<std::string> exclude;
  bool ignore_missing = false;
  std::string json_file;
  std::string diff_vcd;
  std::string merge;  // --merge OUT.vcd|OUT.fst, and its GTKWave save file OUT.gtkw
  std::string wavedrom;
  unsigned wavedrom_window = 8;  // events or cycles on each side of the first divergence
  unsigned max_signals = 20;     // signals listed in the text report (JSON lists all)
  // Event mode: where both files' bytes agree and every value does, B's steps are taken from A's
  // instead of parsed and compared (docs/wavediff.md, "Equal stretches"). The same report either
  // way; off: the reference path (the tests compare the two).
  bool follow_equal_bytes = true;
};

// Where something was seen. Event mode: `time` in the common unit. Clock mode: `cycle` (the edge
// index, from 0) and the edge's time on each side (common unit), and in each file's own units
// (the "#" of the file: a finer file's edge is not rounded there).
struct Point {
  std::uint64_t time = 0;  // A's time (event mode: the time of both)
  std::uint64_t time_b = 0;
  std::uint64_t cycle = 0;
  std::uint64_t own_a = 0;  // clock mode only
  std::uint64_t own_b = 0;
};

struct Divergence {
  Point at;
  std::string a;  // values: bits MSB first ("0101", "x"), reals as numbers ("1.5", "x" unknown)
  std::string b;
  std::optional<std::string> last_common;  // the last value both sides agreed on, if any
  bool open = false;                       // still different at the end of the comparison
};

struct SignalDiff {
  std::string name;         // matched name (A's, after strip)
  std::string name_b;       // B's name (after strip, before --map)
  std::uint64_t count = 0;  // divergences (separate stretches of difference)
  Divergence first;
  Point last;  // start of the last divergence
};

struct Structural {
  std::string signal;
  std::string what;
};

struct Report {
  bool clock_mode = false;
  std::string file_a;
  std::string file_b;
  std::string format_a;
  std::string format_b;
  int pow_a = 0;  // timescales, powers of ten of femtoseconds
  int pow_b = 0;
  int pow = 0;  // the common unit (the coarser of the two)
  std::string clock_a;
  std::string clock_b;
  Edge edge = Edge::rising;
  std::uint64_t edges = 0;  // clock edges compared (clock mode)
  std::size_t compared = 0;
  std::vector<std::string> only_a;
  std::vector<std::string> only_b;
  std::vector<Structural> structural;
  std::vector<SignalDiff> diffs;  // ordered by first divergence
  std::vector<std::string> warnings;
  bool ignore_missing = false;
  // Time steps B took from A where both files' bytes agreed (Options::follow_equal_bytes); not
  // in the text or JSON report.
  std::uint64_t followed = 0;

  [[nodiscard]] bool same() const {
    return diffs.empty() && structural.empty() &&
           (ignore_missing || (only_a.empty() && only_b.empty()));
  }
};

// --start, --end ("100ns", "c12") and --tolerance ("5ns") as typed, "" for none, into `o`: "" or
// what is wrong ("--start: ..."), in the CLI's words for every door.
std::string take_window(std::string_view start, std::string_view end, std::string_view tolerance,
                        Options& o);

// Runs the comparison and writes --diff-vcd and --wavedrom files. Throws InputError (also where
// an output, --json's too, names an input).
Report compare(const Options& o);

// Text and JSON forms of a report.
std::string text_report(const Report& r, unsigned max_signals);
std::string json_report(const Report& r);
// Time in the common unit as text ("1500ps"), and in a file's own units ("1.5").
std::string time_text(std::uint64_t t, int pow);
std::string file_time(std::uint64_t t, int pow, int file_pow);
// The VCD identifier code of the i-th variable: printable ASCII '!'..'~', base 94, least
// significant digit first (what our writers emit; any reader takes any code).
std::string vcd_id(std::size_t i);
// A value of 0/1 digits as hex digits (the leading group is the short one: "101110001" -> "171");
// empty when it holds x, z or other characters.
std::string bits_hex(std::string_view bits);

// --merge's GTKWave save file: the merged file's name with the extension .gtkw.
std::string save_file_name(const std::string& merge);

// The whole command: compare, print the text report to `out` (errors and warnings to `err`),
// write --json. Exit code 0 same, 1 different, 2 bad input.
int run(const Options& o, std::string& out, std::string& err);

const char* edge_name(Edge e);

// Glob with * and ? only (brackets are literal, as in "x[3]").
bool glob_match(std::string_view pattern, std::string_view s);

}  // namespace dpc31::wavediff

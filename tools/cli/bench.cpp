#include "bench.hpp"

#include <fmt/core.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "child.hpp"
#include "cleanup.hpp"
#include "numbers.hpp"
#include "outfile.hpp"
#include "path_option.hpp"

namespace dpc31::cli {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// report: a breakdown shown beside a row, with no target of its own.
enum class Goal : std::uint8_t { at_most, below, at_least, report };

// One row of the table: which benchmark, which of its values, and the target.
struct RowSpec {
  const char* item;
  const char* what;
  const char* benchmark;  // name as registered, without the /real_time... suffixes
  const char* metric;     // a counter, or "time" (real time per iteration)
  double scale;           // metric (time: in seconds) x scale = the value in `unit`
  const char* unit;
  Goal goal;
  double target;
};

constexpr const char* kSetupSh = "setup.sh";  // row h's "benchmark"

// Every row, grouped by item (one dpc31_bench run per item); targets of issue 19.
const std::vector<RowSpec>& rows() {
  static const std::vector<RowSpec> r = {
      {"a", "Chip::read, Int_Req_Reg (C++ API)", "BM_ReadRegister", "time", 1e9, "ns",
       Goal::at_most, 3},
      {"a", "Chip::write, Int_Mask_Reg (C++ API)", "BM_WriteRegister", "time", 1e9, "ns",
       Goal::at_most, 5},
      {"a", "dpc31_read (C HAL)", "BM_HalRead", "time", 1e9, "ns", Goal::at_most, 5},
      {"a", "dpc31_write (C HAL)", "BM_HalWrite", "time", 1e9, "ns", Goal::at_most, 5},
      {"a", "Vpc3Read (C HAL, selected chip)", "BM_Vpc3Read", "time", 1e9, "ns", Goal::at_most, 5},
      {"a", "Vpc3Write (C HAL, selected chip)", "BM_Vpc3Write", "time", 1e9, "ns", Goal::at_most,
       5},
      // Issue 19 item 2: the firmware's buffer copies as block transfers, and byte by byte.
      {"b", "Data_Exchange 12 Mbaud, 244 + 244 bytes, exact timing, block copies",
       "BM_DataExchange/baud:12000000/len:244/block:1", "x_realtime", 1, "x real time",
       Goal::at_least, 200},
      {"b'", "the same, firmware copying byte by byte",
       "BM_DataExchange/baud:12000000/len:244/block:0", "x_realtime", 1, "x real time",
       Goal::at_least, 25},
      {"c", "power-on, start-up and 100 Data_Exchange at 9.6 kbaud",
       "BM_StartupAndDataExchange/baud:9600/dx:100", "x_realtime", 1, "x real time", Goal::at_least,
       20'000},
      {"d", "DP watchdog, TWD = 650 s, expiring (wall time)", "BM_WatchdogExpiry650s", "time", 1e3,
       "ms", Goal::below, 10},
      {"e", "C++ blocks versus Verilated RTL, same stimulus", "BM_CppOverRtl", "cpp_over_rtl", 1,
       "x faster", Goal::at_least, 20},
      {"e", "lockstep (C++ blocks + RTL, compared every cycle)", "BM_Lockstep", "cycles_per_s",
       1e-6, "M cycles/s", Goal::at_least, 8},
      {"f", "dpc31 wavediff, two emulator VCD files (dpc31 run --vcd): throughput",
       "BM_WavediffEmulatorPair", "MB_per_s", 1, "MB/s", Goal::at_least, 1000},
      {"f", "dpc31 wavediff, two emulator VCD files: peak RSS", "BM_WavediffEmulatorPair",
       "peak_rss_MB", 1, "MB", Goal::below, 64},
      {"f", "dpc31 wavediff, two generated VCD files: throughput", "BM_WavediffLargePair",
       "MB_per_s", 1, "MB/s", Goal::at_least, 1000},
      {"f", "dpc31 wavediff, two generated VCD files: peak RSS", "BM_WavediffLargePair",
       "peak_rss_MB", 1, "MB", Goal::below, 64},
      {"g", "socket, `peek 0` pipelined (64 in flight) on one TCP connection",
       "BM_SocketPeekTcp/64", "items_per_second", 1, "/s", Goal::at_least, 2'000'000},
      {"g", "  of which the server's own CPU time per command", "BM_SocketPeekTcp/64",
       "server_ns_per_cmd", 1, "ns", Goal::report, 0},
      {"g", "socket round trips, `peek 0` over the Unix socket, one in flight",
       "BM_SocketPeekUnix/1", "items_per_second", 1, "/s", Goal::at_least, 100'000},
      {"g", "  of which the server's own CPU time per command", "BM_SocketPeekUnix/1",
       "server_ns_per_cmd", 1, "ns", Goal::report, 0},
      {"g", "  the rest: client, kernel and the wake-ups of both", "BM_SocketPeekUnix/1",
       "host_ns_per_cmd", 1, "ns", Goal::report, 0},
      {"g", "socket round trips, `peek 0` over TCP, one in flight", "BM_SocketPeekTcp/1",
       "items_per_second", 1, "/s", Goal::at_least, 100'000},
      {"g", "  of which the server's own CPU time per command", "BM_SocketPeekTcp/1",
       "server_ns_per_cmd", 1, "ns", Goal::report, 0},
      {"g", "  the rest: client, kernel and the wake-ups of both", "BM_SocketPeekTcp/1",
       "host_ns_per_cmd", 1, "ns", Goal::report, 0},
      // Issue 14, item 5: the scheduler's bound in wall time (docs/protocol.md, "Several
      // clients"; docs/performance.md).
      {"g", "`peek 0` round trip, p99, beside 13 clients pipelining", "BM_SocketFlood/13", "p99_us",
       1e-3, "ms", Goal::at_most, 5},
      // Issue 19, item 7: what a full waveform costs (docs/performance.md, docs/waveforms.md).
      {"i", "traced / untraced run, all signals (wall time, side by side)", "BM_TracedOverUntraced",
       "traced_over_untraced", 1, "x slower", Goal::at_most, 3},
      // Issue 34 item 6: the 80C32 core alone (docs/cpu.md).
      {"j", "80C32 core alone at 24 MHz (ALU, MOVX, MUL loop, timers 0 and 1 running)",
       "BM_Mcs51Core", "x_realtime", 1, "x real time", Goal::at_least, 100},
      // Issue 28: MSAC_C1 Reads of a 240-byte record, request and polls (docs/dpv1.md).
      {"k", "1 000 MSAC_C1 Reads of 240 bytes at 12 Mbaud (VPC3+, polled)", "BM_Dpv1Read",
       "x_realtime", 1, "x real time", Goal::at_least, 10},
      // Issue 30 (row l): one DP cycle over a segment of 1..32 slaves (docs/segment.md); the curve
      // of cost against stations is in docs/performance.md.
      {"l", "segment: one DP cycle, 1 slave x (8 + 8 bytes), 1.5 Mbaud",
       "BM_SegmentDpCycle/baud:1500000/slaves:1", "x_realtime", 1, "x real time", Goal::report, 0},
      {"l", "  2 slaves, 1.5 Mbaud", "BM_SegmentDpCycle/baud:1500000/slaves:2", "x_realtime", 1,
       "x real time", Goal::report, 0},
      {"l", "  4 slaves, 1.5 Mbaud", "BM_SegmentDpCycle/baud:1500000/slaves:4", "x_realtime", 1,
       "x real time", Goal::report, 0},
      {"l", "  8 slaves, 1.5 Mbaud", "BM_SegmentDpCycle/baud:1500000/slaves:8", "x_realtime", 1,
       "x real time", Goal::report, 0},
      {"l", "  16 slaves, 1.5 Mbaud", "BM_SegmentDpCycle/baud:1500000/slaves:16", "x_realtime", 1,
       "x real time", Goal::report, 0},
      {"l", "  32 slaves, 1.5 Mbaud", "BM_SegmentDpCycle/baud:1500000/slaves:32", "x_realtime", 1,
       "x real time", Goal::at_least, 100},
      {"l", "  1 slave, 12 Mbaud", "BM_SegmentDpCycle/baud:12000000/slaves:1", "x_realtime", 1,
       "x real time", Goal::report, 0},
      {"l", "  2 slaves, 12 Mbaud", "BM_SegmentDpCycle/baud:12000000/slaves:2", "x_realtime", 1,
       "x real time", Goal::report, 0},
      {"l", "  4 slaves, 12 Mbaud", "BM_SegmentDpCycle/baud:12000000/slaves:4", "x_realtime", 1,
       "x real time", Goal::report, 0},
      {"l", "  8 slaves, 12 Mbaud", "BM_SegmentDpCycle/baud:12000000/slaves:8", "x_realtime", 1,
       "x real time", Goal::report, 0},
      {"l", "  16 slaves, 12 Mbaud", "BM_SegmentDpCycle/baud:12000000/slaves:16", "x_realtime", 1,
       "x real time", Goal::report, 0},
      {"l", "  32 slaves, 12 Mbaud", "BM_SegmentDpCycle/baud:12000000/slaves:32", "x_realtime", 1,
       "x real time", Goal::at_least, 20},
      // Issue 34 item 6 (row m): a whole DO4 session on the 80C32 (docs/cpu.md).
      {"m", "DO4 on the 80C32 at 24 MHz, SPC3 at 1.5 Mbaud: start-up, 2 000 Data_Exchange, OSP",
       "BM_Do4Cpu51Session", "x_realtime", 1, "x real time", Goal::at_least, 20},
      // Issue 19 item 6: not a benchmark but a timed build (--build), after the benchmarks.
      {"h", "fresh build: ./setup.sh with every package present, ccache off (wall time)", kSetupSh,
       "time", 1.0 / 60, "min", Goal::at_most, 5},
  };
  return r;
}

// 3 significant digits, whole numbers from 100 on with thin groups of three ("10 000").
std::string number(double v) {
  if (std::fabs(v) < 100) return fmt::format("{:.3g}", v);
  std::string digits = fmt::format("{:.0f}", v);
  std::string out;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ' ';
    out += digits[i];
  }
  return out;
}

std::string with_unit(double v, const char* unit) {
  const std::string u = unit;
  if (u.rfind("x ", 0) == 0) return number(v) + "×" + u.substr(1);  // "200× real time"
  if (u == "/s") return number(v) + "/s";
  return number(v) + " " + u;
}

double seconds_per_unit(const std::string& time_unit) {
  if (time_unit == "ns") return 1e-9;
  if (time_unit == "us") return 1e-6;
  if (time_unit == "ms") return 1e-3;
  return 1;
}

// The benchmark's entry in Google Benchmark's JSON output: the median of its repetitions if it
// was repeated, else its only run. Runs are named by the benchmark's name, or that followed by
// "/real_time" and the like.
const json* find_entry(const json& out, const std::string& name) {
  if (!out.contains("benchmarks")) return nullptr;
  const json* found = nullptr;
  for (const json& b : out["benchmarks"]) {
    const std::string n = b.value("run_name", b.value("name", ""));
    if (n != name && (n.size() <= name.size() || n.compare(0, name.size(), name) != 0 ||
                      n[name.size()] != '/')) {
      continue;
    }
    const std::string aggregate = b.value("aggregate_name", "");
    if (aggregate == "median") return &b;
    if (aggregate.empty() && found == nullptr) found = &b;
  }
  return found;
}

struct Row {
  const RowSpec* spec = nullptr;
  bool measured = false;
  double value = 0;
  std::string error;
  std::string not_run;  // why a row was not asked for (row h without --build)
  [[nodiscard]] bool met() const {
    switch (spec->goal) {
      case Goal::at_most:
        return value <= spec->target;
      case Goal::below:
        return value < spec->target;
      case Goal::at_least:
        return value >= spec->target;
      case Goal::report:
        return true;
    }
    return false;
  }
  // How far from the target: measured / target for upper bounds, target / measured for lower
  // ones; above 1 means missed by that factor, below 1 the margin is its inverse.
  [[nodiscard]] double ratio() const {
    if (spec->goal == Goal::at_least) return value > 0 ? spec->target / value : INFINITY;
    return value / spec->target;
  }
  [[nodiscard]] std::string target_text() const {
    if (spec->goal == Goal::report) return "—";
    const char* rel = spec->goal == Goal::at_least ? "≥ " : spec->goal == Goal::below ? "< " : "≤ ";
    return rel + with_unit(spec->target, spec->unit);
  }
  [[nodiscard]] std::string result_text() const {
    if (!not_run.empty()) return "not run: " + not_run;
    if (!measured) return "not measured";
    if (spec->goal == Goal::report) return "reported";
    const double r = ratio();
    if (met()) return r > 0 ? fmt::format("met ({}× margin)", number(1 / r)) : "met";
    return fmt::format("missed by {}×", number(r));
  }
};

void fill(Row& row, const json& out, const std::string& run_error) {
  if (!run_error.empty()) {
    row.error = run_error;
    return;
  }
  const json* e = find_entry(out, row.spec->benchmark);
  if (e == nullptr) {
    row.error = std::string(row.spec->benchmark) + " is not in dpc31_bench's output";
    return;
  }
  if (e->value("error_occurred", false)) {
    row.error = e->value("error_message", std::string("error"));
    return;
  }
  const std::string metric = row.spec->metric;
  if (metric == "time") {
    row.value = e->value("real_time", 0.0) * seconds_per_unit(e->value("time_unit", "ns")) *
                row.spec->scale;
  } else if (e->contains(metric) && (*e)[metric].is_number()) {
    row.value = (*e)[metric].get<double>() * row.spec->scale;
  } else {
    row.error = std::string(row.spec->benchmark) + " has no value " + metric;
    return;
  }
  row.measured = true;
}

fs::path self_path() {
  std::error_code ec;
  fs::path p = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path("dpc31") : p;
}

// ": " and the last non-empty line of a child's log (empty if it has none): the reason it failed.
std::string last_line_of(const fs::path& log_file) {
  std::ifstream log(log_file);
  std::string line;
  std::string last;
  while (std::getline(log, line)) {
    if (!line.empty()) last = line;
  }
  return last.empty() ? std::string() : ": " + last;
}

// Runs dpc31_bench on the benchmarks of one item; its JSON output, or an error.
// Its console output goes to `log_file`; the last lines of it are in `error` if it fails. Its
// TMPDIR is `scratch` (everything it writes there goes with that tree), item f's files go to
// `wavediff_dir`.
json run_item(const BenchArgs& a, const std::string& bench, const std::vector<Row*>& item_rows,
              const fs::path& scratch, const fs::path& wavediff_dir, const fs::path& out_file,
              const fs::path& log_file, std::string& error) {
  std::vector<std::string> names;  // each benchmark once, though several rows read it
  for (const Row* r : item_rows) {
    if (std::find(names.begin(), names.end(), r->spec->benchmark) == names.end()) {
      names.emplace_back(r->spec->benchmark);
    }
  }
  const std::string filter = fmt::format("^({})(/|$)", fmt::join(names, "|"));
  const dpc31::child::Result r = dpc31::child::run(
      {"/usr/bin/env", "TMPDIR=" + scratch.string(), bench, "--benchmark_filter=" + filter,
       "--benchmark_min_time=" + fmt::format("{}", a.min_time),
       "--benchmark_repetitions=" + std::to_string(a.repetitions),
       "--benchmark_out=" + out_file.string(), "--benchmark_out_format=json",
       "--dpc31_cli=" + self_path().string(), "--wavediff_mb=" + std::to_string(a.wavediff_mb),
       "--wavediff_dir=" + wavediff_dir.string(),
       std::string("--dpc31_item=") + item_rows.front()->spec->item},
      log_file.string());
  if (r.exit_code != 0) {
    error = r.error.empty() ? fmt::format("dpc31_bench exited with {}", r.exit_code) : r.error;
    error += last_line_of(log_file);
    return {};
  }
  std::ifstream f(out_file);
  json j = json::parse(f, nullptr, false);
  if (j.is_discarded()) error = "dpc31_bench wrote no readable JSON";
  return j;
}

// A new private directory in `parent` (TMPDIR if empty) named `prefix`XXXXXX
// (outfile::make_temp_dir), registered to be removed with everything in it if a signal ends the
// process; empty, with a line on `err`, if it cannot be made.
std::string scratch_dir(const std::string& parent, const std::string& prefix,
                        cleanup::Entry& registered, std::FILE* err) {
  std::string error;
  std::string dir = outfile::make_temp_dir(prefix, error, parent);
  if (dir.empty()) {
    fmt::print(err, "dpc31 bench: {}\n", error);
    return {};
  }
  registered = cleanup::Entry::tree(dir);
  return dir;
}

std::string table(const std::vector<Row>& rs) {
  std::string t = "| item | what | measured | target | result |\n|---|---|---|---|---|\n";
  for (const Row& r : rs) {
    t += fmt::format("| {} | {} | {} | {} | {} |\n", r.spec->item, r.spec->what,
                     r.measured          ? with_unit(r.value, r.spec->unit)
                     : r.not_run.empty() ? "error: " + r.error
                                         : std::string("—"),
                     r.target_text(), r.result_text());
  }
  return t;
}

json to_json(const BenchArgs& a, const std::string& bench, const std::vector<Row>& rs,
             const json& context) {
  json j = {{"dpc31_bench", bench},         {"quick", a.quick},   {"min_time_s", a.min_time},
            {"wavediff_mb", a.wavediff_mb}, {"context", context}, {"rows", json::array()}};
  for (const Row& r : rs) {
    json row = {{"item", r.spec->item},
                {"what", r.spec->what},
                {"benchmark", r.spec->benchmark},
                {"metric", r.spec->metric},
                {"unit", r.spec->unit},
                {"goal", r.spec->goal == Goal::at_least ? ">="
                         : r.spec->goal == Goal::below  ? "<"
                         : r.spec->goal == Goal::report ? "report"
                                                        : "<="},
                {"measured", r.measured}};
    if (r.spec->goal != Goal::report) row["target"] = r.spec->target;
    if (r.measured && r.spec->goal == Goal::report) {
      row["value"] = r.value;
    } else if (r.measured) {
      row["value"] = r.value;
      row["met"] = r.met();
      row["ratio_to_target"] = r.ratio();
    } else if (!r.not_run.empty()) {
      row["not_run"] = r.not_run;
    } else {
      row["error"] = r.error;
    }
    j["rows"].push_back(std::move(row));
  }
  return j;
}

// Row h: `source`/setup.sh into a fresh directory of TMPDIR with ccache off (docs/install.md,
// "Build time"), its wall time; the directory is removed afterwards, also when a signal ends the
// run (setup.sh and what it started have ended by then: util/child). setup.sh's output goes to a
// log whose last line is the error.
void time_build(const std::string& source, Row& row, std::FILE* err) {
  cleanup::Entry registered;
  const std::string dir = scratch_dir({}, "dpc31-bench-build-", registered, err);
  if (dir.empty()) {
    row.error = "cannot create the build directory";
    return;
  }
  fmt::print(err, "dpc31 bench: item h: ./setup.sh of {} into {} ...\n", source, dir);
  std::fflush(err);
  child::stop_point("dpc31 bench item h");
  const fs::path log = fs::path(dir) / "setup.log";
  const auto t0 = std::chrono::steady_clock::now();
  const dpc31::child::Result r = dpc31::child::run(
      {"/usr/bin/env", "CCACHE_DISABLE=1", "DPC31_BUILD_DIR=" + (fs::path(dir) / "build").string(),
       (fs::path(source) / "setup.sh").string()},
      log.string());
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (r.exit_code != 0) {
    row.error = r.error.empty() ? fmt::format("setup.sh exited with {}", r.exit_code) : r.error;
    row.error += last_line_of(log);
  } else {
    row.value = seconds * row.spec->scale;
    row.measured = true;
  }
  std::error_code ec;
  fs::remove_all(dir, ec);
}

}  // namespace

CLI::App* add_bench_subcommand(CLI::App& app, BenchArgs& a) {
  auto* cmd = app.add_subcommand(
      "bench", "run the benchmarks of bench/ and print one table against the targets");
  auto* quick = cmd->add_flag("--quick", a.quick,
                              "one short run each and 8 MB wavediff files (a smoke test)");
  cmd->add_option("--json", a.json, "also write the table as JSON to this file")
      ->transform(outfile::named(outfile::Use::write));
  cmd->add_option("--min-time", a.min_time, "seconds per benchmark (default 0.5)")
      ->check(numbers::real(0.001, 3600.0))
      ->excludes(quick);
  cmd->add_option("--wavediff-mb", a.wavediff_mb,
                  "MB of each of item f's two generated VCD files (default 1000)")
      ->transform(numbers::whole(1, 1'000'000))
      ->excludes(quick);
  cmd->add_option("--repetitions", a.repetitions,
                  "runs of each benchmark; the table shows the median (default 3)")
      ->transform(numbers::whole(1, 100))
      ->excludes(quick);
  cmd->add_option("--wavediff-dir", a.wavediff_dir,
                  "where item f's files go (default: TMPDIR; needs twice --wavediff-mb)")
      ->transform(outfile::named(outfile::Use::place))
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--build", a.build_source,
                  "row h: time a fresh ./setup.sh build of this source tree (about 5 minutes on "
                  "two cores; every package must be installed). This runs SOURCE_DIR/setup.sh, "
                  "a shell script, with your rights: as root it apt-get installs any package it "
                  "lists that is missing. Name only a tree you trust")
      ->transform(outfile::named(outfile::Use::read))
      ->check(CLI::ExistingDirectory &
              CLI::Validator(
                  [](const std::string& d) {
                    return std::filesystem::exists(std::filesystem::path(d) / "setup.sh")
                               ? std::string()
                               : d + " has no setup.sh";
                  },
                  "SOURCE_DIR"))
      ->excludes(quick);
  cmd->add_option("--items", a.items, "only these items, e.g. --items f,g (default: all)")
      ->delimiter(',')
      ->check(CLI::Validator(
          [](const std::string& item) {
            for (const RowSpec& s : rows()) {
              if (item == s.item) return std::string();
            }
            return "no item '" + item + "' (the table's first column)";
          },
          "ITEM"));
  cmd->add_option("--bench", a.bench_binary,
                  "the dpc31_bench program (default: next to this dpc31)")
      ->transform(outfile::named(outfile::Use::read))
      ->check(CLI::ExistingFile);
  // An item's options beside an --items that leaves it out act on nothing: refused, not dropped.
  cmd->callback([cmd, &a] {
    for (const auto& [name, item] : {std::pair{"--wavediff-mb", "f"},
                                     std::pair{"--wavediff-dir", "f"}, std::pair{"--build", "h"}}) {
      if (cmd->count(name) > 0 && !a.items.empty() &&
          std::find(a.items.begin(), a.items.end(), item) == a.items.end()) {
        throw CLI::ValidationError(
            fmt::format("{} is for item {}, which --items leaves out", name, item));
      }
    }
  });
  return cmd;
}

int run_bench(const BenchArgs& args, std::FILE* out, std::FILE* err) {
  BenchArgs a = args;
  if (a.quick) {
    a.min_time = 0.01;
    a.wavediff_mb = 8;
    a.repetitions = 1;
  }
  const std::string bench = a.bench_binary.empty()
                                ? (self_path().parent_path() / "dpc31_bench").string()
                                : a.bench_binary;
  if (::access(bench.c_str(), X_OK) != 0) {
    fmt::print(err, "dpc31 bench: {} is not there (build the dpc31_bench target, or --bench)\n",
               bench);
    return 2;
  }
  // Checked and opened before the minutes of measuring, so that a bad path is one line up front.
  if (const std::string same = outfile::distinct({{"--bench", bench}}, {{"--json", a.json}});
      !same.empty()) {
    fmt::print(err, "dpc31 bench: {}\n", same);
    return 2;
  }
  outfile::OutFile json_out;
  if (!a.json.empty() && !json_out.open(a.json)) {
    fmt::print(err, "dpc31 bench: {}\n", json_out.error());
    return 2;
  }
  std::vector<Row> rs;
  for (const RowSpec& s : rows()) {
    Row r;
    r.spec = &s;
    rs.push_back(r);
  }
  // dpc31_bench's output, log and TMPDIR: a private directory (a fixed name in TMPDIR could be a
  // link another user made), removed with all in it when the run ends, also by a signal; item f's
  // files in it too, or in one of --wavediff-dir.
  cleanup::Entry gone;
  const std::string dir = scratch_dir({}, "dpc31-bench-", gone, err);
  if (dir.empty()) return 2;
  cleanup::Entry wavediff_gone;
  const std::string wavediff_dir =
      a.wavediff_dir.empty() ? dir
                             : scratch_dir(a.wavediff_dir, "dpc31-bench-", wavediff_gone, err);
  if (wavediff_dir.empty()) {
    std::error_code ec;
    fs::remove_all(dir, ec);
    return 2;
  }
  const fs::path out_file = fs::path(dir) / "bench.json";
  const fs::path log_file = fs::path(dir) / "bench.log";
  json context;
  for (std::size_t i = 0; i < rs.size();) {
    std::vector<Row*> item;
    for (std::size_t k = i; k < rs.size() && std::string(rs[k].spec->item) == rs[i].spec->item;
         ++k) {
      item.push_back(&rs[k]);
    }
    const std::string name = item.front()->spec->item;
    i += item.size();
    if (!a.items.empty() && std::find(a.items.begin(), a.items.end(), name) == a.items.end()) {
      for (Row* r : item) r->not_run = "not in --items";
      continue;
    }
    if (item.front()->spec->benchmark == kSetupSh) {
      if (a.build_source.empty()) {
        item.front()->not_run = "dpc31 bench --build SOURCE_DIR (about 5 minutes)";
      } else {
        time_build(a.build_source, *item.front(), err);
      }
      continue;
    }
    fmt::print(err, "dpc31 bench: item {} ...\n", name);
    std::fflush(err);
    child::stop_point("dpc31 bench item " + name);
    std::string error;
    const json j = run_item(a, bench, item, dir, wavediff_dir, out_file, log_file, error);
    if (context.is_null() && j.contains("context")) context = j["context"];
    for (Row* r : item) fill(*r, j, error);
  }
  std::error_code ec;
  fs::remove_all(dir, ec);
  fs::remove_all(wavediff_dir, ec);
  fmt::print(out, "{}", table(rs));
  if (!a.json.empty()) {
    if (!json_out.write(to_json(a, bench, rs, context).dump(2) + "\n") || !json_out.commit()) {
      fmt::print(err, "dpc31 bench: {}\n", json_out.error());
      return 2;
    }
  }
  for (const Row& r : rs) {
    if (!r.measured && r.not_run.empty()) return 1;
  }
  return 0;
}

}  // namespace dpc31::cli

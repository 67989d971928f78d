// The `dpc31 bench` subcommand: runs dpc31_bench (bench/) once per item of issue 7 as a child
// process with JSON output, and prints one table: item, what, measured, target, met or missed
// (by how much). docs/performance.md shows the table and how to reproduce it.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace dpc31::cli {

struct BenchArgs {
  bool quick = false;     // short minimum time and small wavediff files: a smoke test
  std::string json;       // also write the rows as JSON here (temporary file + rename)
  double min_time = 0.5;  // seconds per benchmark (Google Benchmark's --benchmark_min_time)
  int repetitions = 3;    // runs of each benchmark; the table shows the median
  std::uint64_t wavediff_mb = 1000;  // size of each of item f's two VCD files
  std::string wavediff_dir;          // where item f's files go (default: TMPDIR)
  std::string bench_binary;          // default: dpc31_bench next to this dpc31
  std::string build_source;  // row h: time a fresh ./setup.sh build of this tree (empty: not run)
  std::vector<std::string> items;  // --items: only these items (empty: all)
};

CLI::App* add_bench_subcommand(CLI::App& app, BenchArgs& a);

// Exit code: 0 every row measured (met or missed) or not asked for (row h without
// --build), 1 a benchmark or the build could not be run or gave no value, 2 bad input (one line
// on `err`).
int run_bench(const BenchArgs& a, std::FILE* out, std::FILE* err);

}  // namespace dpc31::cli

// Options of dpc31_bench beyond Google Benchmark's own (bench_main.cpp parses them).
#pragma once

#include <cstdint>
#include <string>

namespace dpc31::bench {

struct Options {
  std::string dpc31_cli;             // --dpc31_cli=PATH: the dpc31 binary wavediff runs
  std::uint64_t wavediff_mb = 1000;  // --wavediff_mb=N: size of each of the two VCD files
  std::string wavediff_dir;          // --wavediff_dir=DIR: where they go (default: TMPDIR)
  std::string item;                  // --dpc31_item=X: the item of `dpc31 bench` this run is for
};

Options& options();

// The phase of a benchmark with all its files made (and its children started): a test can stop
// the run here, at "dpc31_bench item X files" (util/child's stop_point; the first one reached).
void files_made();

}  // namespace dpc31::bench

#pragma once

#include <cstdio>
#include <string>

namespace dpc31::cli {

struct RunOptions {
  std::string scenario;  // path of the .scn file
  bool quiet = false;    // no state walk; failures are still reported
  std::string json;      // write a JSON summary here ("" = none)
  std::string record;    // write a golden trace of the run here ("" = none, docs/trace-format.md)
};

// `dpc31 run`: plays a scenario file (docs/scenario-format.md), printing the state walk to `out`
// and failures to `err`. Returns the exit code: 0 every expect held, 1 one failed, 2 bad input.
// With `record`, the run is also written as a trace (for exit codes 0 and 1).
int run_scenario_command(const RunOptions& opt, std::FILE* out, std::FILE* err);

}  // namespace dpc31::cli

#pragma once

#include <cstdio>
#include <string>

namespace dpc31::cli {

struct ReplayOptions {
  std::string trace;   // path of the .trace file
  bool quiet = false;  // no summary line on success
};

// `dpc31 replay`: plays a golden trace (docs/trace-format.md) on a fresh chip and checks every
// expectation. Returns the exit code: 0 all held (a one-line summary to `out`), 1 a mismatch
// (`FILE:LINE: expected X, got Y` to `err`), 2 bad input (`FILE:LINE: message` to `err`).
int run_replay_command(const ReplayOptions& opt, std::FILE* out, std::FILE* err);

}  // namespace dpc31::cli

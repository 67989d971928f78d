// Runs a program as a child process and waits for it: its exit code and its peak resident set
// size (wait4's ru_maxrss). Used by the benchmarks (bench/) and `dpc31 bench`.
#pragma once

#include <string>
#include <vector>

namespace dpc31::child {

struct Result {
  int exit_code = -1;   // -1: could not be started, or ended by a signal
  long maxrss_kib = 0;  // peak RSS in KiB; also counts what the parent had resident when it
                        // spawned the child (Linux carries the high-water mark across exec)
  std::string error;    // why it could not be started, if it could not
};

// argv[0] is the program's path (no PATH search). The child's standard output goes to /dev/null,
// its standard error to `stderr_file` (created or truncated), or to /dev/null if that is empty.
Result run(const std::vector<std::string>& argv, const std::string& stderr_file = {});

}  // namespace dpc31::child

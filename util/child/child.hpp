// Runs a program (or a function) as a child process and waits for it: its exit code and its peak
// resident set size (wait4's ru_maxrss). Used by the benchmarks (bench/), `dpc31 bench`, and
// the FST reader of `dpc31 wavediff` (docs/bad-input.md).
#pragma once

#include <functional>
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

// Calls `fn` in a forked child, its standard output and error on /dev/null, and waits: the exit
// code is what `fn` returned. For third-party code that may exit() or crash on bad input (fstapi
// on a corrupt FST): the caller survives it. The child leaves with _exit(), running no atexit
// handlers or destructors of the parent's objects.
Result call(const std::function<int()>& fn);

}  // namespace dpc31::child

// Runs a program (or a function) as a child process and waits for it: its exit code and its peak
// resident set size (wait4's ru_maxrss). Used by the benchmarks (bench/), `dpc31 bench`, the RTL
// model build of `dpc31 cosim --rtl` and the FST reader of `dpc31 wavediff` (docs/bad-input.md).
//
// A signal that ends the parent (SIGINT, SIGTERM, SIGHUP) while it waits is held, not acted on at
// once: the child runs in a process group of its own, the signal is passed on to that group (a
// signal the child can handle, so that it removes its own files), the parent waits for the child
// to end (at most kGraceSeconds, then SIGKILL to the group), and only then raises the signal
// again in itself, where its cleanup handler (cleanup.hpp) removes what it registered, including
// a scratch tree a dead child left files in. So the parent never ends before its child.
#pragma once

#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace dpc31::child {

// How long a child has to end after the parent passed a signal on, before SIGKILL.
constexpr int kGraceSeconds = 10;

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

// A test's handle on one phase of a process tree (tests/bad_output_test.cpp): if the environment
// variable DPC31_STOP_AT is `name`, the process says so on its standard error ("stopped at NAME")
// and stops itself (SIGSTOP) here; a test sees the stop in /proc, signals the tree at exactly this
// phase and continues it (SIGCONT). Without the variable, nothing.
void stop_point(std::string_view name);

}  // namespace dpc31::child

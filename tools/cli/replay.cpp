#include "replay.hpp"

#include <fmt/core.h>

// The trace replay lives with the emulator (emu/ is not on this target's include path).
#include "textfile.hpp"
#include "trace.hpp"

namespace dpc31::cli {

int run_replay_command(const ReplayOptions& opt, std::FILE* out, std::FILE* err) {
  std::string message;
  ReplayOutcome o;
  const int rc = replay_trace_file(opt.trace, message, &o);
  if (rc != 0) {
    fmt::print(err, "{}\n", shown_line(message));  // one line whatever the name holds
    return rc;
  }
  if (!opt.quiet) {
    // PB3 is counted where the trace checks it (`check pb3`), else it was not looked at.
    fmt::print(out,
               "{}: ok up to cycle {}: {} telegrams in, {} out, {} writes, {} reads, {} X/INT "
               "edges, {}{} states\n",
               opt.trace, o.final_cycle, o.telegrams_in, o.telegrams_out, o.writes, o.reads,
               o.irq_edges, o.pb3_checked ? fmt::format("{} PB3 edges, ", o.pb3_edges) : "",
               o.states);
  }
  return 0;
}

}  // namespace dpc31::cli
